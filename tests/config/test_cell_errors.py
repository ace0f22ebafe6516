"""Bad input gives one line naming the file, key and reason; exit code 2; no traceback."""

import subprocess
import sys

import numpy as np
import pytest

from offline_prog.config.cell import load_cell
from offline_prog.errors import InputError
from offline_prog.plan import plan_cell

from conftest import REPO

BASE = """\
name: test
robot:
  model: kuka_kr16_2
  X_IB: {translation: [0, 0, 0], rotation: !Rpy {deg: [0, 0, 0]}}
tool:
  X_IT: {translation: [1.0, 0, 0.5], rotation: !Rpy {deg: [90, 0, 0]}}
part:
  X_PE: {translation: [0, 0, 0.1], rotation: !Rpy {deg: [180, 0, 0]}}
path:
  points: path.csv
  units: mm
  closed: false
  normal: [0, 0, 1]
motion:
  speed: 0.1
  max_acceleration: 1.0
  max_jerk: 10.0
"""

CSV = "x,y,z\n" + "".join(f"{i * 2.0},{20 * np.sin(i / 6)},0\n" for i in range(40))


def write_cell(tmp_path, text=BASE, csv=CSV):
    (tmp_path / "path.csv").write_text(csv)
    cell = tmp_path / "cell.yaml"
    cell.write_text(text)
    return cell


def test_base_cell_plans(tmp_path):
    plan = plan_cell(write_cell(tmp_path))
    assert plan.path.length > 0.07


