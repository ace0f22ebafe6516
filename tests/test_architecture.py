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
