"""Which plan samples become a seam's linear moves, for the way a controller interpolates.

A controller moving linearly between two written poses interpolates one frame in
another: the fixed tool across the part (``external_tcp``: KRL ``$IPO_MODE=#TCP``, RAPID's
stationary tool), or the part frame in the robot base (``flange``: FANUC's flange-style
points, the tool fixed in B). :class:`PointRule` says which, and the tolerances; every
writer's points come from :func:`process_points`.

Frames: B robot base, P part, F process frame, T fixed tool. Tolerances: chord [m]
and angle [rad] against the plan's tool frames X_PT (the process frames on the seam).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.export.density import (
    DEFAULT_ANGLE_TOL_RAD,
    DEFAULT_CHORD_TOL_M,
    select_points,
)
from offline_prog.export.deviation import (
    inner_samples,
    rotation_angles,
    rotation_matrices,
    segment_deviations,
    segment_max,
)
from offline_prog.export.program import ProgramData

STYLES = ("external_tcp", "flange")
# The pose a controller interpolates in the external_tcp style: "X_TP", the part P in
# the tool T (KSS's rule for every Cartesian position), or "X_PF", T in P (the process
# frame itself: interpolating it moves T straight across P).
CONVENTIONS = ("X_TP", "X_PF")
_GRID = 64  # flange style: nozzle curve samples per LIN segment
_BATCH_SAMPLES = 4096  # inner samples per batch ((K, _GRID, 3) arrays of a few MB)


def _nozzle_deviations(X_BP, X_BT, X_PT, i: np.ndarray, j: np.ndarray):
    """Flange style: for each segment (i, j) (S,), the largest distance [m] / angle [rad]
    of the plan's X_PT[i..j] from the tool frame's curve on the part while the controller
    interpolates X_BP from i to j (position linear, orientation slerp, one parameter);
    0 for j − i < 2. Segments in batches of about _BATCH_SAMPLES inner samples.

    Returns:
        ((S,) distances [m], (S,) angles [rad]).
    """
    distance, angle = np.zeros(len(i)), np.zeros(len(i))
    live = np.flatnonzero(j - i >= 2)
    inner = np.cumsum(j[live] - i[live] - 1)
    for batch in np.split(live, np.flatnonzero(np.diff(inner // _BATCH_SAMPLES)) + 1):
        if len(batch):
            distance[batch], angle[batch] = _nozzle_batch(X_BP, X_BT, X_PT, i[batch], j[batch])
    return distance, angle


def _nozzle_batch(X_BP, X_BT, X_PT, i: np.ndarray, j: np.ndarray):
    """_nozzle_deviations of segments (S,) with j − i ≥ 2, in one pass."""
    lam = np.linspace(0.0, 1.0, _GRID + 1)
    R_i, R_j = X_BP[i, :3, :3], X_BP[j, :3, :3]
    rotvec = Rotation.from_matrix(np.swapaxes(R_i, 1, 2) @ R_j).as_rotvec()
    turns = rotation_matrices((lam[None, :, None] * rotvec[:, None, :]).reshape(-1, 3))
    R_BP = R_i[:, None] @ turns.reshape(len(i), _GRID + 1, 3, 3)  # (S, G+1, 3, 3)
    p_i = X_BP[i, :3, 3]
    p_BP = p_i[:, None] + lam[None, :, None] * (X_BP[j, :3, 3] - p_i)[:, None]
    p_PT = np.einsum("sgji,sgj->sgi", R_BP, X_BT[:3, 3] - p_BP)  # (S, G+1, 3) tool origin in P
    a, d = p_PT[:, :-1], np.diff(p_PT, axis=1)
    seg, k = inner_samples(i, j)
    inner = X_PT[k, :3, 3]
    u = np.einsum("kgc,kgc->kg", inner[:, None] - a[seg], d[seg])
    u = np.clip(u / (d * d).sum(2).clip(1e-30)[seg], 0, 1)
    gap = np.linalg.norm(inner[:, None] - a[seg] - u[..., None] * d[seg], axis=2)  # (K, G)
    near = gap.argmin(axis=1)
    R_PT_curve = np.swapaxes(R_BP[seg, near], 1, 2) @ X_BT[:3, :3]
    angle = rotation_angles(np.swapaxes(R_PT_curve, 1, 2) @ X_PT[k, :3, :3])
    return segment_max(gap.min(axis=1), i, j), segment_max(angle, i, j)


def lin_deviations(X_BP, X_BT, X_PT, i: np.ndarray, j: np.ndarray):
    """For each LIN segment (i, j) (S,) between pose samples, the largest deviation of
    the plan's samples between them: both from the straight line of the tool frames
    X_PT (N, 4, 4) across the part and from the tool's curve on the part while the
    controller interpolates X_BP (N, 4, 4) with the tool fixed at X_BT (4, 4) (flange
    style: P in B with T in B; external_tcp with the X_TP convention: X_BP = X_PT⁻¹,
    X_BT = identity).

    Returns:
        ((S,) distances [m], (S,) angles [rad]).
    """
    p, R = X_PT[:, :3, 3], X_PT[:, :3, :3]
    d_line, a_line = segment_deviations(p, R, i, j)
    d_tool, a_tool = _nozzle_deviations(X_BP, X_BT, X_PT, i, j)
    return np.maximum(d_line, d_tool), np.maximum(a_line, a_tool)


@dataclasses.dataclass(frozen=True)
class PointRule:
    """How a writer's controller interpolates (``style``, and for external_tcp the
    written pose ``convention``), and the largest deviation [m, rad] of the plan from it allowed.

    Raises:
        ValueError: a style or convention not in STYLES / CONVENTIONS, or a tolerance ≤ 0.
    """

    style: str
    convention: str = "X_TP"
    chord_tol_m: float = DEFAULT_CHORD_TOL_M
    angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD

    def __post_init__(self):
        if self.style not in STYLES or self.convention not in CONVENTIONS:
            raise ValueError(
                f"style {self.style!r} / tcp_pose_convention {self.convention!r}: "
                f"use one of {STYLES} / {CONVENTIONS}"
            )
        if not (self.chord_tol_m > 0 and self.angle_tol_rad > 0):  # NaN too
            raise ValueError("need chord_tol_m > 0 and angle_tol_rad > 0")


def process_points(data: ProgramData, rule: PointRule, chord_tol_m: float, angle_tol_rad: float):
    """The samples that become linear moves under ``rule``, within the tolerances given
    here (the rule's, less what densify measured between the samples), and the worst
    deviation [m, rad].

    ``external_tcp``: the points hold the tolerances both if the controller moves the
    fixed TCP in straight lines across the part (the tool frames X_PT interpolated)
    and if it interpolates the written poses (X_TP = P in T for the "X_TP" convention:
    the tool's curve on the part then bends with the part's rotation). ``flange``: each
    LIN segment of X_BP is split until the nozzle's curve on the part also stays within
    them.

    Returns:
        (indices (K,), max chord [m], max angle [rad]).
    """
    p, R = data.X_PT[:, :3, 3], data.X_PT[:, :3, :3]
    chosen = select_points(p, R, chord_tol_m=chord_tol_m, angle_tol_rad=angle_tol_rad)
    if rule.style == "external_tcp" and rule.convention == "X_PF":  # the poses are T in P
        return chosen.indices, chosen.max_chord_m, chosen.max_angle_rad
    if rule.style == "flange":  # the controller interpolates P in B; the tool is fixed in B
        X_BP, X_BT = data.X_BE @ data.X_EP, data.X_BT
    else:  # it interpolates P in T, the tool at T's origin
        X_BP, X_BT = np.linalg.inv(data.X_PT), np.eye(4)
    # Split each LIN segment until the nozzle curve on P fits as well, all the
    # segments of a round at once; the ends kept are those of splitting one by one.
    i, j = chosen.indices[:-1], chosen.indices[1:]
    ends, worst = [chosen.indices[:1]], np.zeros(2)
    while len(i):
        d, a = lin_deviations(X_BP, X_BT, data.X_PT, i, j)
        split = (j - i > 1) & ((d > chord_tol_m) | (a > angle_tol_rad))
        ends.append(j[~split])
        worst = np.maximum(worst, [d[~split].max(initial=0.0), a[~split].max(initial=0.0)])
        mid = (i[split] + j[split]) // 2
        i, j = np.concatenate([i[split], mid]), np.concatenate([mid, j[split]])
    return np.sort(np.concatenate(ends)), float(worst[0]), float(worst[1])