CASES = [  # (replace, with, key in message, reason fragment)
    ("  speed: 0.1", "  speed: 0.1\n  sped: 1", "motion.sped", "unknown key"),
    ("  max_jerk: 10.0\n", "", "motion.max_jerk", "missing"),
    ("path.csv", "nothere.csv", "path.points", "does not exist"),
    ("units: mm", "units: inch", "path.units", "not a unit"),
    ("speed: 0.1", "speed: .nan", "motion.speed", "not a finite number"),
    ("speed: 0.1", "speed: -0.1", "motion.speed", "must be > 0"),
    ("speed: 0.1", "speed: fast", "motion.speed", "expected float"),
    ("[1.0, 0, 0.5]", "[1.0, 0]", "tool.X_IT.translation", "3 numbers"),
    ("[1.0, 0, 0.5]", "[1.0, .nan, 0.5]", "tool.X_IT.translation", "NaN"),
    ("!Rpy {deg: [90, 0, 0]}", "{deg: [90, 0, 0]}", "tool.X_IT.rotation", "!Rpy"),
    ("name: test", "name: test\ntool_typo: {}", "tool_typo", "unknown key"),
    (
        "name: test",
        "name: test\nobstacles: [{name: a, shape: cone}]",
        "obstacles[0].shape",
        "use box",
    ),
    (
        "name: test",
        "name: test\nobstacles: [{name: a, shape: box, size_mm: [1, 1, 1]}, "
        "{name: a, shape: sphere, radius_mm: 1}]",
        "obstacles[1].name",
        "used twice",
    ),
    (
        "name: test",
        "name: test\nobstacles: [{name: a, shape: mesh, mesh: nope.stl}]",
        "obstacles[0].mesh",
        "does not exist",
    ),
    (
        "name: test",
        "name: test\nallowed_contact: [[tip, plate]]",
        "allowed_contact[0]",
        "not a shape",
    ),
    (
        "name: test",
        "name: test\nobstacles: [{name: a, shape: box, size_mm: [1, .nan, 1]}]",
        "obstacles[0].size_mm",
        "NaN",
    ),
    ("max_jerk: 10.0", "max_jerk: 10.0\n  clearance: -1.0", "motion.clearance", "must be ≥ 0"),
    ("X_IT: {", "free_rotation_deg: 270\n  X_IT: {", "tool.free_rotation_deg", "within"),
    (
        "X_IT: {",
        "free_rotation_deg: 90\n  turn_smoothing_mm: -5\n  X_IT: {",
        "tool.turn_smoothing_mm",
        "must be ≥ 0 mm",
    ),
    ("X_IT: {", "turn_smoothing_mm: 30\n  X_IT: {", "tool.turn_smoothing_mm", "needs tool.free"),
    ("X_IT: {", "symmetry_axis: w\n  X_IT: {", "tool.symmetry_axis", "use x, y or z"),
    ("model: kuka_kr16_2", "model: no_such_robot", "robot.model", "not a robot folder"),
    ("closed: false", "closed: maybe", "path.closed", "expected bool"),
    (
        "closed: false",
        "closed: true",
        "path.closed",
        "ends of path.csv are 78.119 mm apart, more than twice the point spacing",
    ),
    ("  normal: [0, 0, 1]\n", "", "path.normal", "exactly one way"),
    ("normal: [0, 0, 1]", "normal: [1, 0, 0]", "path.normal", "tangent"),
    ("normal: [0, 0, 1]", "normal: [0, 0, 0]", "path.normal", "zero vector"),
    (
        "max_jerk: 10.0",
        "max_jerk: 10.0\n  cusp_smoothing_mm: 0",
        "motion.cusp_smoothing_mm",
        "must be > 0",
    ),
    ("units: mm", "units: mm\n  degree: 3", "path.degree", "< 5"),
    (
        "max_jerk: 10.0",
        "max_jerk: 10.0\n  time_law: fastest",
        "motion.time_law",
        "use time_optimal",
    ),
    ("max_jerk: 10.0", "max_jerk: 10.0\n  process: glue", "motion.process", "constant_speed"),
    ("  closed: false", "  closed: false\n  dxf: a.dxf", "path", "exactly one of"),
    # A pose typed in mm gets the unit hint motion.speed: 100 gets (it was only "out of
    # reach" once planned).
    (
        "[1.0, 0, 0.5]",
        "[1000, 0, 500]",
        "tool.X_IT.translation",
        "1118 m from the origin, more than a cell's 20 m (the unit is m: [1000, 0, 500] mm "
        "is [1, 0, 0.5])",
    ),
    ("[0, 0, 0.1]", "[0, 0, 100]", "part.X_PE.translation", "[0, 0, 100] mm is [0, 0, 0.1]"),
    (
        "X_IB: {translation: [0, 0, 0]",
        "X_IB: {translation: [0, 0, 30]",
        "robot.X_IB.translation",
        "30 m",
    ),
    (
        "name: test",
        "name: test\nobstacles: [{name: a, shape: box, size_mm: [1, 1, 1], "
        "pose: {translation: [1000, 0, 150]}}]",
        "obstacles[0].pose.translation",
        "[1000, 0, 150] mm is [1, 0, 0.15]",
    ),
    ("path:\n", "path:\n  analytic: {kind: spiral}\n", "path", "exactly one of"),
    ("speed: 0.1", "speed: 0.1\n  approach_speed: -0.05", "motion.approach_speed", "(0, 2]"),
    ("speed: 0.1", "speed: 0.1\n  approach_speed: 50", "motion.approach_speed", "path speed"),
    ("speed: 0.1", "speed: 0.1\n  link_speed_percent: 0", "motion.link_speed_percent", "(0, 100]"),
    (
        "speed: 0.1",
        "speed: 0.1\n  link_speed_percent: 150",
        "motion.link_speed_percent",
        "got 150",
    ),
]


@pytest.mark.parametrize(("old", "new", "key", "reason"), CASES)
def test_bad_cell_names_file_key_and_reason(tmp_path, old, new, key, reason):
    assert old in BASE
    cell = write_cell(tmp_path, BASE.replace(old, new, 1))
    with pytest.raises(InputError) as info:
        plan_cell(cell)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(str(cell))
    assert f": {key}:" in message or message.split(": ")[1] == key
    assert reason in message


