"""The house shows its design: layer contracts hold, no import circles, small modules."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "offline_prog"
# Formatted lines (`ruff format` decides the layout): a module that grows past this is split
# by concept, not squeezed; one that cannot be says why in its docstring, with this phrase.
MAX_MODULE_LINES = 400
LONG_MODULE_REASON = f"Longer than {MAX_MODULE_LINES} lines because"


def test_layer_contracts_hold():
    """import-linter's contracts in pyproject.toml: layers top-down, numerical code
    never imports offline_prog.viz, matplotlib or meshcat."""
    importlinter = pytest.importorskip("importlinter.cli")
    root = PACKAGE.parent
    sys.path.insert(0, str(root))
    try:
        code = importlinter.lint_imports(
            config_filename=str(root / "pyproject.toml"), no_cache=True
        )
    finally:
        sys.path.remove(str(root))
    assert code == 0, "lint-imports found a broken contract (run `lint-imports` to see it)"


def _imports(file: Path) -> set[str]:
    """offline_prog modules imported anywhere in ``file`` (lazy imports included)."""
    names = set()
    for node in ast.walk(ast.parse(file.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            for alias in node.names:
                names.add(f"{node.module}.{alias.name}")
                names.add(node.module)
        elif isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
    return {n for n in names if n.startswith("offline_prog")}


def test_no_import_circles():
    """Module-level import graph, lazy imports included, has no cycle."""
    modules = {
        ".".join(f.relative_to(PACKAGE.parent).with_suffix("").parts).removesuffix(".__init__"): f
        for f in PACKAGE.rglob("*.py")
    }
    graph = {m: {n for n in _imports(f) if n in modules and n != m} for m, f in modules.items()}
    state: dict[str, int] = {}

    def visit(module: str, stack: list[str]) -> None:
        state[module] = 1
        for other in sorted(graph[module]):
            if state.get(other) == 1:
                cycle = stack[stack.index(other) :] + [other] if other in stack else [other]
                pytest.fail(f"import circle: {' -> '.join(cycle)}")
            if other not in state:
                visit(other, [*stack, other])
        state[module] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module, [module])


def test_modules_are_small_or_say_why():
    too_long = []
    for file in sorted(PACKAGE.rglob("*.py")):
        lines = len(file.read_text().splitlines())
        doc = ast.get_docstring(ast.parse(file.read_text())) or ""
        if lines > MAX_MODULE_LINES and LONG_MODULE_REASON not in doc:
            too_long.append(f"{file.relative_to(PACKAGE.parent)} ({lines} lines)")
    listed = ", ".join(too_long)
    assert not too_long, f"modules over {MAX_MODULE_LINES} lines without a reason: {listed}"


def test_code_is_ruff_formatted():
    """`ruff format` decides the layout of the package, its tests and scripts (what CI runs)."""
    pytest.importorskip("ruff")
    root = PACKAGE.parent
    done = subprocess.run(
        [sys.executable, "-m", "ruff", "format", "--check", "offline_prog", "tests", "scripts"],
        cwd=root,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, "run `python3 -m ruff format .`:\n" + done.stdout + done.stderr


def test_robot_descriptions_are_package_data():
    """Robots ship inside the package, so `pip install .` (not editable) can plan."""
    import tomllib

    config = tomllib.loads((PACKAGE.parent / "pyproject.toml").read_text())
    patterns = config["tool"]["setuptools"]["package-data"]["offline_prog"]
    for robot in (PACKAGE / "robots").iterdir():
        if robot.is_dir():
            for file in robot.rglob("*"):
                if file.is_file():
                    relative = file.relative_to(PACKAGE)
                    assert any(relative.match(p) for p in patterns), f"{relative} not package data"


# Our own readers, which decode UTF-8 themselves (config.safe_yaml.read_text: the size
# limit, a BOM, the one-line error).
OWN_TEXT_READERS = {"safe_yaml"}


def _text_io_without_encoding(tree: ast.AST) -> list[int]:
    """Lines of ``open(...)`` in text mode, ``.read_text(...)`` and ``.write_text(...)``
    calls that do not name their ``encoding``."""
    lines = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call) or any(k.arg == "encoding" for k in node.keywords):
            continue
        if isinstance(node.func, ast.Name) and node.func.id == "open":
            mode = node.args[1] if len(node.args) > 1 else None
            mode = next((k.value for k in node.keywords if k.arg == "mode"), mode)
            binary = isinstance(mode, ast.Constant) and "b" in str(mode.value)
            if not binary:
                lines.append(node.lineno)
        elif isinstance(node.func, ast.Attribute) and node.func.attr in ("read_text", "write_text"):
            owner = node.func.value
            if not (isinstance(owner, ast.Name) and owner.id in OWN_TEXT_READERS):
                lines.append(node.lineno)
    return lines


def test_text_files_are_read_and_written_as_utf8():
    """Every text file the package reads or writes names its encoding: the locale's would
    misread a cell's σ, or fail to write a robot folder's SOURCES.md (its …), where it is not UTF-8
    (a C or POSIX locale only gets UTF-8 from Python's own coercion)."""
    found = [
        f"{file.relative_to(PACKAGE.parent)}:{line}"
        for file in sorted(PACKAGE.rglob("*.py"))
        for line in _text_io_without_encoding(ast.parse(file.read_text(encoding="utf-8")))
    ]
    assert not found, "text I/O without encoding= at " + ", ".join(found)


def test_the_encoding_check_sees_each_form():
    code = (
        "open(a)\nopen(a, 'w')\nopen(a, mode='rb')\nopen(a, encoding='utf-8')\n"
        "p.read_text()\np.write_text(t, encoding='utf-8')\nq.write_text(t)\nos.open(a, 0)\n"
        "safe_yaml.read_text(f)\n"
    )
    assert _text_io_without_encoding(ast.parse(code)) == [1, 2, 5, 7]
