"""Point density of Cartesian programs: as few points as the tolerances allow.

A controller moving LIN between two programmed poses interpolates the position
along the chord and the orientation by slerp in proportion. ``select_points``
keeps the dense plan's samples that are needed so that every dropped sample
lies within ``chord_tol_m`` of that chord and within ``angle_tol_rad`` of the
interpolated orientation (greedy, longest segment first: doubling then
bisection, O(N log N) vectorized checks).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial.transform import Rotation

DEFAULT_CHORD_TOL_M = 0.05e-3
DEFAULT_ANGLE_TOL_RAD = np.deg2rad(0.1)


@dataclasses.dataclass(frozen=True)
class Selection:
    """Chosen sample indices (first and last included) and the achieved deviations."""

    indices: np.ndarray
    max_chord_m: float
    max_angle_rad: float


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


def rotation_matrices(rotvec: np.ndarray) -> np.ndarray:
    """(K, 3, 3) rotations of (K, 3) rotation vectors [rad] (Rodrigues, vectorized)."""
    angle = np.linalg.norm(rotvec, axis=1)
    small = angle < 1e-12
    axis = rotvec / np.where(small, 1.0, angle)[:, None]
    K = np.zeros((len(rotvec), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    K -= np.swapaxes(K, 1, 2)
    s, c = np.sin(angle)[:, None, None], (1.0 - np.cos(angle))[:, None, None]
    return np.eye(3) + s * K + c * (K @ K)


def rotation_angles(R: np.ndarray) -> np.ndarray:
    """(K,) rotation angles [rad] of (K, 3, 3) rotations, accurate near 0 and π
    (atan2 of the skew part's norm against the trace)."""
    skew = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], 1)
    return np.arctan2(0.5 * np.linalg.norm(skew, axis=1), 0.5 * (np.trace(R, axis1=1, axis2=2) - 1))


def select_points(
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
