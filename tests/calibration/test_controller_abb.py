"""ABB RAPID: a module written by hand round-trips (the frames read equal the frames
written to 0.001 mm / 0.001°), the RAPID writer's own declarations read back as the
cell's frames under the names the reader derives, and anything else in a declaration
is refused in one line (the text is parsed, never run)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from offline_prog.calibration.controller_abb import (
    data_names,
    held_work_object,
    parse_aggregate,
    read_rapid,
    stationary_tool,
)
from offline_prog.errors import InputError

MM, DEG = 1e-3, 1e-3
MODULE = """MODULE CalibData
  ! Calibrated on the controller (stationary tool, held work object).
  PERS tooldata tool_welding_torch := [FALSE,[[1100.512,-0.412,899.733],
    [0.7072068,-0.7070068,0.0012,-0.0004]],[5,[0,0,100],[1,0,0,0],0,0,0]];
  TASK PERS wobjdata wobj_bracket := [TRUE,TRUE,"",[[-30.25,0.4,300.118],
    [0.7071068,0.0,-0.7071068,0.0]],[[1.5,0,0],[0.9998477,0,0,0.0174524]]]; ! "1.5 mm, 2° z"
  PERS tooldata tool0_copy := [TRUE,[[0,0,0],[1,0,0,0]],[0.001,[0,0,0.001],[1,0,0,0],0,0,0]];
  PERS string note := "PERS tooldata fake := [ not, data ];";
ENDMODULE
"""


def matrix(p_mm, q_wxyz) -> np.ndarray:
    """The expected frame, computed without the reader (scipy's quaternion is xyzw)."""
    X = np.eye(4)
    w, x, y, z = q_wxyz
    X[:3, :3] = Rotation.from_quat([x, y, z, w]).as_matrix()
    X[:3, 3] = np.array(p_mm) * 1e-3
    return X


def assert_same(X, expected):
    assert np.abs(X[:3, 3] - expected[:3, 3]).max() * 1e3 < MM
    assert np.degrees(Rotation.from_matrix(X[:3, :3].T @ expected[:3, :3]).magnitude()) < DEG


def test_a_hand_written_module_round_trips():
    data = read_rapid("CalibData.mod", MODULE)
    assert set(data.tooldata) == {"tool_welding_torch", "tool0_copy"}
    assert set(data.wobjdata) == {"wobj_bracket"}  # not the one inside a string
    tframe = stationary_tool("m", "tool_welding_torch", data.tooldata["tool_welding_torch"])
    assert_same(
        tframe, matrix([1100.512, -0.412, 899.733], [0.7072068, -0.7070068, 0.0012, -0.0004])
    )
    object_in_E = held_work_object("m", "wobj_bracket", data.wobjdata["wobj_bracket"])
    uframe = matrix([-30.25, 0.4, 300.118], [0.7071068, 0.0, -0.7071068, 0.0])
    oframe = matrix([1.5, 0, 0], [0.9998477, 0, 0, 0.0174524])
    assert_same(object_in_E, uframe @ oframe)


def test_robhold_says_which_is_the_stationary_tool():
    data = read_rapid("m", MODULE)
    with pytest.raises(InputError, match="robhold is TRUE: a tool the robot holds"):
        stationary_tool("m", "tool0_copy", data.tooldata["tool0_copy"])
    fixed = [False, True, "", [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]]] * 1
    fixed.append([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]])
    with pytest.raises(InputError, match="robhold is FALSE: a work object fixed in the cell"):
        held_work_object("m", "wobj", fixed)


def test_the_names_are_the_writers():
    assert data_names("welding_torch", "bracket") == ("tool_welding_torch", "wobj_bracket")
    assert data_names("nozzle 2 (left)", "plate/A") == ("tool_nozzle_2__left_", "wobj_plate_A")


def test_the_rapid_writers_declarations_read_back(planned_folder):
    """Export → parse → compare: the weld demo's RAPID frames module declares the tooldata and
    wobjdata the reader derives from the cell, and they hold the cell's frames (X_IB is
    the identity in the demo)."""
    plan, folder = planned_folder("weld_seam_irb2400")
    frames = folder / "programs" / "OfflineProgFrames.mod"  # the nominal frames' module
    data = read_rapid(frames.name, frames.read_text(encoding="utf-8"))
    tool, wobj = data_names(plan.cell.tool.name, plan.cell.part.name)
    X_IT = stationary_tool("m", tool, data.tooldata[tool])
    X_EP = held_work_object("m", wobj, data.wobjdata[wobj])
    from offline_prog.config.cell import transform

    assert_same(X_IT, transform(plan.cell.tool.X_IT).GetAsMatrix4())
    assert_same(X_EP, transform(plan.cell.part.X_PE).inverse().GetAsMatrix4())


@pytest.mark.parametrize(
    ("value", "reason"),
    [
        ("[FALSE,[[0,0,0],[1,0,0,0]]", "not one [...] aggregate"),
        ("[FALSE,[[0,0,0],[1,0,0,0]]]]", "unbalanced ]"),
        ("[FALSE,[[0,0,x0],[1,0,0,0]],load0]", "unexpected 'x0]"),
        ('[FALSE,[[0,0,__import__("os")],[1,0,0,0]],0]', "unexpected '__import__"),
        ("[FALSE,[[0,0,1e999],[1,0,0,0]],0]", "1e999 is not finite"),
    ],
)
def test_a_declaration_that_is_not_data_is_refused(value, reason):
    with pytest.raises(ValueError, match=reason.replace("[", r"\[").replace("(", r"\(")):
        parse_aggregate(value)
    with pytest.raises(InputError) as error:
        read_rapid("m.mod", f"PERS tooldata tool_x := {value};")
    assert str(error.value).startswith("m.mod: tool_x: PERS tooldata tool_x: ")


def test_a_quaternion_that_is_not_unit_is_refused():
    value = [False, [[0.0, 0.0, 0.0], [1.0, 0.5, 0.0, 0.0]], [1.0]]
    with pytest.raises(InputError, match="the quaternion's norm is 1.1180, not 1"):
        stationary_tool("m", "tool_x", value)
