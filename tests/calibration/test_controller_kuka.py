"""KUKA ``$config.dat``: a file written by hand round-trips (the frames read equal the
frames written to 0.001 mm / 0.001°), the KRL writer's frames read back as written,
and a malformed frame is one line naming the file's line."""

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from scipy.spatial.transform import Rotation

from offline_prog.calibration.controller_kuka import read_config_dat
from offline_prog.errors import InputError
from offline_prog.export.kuka.kuka import krl_frame, kuka_abc_deg

MM, DEG = 1e-3, 1e-3  # the round trip's tolerances
CONFIG_DAT = """&ACCESS RVO
&REL 27
DEFDAT  $CONFIG
;FOLD TOOL- and BASE-data
DECL FRAME TOOL_DATA[16]
TOOL_DATA[1]={X 0.412,Y -0.835,Z -100.731,A 179.5,B -0.25,C -179.75} ; the plate
TOOL_DATA[2]={X 0.0,Y 0.0,Z 0.0,A 0.0,B 0.0,C 0.0}
TOOL_NAME[1,]="PLATE; on the flange"
TOOL_TYPE[1]=#BASE
decl frame BASE_DATA[32]
BASE_DATA[1]={X 0.0,Y 0.0,Z 0.0,A 0.0,B 0.0,C 0.0}
base_data[3]={Y -3.47E-01,X 1000.521,Z 500.812,A 0.125,B -0.05,C 90.2}
BASE_NAME[3,]="NOZZLE"
BASE_TYPE[3]=#TCP
;ENDFOLD
ENDDAT
"""
WRITTEN = {  # X, Y, Z [mm], A, B, C [deg], as typed above
    ("TOOL", 1): (0.412, -0.835, -100.731, 179.5, -0.25, -179.75),
    ("BASE", 3): (1000.521, -0.347, 500.812, 0.125, -0.05, 90.2),
}


def test_a_hand_written_config_dat_round_trips():
    read = read_config_dat("$config.dat", CONFIG_DAT)
    assert set(read.frames) == {("TOOL", 1), ("TOOL", 2), ("BASE", 1), ("BASE", 3)}
    assert read.names[("BASE", 3)] == "NOZZLE" and read.names[("TOOL", 1)] == "PLATE; on the flange"
    assert read.types == {("TOOL", 1): "#BASE", ("BASE", 3): "#TCP"}
    for key, (x, y, z, a, b, c) in WRITTEN.items():
        X = read.frames[key]
        assert np.abs(X[:3, 3] * 1e3 - [x, y, z]).max() < MM
        abc = kuka_abc_deg(X[None, :3, :3])[0]  # the writer's angles of what was read
        assert np.abs((abc - [a, b, c] + 180.0) % 360.0 - 180.0).max() < DEG, (key, abc)
        # R = Rz(A)·Ry(B)·Rx(C): Drake's roll-pitch-yaw (C, B, A).
        expected = RigidTransform(
            RollPitchYaw(np.radians([c, b, a])), [x * 1e-3, y * 1e-3, z * 1e-3]
        )
        assert np.allclose(X, expected.GetAsMatrix4(), atol=1e-12)


def test_the_krl_writers_frames_read_back(rng):
    """The KRL writer's X, Y, Z, A, B, C text of a frame, in a $config.dat line, is the
    frame (the reader inverts the writer's convention: one convention, both ways)."""
    for k in range(30):
        R = Rotation.random(random_state=k).as_matrix()
        X = np.eye(4)
        X[:3, :3], X[:3, 3] = R, rng.uniform(-2.0, 2.0, 3)
        text = f"BASE_DATA[{k + 1}]={{{krl_frame(X)}}}\n"
        read = read_config_dat("$config.dat", text).frames[("BASE", k + 1)]
        assert np.abs(read[:3, 3] - X[:3, 3]).max() < 1e-7  # 4 decimals of mm
        angle = Rotation.from_matrix(read[:3, :3].T @ R).magnitude()
        assert np.degrees(angle) < 1e-4  # 5 decimals of a degree


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ("BASE_DATA[3]={X 1,Y 2,Z 3,A 4,B 5}", "line 1: BASE_DATA[3] lacks C"),
        ("BASE_DATA[3]={X 1,Y 2,Z 3,A 4,B 5,C x}", "line 1: BASE_DATA[3] is not {X"),
        ("TOOL_DATA[1]={X 1,Y 2,Z 3,A 4,B 5,C 6,X 7}", "line 1: TOOL_DATA[1]: component X"),
        ("TOOL_DATA[1]={X 1,Y 2,Z 3,A 4,B 5,C 6,E1 7}", "line 1: TOOL_DATA[1] is not {X"),
        ("TOOL_DATA[1]=TOOL_DATA[2]", "line 1: TOOL_DATA[1] is not {X"),
        (
            "BASE_DATA[3]={X 1,Y 2,Z 3,A 4,B 5,C 6}\nBASE_DATA[3]={X 1,Y 2,Z 3,A 4,B 5,C 6}",
            "line 2: BASE_DATA[3] is given twice (also line 1)",
        ),
        ("BASE_DATA[3]={X 1e999,Y 2,Z 3,A 4,B 5,C 6}", "line 1: BASE_DATA[3]: X is not finite"),
    ],
)
def test_a_malformed_frame_is_one_line(text, reason):
    with pytest.raises(InputError) as error:
        read_config_dat("$config.dat", text)
    assert str(error.value) == f"$config.dat: {reason}" or reason in str(error.value)
    assert "\n" not in str(error.value)
