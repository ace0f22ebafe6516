"""FANUC conventions: controller axes, configuration strings, W-P-R, and LS text (the
program file, its /POS entries and TP remarks).

Sources and assumptions (the LS program writer, :mod:`offline_prog.export.fanuc.fanuc_ls`,
states them in each program's header):

- Axes: FANUC counts J3 from the horizontal; the ROS-Industrial FANUC support packages'
  URDFs count joint_3 from the upper arm, about the opposite direction of joint_2, and
  the ROS-Industrial ``fanuc_driver`` converts between them with its J2/J3 linkage
  correction (ros-industrial/fanuc, ``J23_factor``). Here J3 = q3 + f·q2 with f the robot
  record's ``controller.j23_factor`` (-1 for those URDFs): RobotModel.controller_joints.
- Orientation: W, P, R are rotations about the fixed x, y, z axes of the user frame, in
  that order: R_UF = Rz(R) · Ry(P) · Rx(W) (Drake's RollPitchYaw(W, P, R)).
- Configuration ``'F|N U|D T|B, t1, t4, t6'``: N (no flip) when J5 ≤ 0 in FANUC's axes,
  F when J5 > 0; U when the elbow (axis 3) is above the line from axis 2 to the wrist
  centre, D below; T when the wrist centre is in front of axis 1, B behind it (the same
  geometric tests as ABB's cfx bits, ``export.abb.abb.confdata``); turn numbers of J1, J4,
  J6: 0 for (-180°, 180°], 1 for (180°, 540°], -1 for (-540°, -180°].
- World: FANUC's world frame sits on axis 1 at the height of axis 2 (the ROS-Industrial
  FANUC support packages' ``base`` frame: base_link raised by c1); the user frame is the
  fixed tool T in that world (``export.fanuc.fanuc_frames``).
"""

from __future__ import annotations

import datetime

import numpy as np
from pydrake.math import RollPitchYaw, RotationMatrix

from offline_prog.export.text import fanuc_comments
from offline_prog.robot.model import RobotModel

MM_DIGITS, DEG_DIGITS = 3, 4  # 0.5 µm, 0.00005°


def fanuc_axes_deg(robot: RobotModel, q: np.ndarray) -> np.ndarray:
    """(N, 6) FANUC axis values [deg] from URDF joints q (N, 6) [rad]."""
    return np.rad2deg(robot.controller_joints(np.asarray(q, dtype=float)))


def turn_numbers(axes_deg: np.ndarray) -> np.ndarray:
    """(N, 3) turn numbers of J1, J4, J6: ceil((J - 180°) / 360°)."""
    return np.ceil((axes_deg[:, [0, 3, 5]] - 180.0) / 360.0).astype(int)


def config_flags(robot: RobotModel, q: np.ndarray) -> list[str]:
    """The ``'N U T'`` part of the configuration for URDF joints q (N, 6) [rad]."""
    p = robot.params
    axes = fanuc_axes_deg(robot, q)
    theta = q * np.asarray(p.sign_corrections, float) - np.asarray(p.offsets, float)
    t2, t23 = theta[:, 1], theta[:, 1] + theta[:, 2]
    psi3, k = np.arctan2(p.a2, p.c3), np.hypot(p.a2, p.c3)
    behind_axis1 = p.c2 * np.sin(t2) + k * np.sin(t23 + psi3) + p.a1 < 0.0
    elbow_down = np.sin(theta[:, 2] + psi3) < 0.0
    return [
        f"{'F' if j5 > 0 else 'N'} {'D' if down else 'U'} {'B' if back else 'T'}"
        for j5, down, back in zip(axes[:, 4], elbow_down, behind_axis1, strict=True)
    ]


def config_strings(robot: RobotModel, q: np.ndarray) -> list[str]:
    """``'N U T, 0, 0, 0'`` for each row of q (N, 6) [rad]."""
    turns = turn_numbers(fanuc_axes_deg(robot, q))
    return [
        f"{flags}, {t[0]}, {t[1]}, {t[2]}"
        for flags, t in zip(config_flags(robot, q), turns, strict=True)
    ]


