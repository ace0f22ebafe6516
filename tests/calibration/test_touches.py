"""The touches file: read as the contract says (header, degrees in trajectory.csv's
convention or the controller's), and refused in one line naming the line and what to
fix: a wrong header, an unknown target, radians, a touch beyond the joint limits."""

import numpy as np
import pytest

from offline_prog.calibration.touches import HEADER, parse_touches, read_touches
from offline_prog.config.calibration_keys import CalibrationConfig
from offline_prog.errors import InputError
from offline_prog.robot.model import load_robot

CALIBRATION = CalibrationConfig(
    pointer_mm=[0, 0, 250], tool_axis_point_mm=50.0, part_points={"corner_a": [1.0, 2.0, 0.0]}
)
ROW = "10.5,-80,95.25,0,40,10"


def parse(text: str, robot="kuka_kr16_2", calibration=CALIBRATION, **kwargs):
    return parse_touches("t.csv", text, load_robot(robot), calibration, **kwargs)


def test_rows_become_urdf_joints_in_radians():
    text = f"# a comment\n{','.join(HEADER)}\n\ntool_tip,{ROW}\n  # another\ncorner_a,{ROW}\n"
    touches = parse(text)
    assert touches.targets == ("tool_tip", "corner_a") and touches.lines == (4, 6)
    assert np.allclose(np.degrees(touches.q[0]), [10.5, -80, 95.25, 0, 40, 10])
    assert touches.where(1) == "line 6 (corner_a)"


def test_controller_angles_undo_the_j2_j3_coupling():
    """ABB IRB 2400: the controller's axis 3 is q2 + q3 (robot.yaml)."""
    robot = load_robot("abb_irb2400")
    assert robot.j23_coupled
    urdf = parse(f"{','.join(HEADER)}\ntool_tip,10,20,-10,0,30,0\n", "abb_irb2400")
    shown = parse(
        f"{','.join(HEADER)}\ntool_tip,10,20,10,0,30,0\n", "abb_irb2400", controller_angles=True
    )
    assert np.allclose(urdf.q, shown.q)
    assert np.allclose(np.degrees(robot.controller_joints(urdf.q[0]))[2], 10.0)


def test_the_file_is_read_with_its_limits(tmp_path):
    file = tmp_path / "touches.csv"
    file.write_bytes(b"\xef\xbb\xbf" + f"{','.join(HEADER)}\ntool_tip,{ROW}\n".encode())
    assert read_touches(file, load_robot("kuka_kr16_2"), CALIBRATION).targets == ("tool_tip",)
    file.write_bytes(b"target\xe9\n")
    with pytest.raises(InputError, match="not UTF-8"):
        read_touches(file, load_robot("kuka_kr16_2"), CALIBRATION)


BAD = [
    ("target,q1,q2,q3,q4,q5,q6\n", "line 1: the header must be target,q1_deg"),
    (f"{','.join(HEADER)}\n", "no touches below the header"),
    (f"{','.join(HEADER)}\ntool_tip,1,2,3\n", "line 2: expected 7 fields, got 4"),
    (f"{','.join(HEADER)}\ntool_tip,{ROW}\nnozzle,{ROW}\n", "line 3: target 'nozzle' is not"),
    (f"{','.join(HEADER)}\ntool_tip,1,2,x,4,5,6\n", "line 2: 'x' is not a number"),
    (f"{','.join(HEADER)}\ntool_tip,1,2,nan,4,5,6\n", "line 2: 'nan' is not a finite number"),
    (f"{','.join(HEADER)}\ntool_tip,0.1,-1.2,1.5,0.0,0.7,3.1\n", "look like radians"),
    (
        f"{','.join(HEADER)}\ncorner_a,{ROW}\ntool_tip,0,-80,170,0,40,0\n",
        "line 3: tool_tip: axis 3",
    ),
]


@pytest.mark.parametrize(("text", "reason"), BAD)
def test_a_bad_file_is_one_line_naming_what_to_fix(text, reason):
    with pytest.raises(InputError) as error:
        parse(text)
    assert reason in str(error.value) and "\n" not in str(error.value)
    assert str(error.value).startswith("t.csv: ")


def test_a_touch_beyond_the_limits_names_the_axis_and_the_limits():
    with pytest.raises(InputError) as error:
        parse(f"{','.join(HEADER)}\ntool_tip,0,-80,170,0,40,0\n")
    assert "axis 3 at 170.000° is beyond the robot's joint limits [-130, 154]°" in str(error.value)


def test_tool_axis_needs_its_point_in_the_cell():
    calibration = CalibrationConfig(pointer_mm=[0, 0, 250])
    with pytest.raises(InputError, match="needs calibration.tool_axis_point_mm"):
        parse(f"{','.join(HEADER)}\ntool_axis,{ROW}\n", calibration=calibration)
