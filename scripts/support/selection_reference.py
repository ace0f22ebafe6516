"""The point selection as it was before it was vectorised (main at c8cd200): one
deviation per candidate segment in Python. The reference that the batched selection
(export.density.select_points, export.kuka.krl_points.process_points) must reproduce
point for point; scripts/bench_write.py times both."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M, Selection
from offline_prog.export.deviation import rotation_angles, rotation_matrices

_GRID = 64


def segment_deviation(p: np.ndarray, R: np.ndarray, i: int, j: int) -> tuple[float, float]:
    """Largest position [m] and angle [rad] deviation of samples i..j from LIN i → j.

    Args:
        p: (N, 3) positions; R: (N, 3, 3) orientations (same frame).
    """
    if j - i < 2:
        return 0.0, 0.0
    a, b = p[i], p[j]
    chord = b - a
    length2 = float(chord @ chord)
    inner = p[i + 1 : j]
    lam = np.clip((inner - a) @ chord / length2, 0.0, 1.0) if length2 > 0 else np.zeros(len(inner))
    distance = np.linalg.norm(inner - (a + lam[:, None] * chord), axis=1)
    if length2 == 0.0:  # pure reorientation: interpolate by sample index instead
        lam = np.arange(1, j - i) / (j - i)
    # Slerp R(λ) = R_i·Exp(λ·θ·k) = R_i + sin(λθ)·R_i·K + (1 − cos(λθ))·R_i·K² (K = [k]×),
    # and each sample's angle from it by the trace: tr(R(λ)ᵀ R_k) = 1 + 2 cos(angle).
    omega = rotation_vector(R[i].T @ R[j])
    theta = float(np.linalg.norm(omega))
    k = omega / theta if theta > 0 else np.zeros(3)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    A, B, R_k = R[i] @ K, R[i] @ K @ K, R[i + 1 : j]
    trace = (
        np.einsum("nab,ab->n", R_k, R[i])
        + np.sin(lam * theta) * np.einsum("nab,ab->n", R_k, A)
        + (1.0 - np.cos(lam * theta)) * np.einsum("nab,ab->n", R_k, B)
    )
    angle = np.arccos(np.clip(0.5 * (trace - 1.0), -1.0, 1.0))  # ~1e-8 rad near 0
    return float(distance.max()), float(angle.max())


def rotation_vector(R: np.ndarray) -> np.ndarray:
    """(3,) rotation vector [rad] of one rotation (3, 3): axis · angle. Near π the axis
    is ill-conditioned from the skew part, so scipy's careful branch takes over."""
    skew = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    sin2 = float(np.linalg.norm(skew))  # 2 sin θ
    angle = float(np.arctan2(0.5 * sin2, 0.5 * (np.trace(R) - 1.0)))
    if angle > np.pi - 1e-3:
        return Rotation.from_matrix(R).as_rotvec()
    return skew * (angle / sin2) if sin2 > 1e-15 else 0.5 * skew


def reference_select_points(
    p: np.ndarray,
    R: np.ndarray,
    *,
    chord_tol_m: float = DEFAULT_CHORD_TOL_M,
    angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD,
) -> Selection:
    """Fewest samples of a dense pose path that LIN segments follow within tolerance.

    Args:
        p: (N, 3) positions [m]; R: (N, 3, 3) orientations, in one frame.
        chord_tol_m, angle_tol_rad: largest allowed deviation of any dense sample.
    """
    n = len(p)

    def fits(i: int, j: int) -> bool:
        d, a = segment_deviation(p, R, i, j)
        return d <= chord_tol_m and a <= angle_tol_rad

    chosen, i = [0], 0
    worst_d = worst_a = 0.0
    while i < n - 1:
        step = 1
        while i + 2 * step < n and fits(i, i + 2 * step):
            step *= 2
        lo, hi = i + step, min(i + 2 * step, n - 1)  # lo fits; find the last that fits
        if hi == n - 1 and fits(i, hi):
            lo = hi
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if fits(i, mid):
                lo = mid
            else:
                hi = mid
        d, a = segment_deviation(p, R, i, lo)
        worst_d, worst_a = max(worst_d, d), max(worst_a, a)
        chosen.append(lo)
        i = lo
    return Selection(np.asarray(chosen), worst_d, worst_a)


def reference_nozzle_deviation(X_BP, X_BT, X_PF, i: int, j: int) -> tuple[float, float]:
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


def reference_process_points(
    data,
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
    p, R = data.X_PT[:, :3, 3], data.X_PT[:, :3, :3]
    chosen = reference_select_points(p, R, chord_tol_m=chord_tol_m, angle_tol_rad=angle_tol_rad)
    if style == "external_tcp" and convention == "X_PF":  # the written poses are X_PF
        return chosen.indices, chosen.max_chord_m, chosen.max_angle_rad
    if style == "flange":  # the controller interpolates P in B; the tool is fixed in B
        X_BP, X_BT = data.X_BE @ data.X_EP, data.X_BT
    else:  # it interpolates P in T, the tool at T's origin
        X_BP, X_BT = np.linalg.inv(data.X_PT), np.eye(4)
    indices, worst = [int(chosen.indices[0])], np.zeros(2)
    stack = list(zip(chosen.indices[1:], chosen.indices[:-1], strict=True))[::-1]
    while stack:  # split each LIN segment until the nozzle curve on P fits as well
        j, i = (int(v) for v in stack.pop())
        deviation = np.maximum(
            segment_deviation(p, R, i, j), reference_nozzle_deviation(X_BP, X_BT, data.X_PT, i, j)
        )
        if j - i > 1 and (deviation[0] > chord_tol_m or deviation[1] > angle_tol_rad):
            stack += [(j, (i + j) // 2), ((i + j) // 2, i)]
            continue
        indices.append(j)
        worst = np.maximum(worst, deviation)
    return np.asarray(indices), float(worst[0]), float(worst[1])
