"""The cell keys of calibration (calibration:, issue 38) and of the controller's frame
numbers (tool.controller_frame, part.controller_frame, issue 42): read as the contract
spells them, refused in one line naming the key."""

import pytest
from test_cell_errors import BASE, write_cell

from offline_prog.config.cell import load_cell
from offline_prog.config.checks import check_cell
from offline_prog.errors import InputError
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import load_inputs

POINTS = """  part_points:
    corner_a: [-200, -150, 0]
    corner_b: [200, -150, 0]
    hole_c: [0, 100, 0]
"""
BLOCK = (
    """calibration:
  pointer_mm: [0, 0, 250]        # nominal tip of a pointer on the flange, in E
  tool_axis_point_mm: 50          # optional
"""
    + POINTS
)
NUMBERED = BASE.replace("tool:\n", "tool:\n  controller_frame: 3\n").replace(
    "part:\n", "part:\n  controller_frame: 1\n"
)


def test_the_contract_keys_load(tmp_path):
    cell = load_cell(write_cell(tmp_path, NUMBERED + BLOCK))
    assert cell.calibration.pointer_mm == [0, 0, 250]
    assert cell.calibration.tool_axis_point_mm == 50
    assert list(cell.calibration.part_points) == ["corner_a", "corner_b", "hole_c"]
    assert cell.calibration.part_points["hole_c"] == [0, 100, 0]
    assert (cell.tool.controller_frame, cell.part.controller_frame) == (3, 1)
    check_cell(tmp_path / "cell.yaml", cell, ROBOTS_DIR)
    assert load_cell(write_cell(tmp_path)).calibration is None  # optional


CASES = [  # (replace, with, key in message, reason fragment)
    ("[0, 0, 250]", "[0, 250]", "calibration.pointer_mm", "expected [x, y, z] in mm"),
    ("[0, 0, 250]", "[0, 0, 25000]", "calibration.pointer_mm", "more than 5000 mm"),
    ("[0, 0, 250]", "[0, .nan, 250]", "calibration.pointer_mm", "NaN"),
    ("point_mm: 50", "point_mm: -50", "calibration.tool_axis_point_mm", "must be > 0"),
    ("point_mm: 50", "point_mm: fifty", "calibration.tool_axis_point_mm", "expected float"),
    ("hole_c: [0, 100, 0]", "hole_c: [0, 100]", "calibration.part_points.hole_c", "[x, y, z]"),
    ("hole_c: [0, 100, 0]", "tool_tip: [0, 1, 0]", "calibration.part_points.tool_tip", "not a"),
    ("hole_c: [0, 100, 0]", "'a,b': [0, 100, 0]", "calibration.part_points.a,b", "not a point"),
    ("hole_c: [0, 100, 0]", "1: [0, 100, 0]", "calibration.part_points.1", "must be text"),
    (POINTS, "  part_points: [1, 2]\n", "calibration.part_points", "expected a mapping"),
    ("  pointer_mm", "  pointer: [0, 0, 1]\n  pointer_mm", "calibration.pointer", "unknown key"),
    ("controller_frame: 3", "controller_frame: 0", "tool.controller_frame", "is not a frame"),
    ("controller_frame: 1", "controller_frame: 17", "part.controller_frame", "use 1..16"),
    ("controller_frame: 3", "controller_frame: 2.5", "tool.controller_frame", "expected int"),
]


@pytest.mark.parametrize(("old", "new", "key", "reason"), CASES)
def test_a_bad_value_is_one_line_naming_the_key(tmp_path, old, new, key, reason):
    text = (NUMBERED + BLOCK).replace(old, new, 1)
    assert text != NUMBERED + BLOCK
    file = write_cell(tmp_path, text)
    with pytest.raises(InputError) as error:
        load_inputs(file, ROBOTS_DIR)  # the type checks, check_cell, the robot's ranges
    message = str(error.value)
    assert f": {key}: " in message and reason in message and "\n" not in message, message


def test_frame_numbers_are_checked_against_the_robot_s_controller(tmp_path):
    """KUKA numbers 32 bases and 16 tools; a UR takes any number from 1."""
    text = NUMBERED.replace("controller_frame: 3", "controller_frame: 33")
    with pytest.raises(InputError, match="33 is not a BASE_DATA number of the robot's krl"):
        load_inputs(write_cell(tmp_path, text), ROBOTS_DIR)
    ur = text.replace("model: kuka_kr16_2", "model: ur10e")
    assert load_inputs(write_cell(tmp_path, ur), ROBOTS_DIR).cell.tool.controller_frame == 33
