"""ABB conventions: controller axis values and confdata (see ``export.abb.rapid``)."""

from __future__ import annotations

import numpy as np

from offline_prog.robot.model import RobotModel


def abb_axes_deg(robot: RobotModel, q: np.ndarray) -> np.ndarray:
    """Controller axis values (N, 6) [deg] from URDF joint positions q (N, 6) [rad]:
    axis 3 = q3 + j23_factor · q2 on a robot whose controller couples them (the robot
    record's ``controller.j23_factor``, ``RobotModel.controller_joints``)."""
    return np.rad2deg(robot.controller_joints(np.asarray(q, dtype=float)))


def confdata(robot: RobotModel, q: np.ndarray) -> np.ndarray:
    """``[cf1, cf4, cf6, cfx]`` (N, 4) for URDF joints q (N, 6) [rad] of an OPW robot.

    cfN = floor(axis N / 90°): 0 for [0°, 90°), -1 for [-90°, 0°), 1 for [90°, 180°) ...
    cfx = 4·a + 2·b + c (RAPID TRM, confdata, 6-axis robots, table of 8 configurations):
    a = wrist centre behind axis 1, b = wrist centre behind the lower arm (the line
    axis 2 → axis 3), c = axis 5 value negative. In OPW terms (wrist centre in the arm plane):
    a ⇔ x of the wrist centre in the frame turned by θ1 < 0; b ⇔ sin(θ3 + ψ3) < 0 with
    ψ3 = atan2(a2, c3), the side of the lower-arm line the wrist centre is on.
    """
    p = robot.params
    cf = np.floor(np.rad2deg(q[:, [0, 3, 5]]) / 90.0).astype(int)
    theta = q * np.asarray(p.sign_corrections, float) - np.asarray(p.offsets, float)
    t2, t23 = theta[:, 1], theta[:, 1] + theta[:, 2]
    psi3, k = np.arctan2(p.a2, p.c3), np.hypot(p.a2, p.c3)
    behind_axis1 = p.c2 * np.sin(t2) + k * np.sin(t23 + psi3) + p.a1 < 0.0
    behind_lower_arm = np.sin(theta[:, 2] + psi3) < 0.0
    cfx = 4 * behind_axis1 + 2 * behind_lower_arm + (q[:, 4] < 0.0)
    return np.column_stack([cf, cfx]).astype(int)
