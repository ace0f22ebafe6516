"""Every script in scripts/ tells the truth: it answers ``--help`` without doing any of
its work, runs at tiny sizes to the end (the slow smoke runs), and needs nothing of the
test suite (a script imports from scripts/support, never from tests/).

``scripts/bench.py --only timing`` (TypeError), ``--only collision`` and a full run
(AttributeError) and ``scripts/bench_order.py`` (AttributeError) crashed once the
planner's API moved on: only a run catches that.
"""

import ast
import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import CELLS, REPO

SCRIPTS = REPO / "scripts"
PYTHON_SCRIPTS = sorted(SCRIPTS.glob("*.py"))
SHELL_SCRIPTS = sorted(SCRIPTS.glob("*.sh"))
TESTS_MODULES = {f.stem for f in (REPO / "tests").rglob("*.py")}
# All of them in one interpreter (the imports paid once): each script's exit code and
# what it printed.
HELP_PROBE = """
import contextlib, io, json, runpy, sys
found = {}
for script in sys.argv[1:]:
    sys.argv, out = [script, "--help"], io.StringIO()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
            runpy.run_path(script, run_name="__main__")
        code = "no exit"
    except SystemExit as done:
        code = done.code
    found[script] = [code, out.getvalue()]
print(json.dumps(found))
"""


def _tree_digest(folder: Path) -> dict[str, str]:
    """{file: sha256} of the folder's files, without the ``_test_*`` cells other tests
    write beside the demos for a moment (the suite runs on two workers)."""
    return {
        str(f.relative_to(folder)): hashlib.sha256(f.read_bytes()).hexdigest()
        for f in sorted(folder.rglob("*"))
        if f.is_file() and not f.name.startswith("_test_")
    }


def _env() -> dict:
    return {**os.environ, "PYTHONPATH": str(REPO)}


def test_every_script_answers_help_and_does_nothing_else(tmp_path):
    """``--help`` prints the usage and exits 0; it regenerated the demo STEP part
    (make_cad_demo.py), read ``--help`` as a cell file (process_bound.py, bench_timing.py)
    or ran the whole benchmark. Nothing in the checkout changes."""
    before = _tree_digest(CELLS)
    done = subprocess.run(
        [sys.executable, "-c", HELP_PROBE, *map(str, PYTHON_SCRIPTS)],
        cwd=tmp_path,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    found = json.loads(done.stdout.strip().splitlines()[-1])
    for script in PYTHON_SCRIPTS:
        code, text = found[str(script)]
        assert code == 0 and text.startswith("usage: "), (script.name, code, text[-500:])
    for script in SHELL_SCRIPTS:
        done = subprocess.run(
            ["bash", str(script), "--help"], cwd=tmp_path, capture_output=True, text=True
        )
        assert done.returncode == 0 and done.stdout.startswith("usage: "), script.name
    assert _tree_digest(CELLS) == before
    assert list(tmp_path.iterdir()) == []


def _imports_and_paths(file: Path) -> tuple[set[str], list[str]]:
    """(top-level module names imported anywhere in ``file``, string constants that name
    a ``tests`` folder)."""
    tree = ast.parse(file.read_text(encoding="utf-8"))
    names, paths = set(), []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module.split(".")[0])
        elif (
            isinstance(node, ast.Constant)
            and isinstance(node.value, str)
            and (node.value.strip("/") == "tests" or node.value.startswith("tests/"))
        ):
            paths.append(node.value)
    return names, paths


@pytest.mark.parametrize("script", sorted(SCRIPTS.rglob("*.py")), ids=lambda p: p.name)
def test_no_script_imports_from_tests(script):
    """A script runs without the test suite (cad_accuracy.py needed pytest through a
    test module): nothing it imports is a module of tests/, no path it builds is."""
    names, paths = _imports_and_paths(script)
    assert not names & TESTS_MODULES, sorted(names & TESTS_MODULES)
    assert not paths and "pytest" not in names