def wpr_deg(R: np.ndarray) -> np.ndarray:
    """(3,) W, P, R [deg] of a rotation matrix (3, 3): R = Rz(R) Ry(P) Rx(W)."""
    return np.rad2deg(RollPitchYaw(RotationMatrix(R)).vector())


def _f(value: float, digits: int) -> str:
    text = f"{value:.{digits}f}"
    return text if float(text) != 0.0 else f"{0.0:.{digits}f}"


def cartesian_pos(index: int, X_UE: np.ndarray, config: str, *, uf: int, ut: int) -> str:
    """One /POS entry: pose (4, 4) [m] of the tool frame in the user frame."""
    x, y, z = X_UE[:3, 3] * 1e3
    w, p, r = wpr_deg(X_UE[:3, :3])
    m, d = MM_DIGITS, DEG_DIGITS
    return (
        f"P[{index}]{{\n   GP1:\n\tUF : {uf}, UT : {ut},\t\tCONFIG : '{config}',\n"
        f"\tX = {_f(x, m)}  mm,\tY = {_f(y, m)}  mm,\tZ = {_f(z, m)}  mm,\n"
        f"\tW = {_f(w, d)} deg,\tP = {_f(p, d)} deg,\tR = {_f(r, d)} deg\n}};"
    )


def joint_pos(index: int, axes_deg: np.ndarray, *, uf: int, ut: int) -> str:
    """One /POS entry in joint representation (FANUC axes [deg])."""
    j = [_f(v, DEG_DIGITS) for v in axes_deg]
    return (
        f"P[{index}]{{\n   GP1:\n\tUF : {uf}, UT : {ut},\n"
        f"\tJ1= {j[0]} deg,\tJ2= {j[1]} deg,\tJ3= {j[2]} deg,\n"
        f"\tJ4= {j[3]} deg,\tJ5= {j[4]} deg,\tJ6= {j[5]} deg\n}};"
    )


def ls_text(name: str, statements: list[str], positions: list[str], comment: str) -> str:
    """A whole LS file: numbered /MN lines (statements without the closing `` ;``) and
    the /POS entries."""
    mn = "".join(f"{k:4d}:{s} ;\n" for k, s in enumerate(statements, start=1))
    pos = "\n".join(positions)
    return _attr(name, len(statements), comment) + f"/MN\n{mn}/POS\n{pos}\n/END\n"


def remarks(lines: list[str]) -> list[str]:
    """TP remark statements (``! text``, at most 32 characters each) for header lines."""
    return [f"  ! {piece}" for line in lines for piece in fanuc_comments(line)]


def _attr(name: str, lines: int, comment: str) -> str:
    now = datetime.datetime.now(datetime.UTC)
    stamp = f"DATE {now:%y-%m-%d}  TIME {now:%H:%M:%S}"
    return (
        f'/PROG  {name}\n/ATTR\nOWNER\t\t= MNEDITOR;\nCOMMENT\t\t= "{comment[:16]}";\n'
        f"PROG_SIZE\t= 0;\nCREATE\t\t= {stamp};\nMODIFIED\t= {stamp};\nFILE_NAME\t= ;\n"
        f"VERSION\t\t= 0;\nLINE_COUNT\t= {lines};\nMEMORY_SIZE\t= 0;\nPROTECT\t\t= READ_WRITE;\n"
        "TCD:  STACK_SIZE\t= 0,\n      TASK_PRIORITY\t= 50,\n      TIME_SLICE\t= 0,\n"
        "      BUSY_LAMP_OFF\t= 0,\n      ABORT_REQUEST\t= 0,\n      PAUSE_REQUEST\t= 0;\n"
        "DEFAULT_GROUP\t= 1,*,*,*,*;\nCONTROL_CODE\t= 00000000 00000000;\n"
    )
