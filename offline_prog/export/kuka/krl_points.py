"""Which plan samples become KRL LIN points, for each KRL style (see ``export.kuka.krl``).

Frames: B robot base, P part, F process frame, T fixed tool. Tolerances: chord [m]
and angle [rad] against the plan's process frames.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.export.density import (
    rotation_angles,
    rotation_matrices,
    segment_deviation,
    select_points,
)
from offline_prog.export.program import ProgramData

_GRID = 64  # flange style: nozzle curve samples per LIN segment


def _nozzle_deviation(X_BP, X_BT, X_PF, i: int, j: int) -> tuple[float, float]:
    """Flange style: largest distance [m] / angle [rad] of the plan's X_PF[i..j] from the
    tool frame's curve on the part while the controller interpolates X_BP from i to j
    (position linear, orientation slerp, one parameter)."""
    if j - i < 2:
        return 0.0, 0.0
    lam = np.linspace(0.0, 1.0, _GRID + 1)
    rotvec = Rotation.from_matrix(X_BP[i, :3, :3].T @ X_BP[j, :3, :3]).as_rotvec()
    R_BP = X_BP[i, :3, :3] @ rotation_matrices(lam[:, None] * rotvec)
    p_BP = X_BP[i, :3, 3] + lam[:, None] * (X_BP[j, :3, 3] - X_BP[i, :3, 3])
    p_PT = np.einsum("nji,nj->ni", R_BP, X_BT[:3, 3] - p_BP)  # (G+1, 3) tool origin in P
    a, d = p_PT[:-1], np.diff(p_PT, axis=0)
    inner = X_PF[i + 1 : j, :3, 3]
    u = np.clip(np.einsum("kgc,gc->kg", inner[:, None] - a, d) / (d * d).sum(1).clip(1e-30), 0, 1)
    gap = np.linalg.norm(inner[:, None] - a - u[..., None] * d, axis=2)  # (K, G)
    near = gap.argmin(axis=1)
    R_PT = np.swapaxes(R_BP[near], 1, 2) @ X_BT[:3, :3]
    angle = rotation_angles(np.swapaxes(R_PT, 1, 2) @ X_PF[i + 1 : j, :3, :3])
    return float(gap.min(axis=1).max()), float(angle.max())


def process_points(
    data: ProgramData,
    style: str,
    chord_tol_m: float,
    angle_tol_rad: float,
    convention: str = "X_TP",
):
    """The samples that become LIN points, and the worst deviation [m, rad].

    ``external_tcp``: the points hold the tolerances both if the controller moves the
    fixed TCP in straight lines across the part (the process frames X_PF interpolated)
    and if it interpolates the written poses (X_TP = P in T for the "X_TP" convention:
    the tool's curve on the part then bends with the part's rotation). ``flange``: each
    LIN segment of X_BP is split until the nozzle's curve on the part also stays within
    them.

    Returns:
        (indices (K,), max chord [m], max angle [rad]).
    """
    p, R = data.X_PF[:, :3, 3], data.X_PF[:, :3, :3]
    chosen = select_points(p, R, chord_tol_m=chord_tol_m, angle_tol_rad=angle_tol_rad)
    if style == "external_tcp" and convention == "X_PF":  # the written poses are X_PF
        return chosen.indices, chosen.max_chord_m, chosen.max_angle_rad
    if style == "flange":  # the controller interpolates P in B; the tool is fixed in B
        X_BP, X_BT = data.X_BE @ data.X_EP, data.X_BT
    else:  # it interpolates P in T, the tool at T's origin
        X_BP, X_BT = np.linalg.inv(data.X_PF), np.eye(4)
    indices, worst = [int(chosen.indices[0])], np.zeros(2)
    stack = list(zip(chosen.indices[1:], chosen.indices[:-1], strict=True))[::-1]
    while stack:  # split each LIN segment until the nozzle curve on P fits as well
        j, i = (int(v) for v in stack.pop())
        deviation = np.maximum(
            segment_deviation(p, R, i, j), _nozzle_deviation(X_BP, X_BT, data.X_PF, i, j)
        )
        if j - i > 1 and (deviation[0] > chord_tol_m or deviation[1] > angle_tol_rad):
            stack += [(j, (i + j) // 2), ((i + j) // 2, i)]
            continue
        indices.append(j)
        worst = np.maximum(worst, deviation)
    return np.asarray(indices), float(worst[0]), float(worst[1])