# (script, arguments at tiny sizes, a line fragment its last part prints). Not run:
# update_constraints.sh (a fresh virtual environment from the index and both suites).
SMOKE = [
    (
        "bench.py",
        ["--only", "command", "stages", "collision", "session", "ik", "timing"]
        + ["--runs", "1", "--samples", "50", "--drake-samples", "3"]
        + ["--cells", "seal_plate_kr16", "seal_job_kr16"],
        "solve on a 5,000-sample path",
    ),
    (
        "bench_table.py",
        ["--runs", "1", "--big-seams", "2", "--candidates", "2", "--cells", "seal_plate_kr16"],
        "import floor, median of all",
    ),
    ("bench_candidate.py", ["--rounds", "1", "--candidates", "2"], "=="),
    ("bench_job_size.py", ["--seams", "2"], "order search:"),
    ("bench_links.py", ["--pairs", "1", "--budget", "2"], "link duration"),
    ("bench_order.py", ["--holes", "1", "--sizes", "4"], "heuristic / exact"),
    ("bench_place.py", ["--budget", "2", "--seeds", "1", "--candidates", "2"], "unreachable"),
    ("bench_timing.py", ["seal_plate_kr16"], "solve on a 5,000-sample path"),
    (
        "bench_write.py",
        [str(CELLS / "seal_plate_kr16.yaml"), "--runs", "1", "--baseline"],
        "same points and deviations: True",
    ),
    ("calibration_accuracy.py", ["--draws", "1"], "tip_mm"),
    ("cad_accuracy.py", ["--parts", "plate", "--stl-chord-mm", "0.1"], "plate top loop"),
    ("process_bound.py", [], "report.json quality.timing_bound"),
    ("figures.py", ["--cells", "seal_plate_kr16", "--runs", "1", "--out", "figures.md"], "wrote"),
    ("off_seam_speeds.py", ["--cells", "weld_seam_irb2400"], "cycle / default"),
    ("flying_entry_figures.py", ["--cells", "seal_plate_kr16"], "cycle flying / rest"),
    ("program_bead_figures.py", ["--controllers", "abb"], "acceptance: within"),
]


def run_script(name: str, args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    done = subprocess.run(
        [sys.executable, str(SCRIPTS / name), *args],
        cwd=cwd,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=3600,
    )
    assert done.returncode == 0, (name, done.stdout[-1500:], done.stderr[-3000:])
    return done


@pytest.mark.slow
@pytest.mark.parametrize(("name", "args", "said"), SMOKE, ids=[s[0] for s in SMOKE])
def test_each_script_runs_to_the_end_at_tiny_sizes(tmp_path, name, args, said):
    before = _tree_digest(CELLS)
    done = run_script(name, args, tmp_path)
    assert said in done.stdout, done.stdout[-1500:]
    assert _tree_digest(CELLS) == before


@pytest.mark.slow
def test_compare_outputs_finds_a_plan_folder_equal_to_itself(planned_folder, tmp_path):
    folder = planned_folder("seal_plate_kr16")[1]
    run_script("compare_outputs.py", [str(folder), str(folder)], tmp_path)


@pytest.mark.slow
def test_the_demo_data_scripts_write_the_committed_files(tmp_path):
    """make_cad_demo.py and make_demo_paths.py write into --out (they wrote into
    cells/data, even for --help) what cells/data holds, up to the writers' time stamps."""
    run_script("make_cad_demo.py", ["--out", str(tmp_path)], tmp_path)
    run_script("make_demo_paths.py", ["--out", str(tmp_path)], tmp_path)
    run_script("make_demo_touches.py", ["--out", str(tmp_path)], tmp_path)
    touches = "seal_plate_kr16_touches.csv"
    assert (tmp_path / touches).read_text(encoding="utf-8") == (
        CELLS / "calibration" / touches
    ).read_text(encoding="utf-8")

    def without_stamps(file: Path) -> list[str]:
        lines = file.read_text(encoding="utf-8").splitlines()
        return [line for line in lines if not line.startswith("FILE_NAME(")]

    data = CELLS / "data"
    assert without_stamps(tmp_path / "seal_plate.step") == without_stamps(data / "seal_plate.step")
    assert (tmp_path / "tape_cylinder.csv").read_text(encoding="utf-8") == (
        data / "tape_cylinder.csv"
    ).read_text(encoding="utf-8")
    import ezdxf

    def spline(file: Path) -> list:
        entity = next(iter(ezdxf.readfile(file).modelspace().query("SPLINE")))
        return [tuple(p) for p in entity.fit_points]

    assert spline(tmp_path / "weld_seam.dxf") == spline(data / "weld_seam.dxf")