@pytest.mark.parametrize("robots_dir", ["robotz", "robots"])
def test_robots_dir_must_hold_the_robot(tmp_path, robots_dir):
    """A missing or mistyped robot.robots_dir planned with the bundled robot of the
    same name: the folder must exist and hold the robot."""
    (tmp_path / "robots" / "other").mkdir(parents=True)
    text = BASE.replace("model: kuka_kr16_2\n", f"model: kuka_kr16_2\n  robots_dir: {robots_dir}\n")
    cell = write_cell(tmp_path, text)
    with pytest.raises(InputError) as error:
        plan_cell(cell)
    assert error.value.file == str(cell) and error.value.key == "robot.robots_dir"
    folder = tmp_path / robots_dir
    reason = "folder not found" if robots_dir == "robotz" else "holds no robot folder 'kuka_kr16_2'"
    assert reason in error.value.reason and str(folder) in error.value.reason


def test_closed_defaults_to_false(tmp_path):
    assert (
        load_cell(write_cell(tmp_path, BASE.replace("  closed: false\n", ""))).path.closed is False
    )


def test_speed_reference_must_be_tcp_or_flange(tmp_path):
    cell = write_cell(
        tmp_path, BASE.replace("max_jerk: 10.0", "max_jerk: 10.0\n  speed_reference: wrist")
    )
    with pytest.raises(InputError, match="motion.speed_reference: 'wrist'"):
        plan_cell(cell)


@pytest.mark.parametrize(
    ("csv", "reason"),
    [
        ("x,y\n1,2\n", "header must start with x,y,z"),
        ("x,y,z\n1,2,3\n1,2\n", "line 3 has 2 values"),
        ("x,y,z\n1,2,3\n1,nan,3\n", "line 3 holds NaN"),
        ("x,y,z\n1,2,3\n1,b,3\n", "not a number"),
        ("x,y,z,nx,ny,nz\n1,2,3,0,0,0\n", "normal (nx,ny,nz) is zero"),
        ("x,y,z,w\n1,2,3,1\n", "unknown columns"),
    ],
)
def test_bad_csv_names_line(tmp_path, csv, reason):
    cell = write_cell(tmp_path, csv=csv)
    with pytest.raises(InputError, match="path.points: path.csv: ") as info:
        plan_cell(cell)
    assert reason in str(info.value)


@pytest.mark.parametrize(
    ("csv", "reason"),
    [
        ("x,y,z\n" + "1,2,3\n" * 10, "at least 6"),  # duplicates collapse to one point
        ("x,y,z\n0,0,0\n1,0,0\n2,0,0\n", "at least 6"),
        ("x,y,z\n" + "".join(f"{v},0,0\n" for v in [0, 1, 2, 3, 2, 1, 0, 1, 2, 3]), "turns back"),
    ],
)
def test_geometry_the_method_cannot_handle(tmp_path, csv, reason):
    with pytest.raises(InputError, match=f"cell.yaml: path: .*{reason}"):
        plan_cell(write_cell(tmp_path, csv=csv))


def test_yaml_syntax_error_names_line(tmp_path):
    with pytest.raises(InputError, match="line 4: not valid YAML"):
        load_cell(write_cell(tmp_path, "robot:\n  model: [\n  x: 1\n"))


def test_cli_bad_input_is_one_line_exit_2(tmp_path):
    cell = write_cell(tmp_path, BASE.replace("units: mm", "units: furlong"))
    done = subprocess.run(
        [sys.executable, "-m", "offline_prog", "plan", str(cell), "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        cwd=REPO,
    )
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert lines == [f"error: {cell}: path.units: 'furlong' is not a unit (use m or mm)"]
    assert "Traceback" not in done.stderr + done.stdout
    assert not (tmp_path / "out").exists()


def test_cli_missing_cell_file(tmp_path):
    done = subprocess.run(
        [sys.executable, "-m", "offline_prog", "plan", str(tmp_path / "none.yaml")],
        capture_output=True,
        text=True,
        cwd=REPO,
    )
    assert done.returncode == 2
    assert "none.yaml: cannot read" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
