"""The fixed tool's axis: T's +z direction in I from ``tool_axis`` touches.

A ``tool_axis`` touch puts the pointer's tip Q on the point d = ``tool_axis_point_mm``
along +z of T: ``p_IE_i + R_IE_i p_EQ = p_IT + d z_T``. With the tip p_IT and the
pointer p_EQ known (the pivot), each touch gives the direction z_T; their mean starts
the joint estimate. The rotation about the axis is not observed: R_IT becomes the
cell's R_IT turned by the smallest rotation from its z axis to z_T
(``measurement.axis_rotation``), so a symmetric tool keeps the turn the cell gives it.
"""

from __future__ import annotations

import numpy as np

from offline_prog.calibration.limits import MAX_AXIS_TILT_DEG, MIN_TOOL_AXIS_TOUCHES
from offline_prog.calibration.measurement import axis_rotation
from offline_prog.errors import InputError


def axis_start(
    X_IE: np.ndarray, p_IT: np.ndarray, p_EQ: np.ndarray, R_IT: np.ndarray, file: str
) -> np.ndarray:
    """R_IT (3, 3) with its z axis through the touched axis points.

    Args:
        X_IE: (N, 4, 4) flange poses of the ``tool_axis`` touches [m].
        p_IT: (3,) the tool's tip in I [mm]; p_EQ: (3,) the pointer's tip in E [mm].
        R_IT: (3, 3) the cell's rotation of T in I.

    Raises:
        InputError: the touched axis leans more than MAX_AXIS_TILT_DEG from the
            cell's (a wrong sign of tool_axis_point_mm, or the wrong point touched).
    """
    p_IQ = X_IE[:, :3, 3] * 1e3 + np.einsum("nij,j->ni", X_IE[:, :3, :3], p_EQ)
    z = (p_IQ - p_IT).mean(axis=0)
    z = z / np.linalg.norm(z)
    tilt = np.degrees(np.arccos(np.clip(z @ R_IT[:, 2], -1.0, 1.0)))
    if tilt > MAX_AXIS_TILT_DEG:
        raise InputError(
            file,
            "",
            f"the tool_axis touches lie {tilt:.0f}° off the cell's +z axis of T (at most "
            f"{MAX_AXIS_TILT_DEG:g}°): check calibration.tool_axis_point_mm's sign, the "
            "point touched, or tool.X_IT",
        )
    a = (z @ R_IT[:, :2]) / (z @ R_IT[:, 2])
    return axis_rotation(R_IT, a)


def check_axis(file: str, n_axis: int, n_tip: int) -> None:
    """Enough ``tool_axis`` touches, and ``tool_tip`` touches for the pointer.

    Raises:
        InputError: one line saying what to add.
    """
    if n_axis and n_tip == 0:
        raise InputError(
            file,
            "",
            "tool_axis touches need tool_tip touches too (the pointer's tip is found from "
            "them): add tool_tip touches",
        )
    if 0 < n_axis < MIN_TOOL_AXIS_TOUCHES:
        raise InputError(
            file,
            "",
            f"{n_axis} tool_axis touch: the axis needs at least {MIN_TOOL_AXIS_TOUCHES}; "
            f"add {MIN_TOOL_AXIS_TOUCHES - n_axis}",
        )
