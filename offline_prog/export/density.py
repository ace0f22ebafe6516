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
    R_ij = Rotation.from_matrix(R[i].T @ R[j]).as_rotvec()
    R_interp = R[i] @ Rotation.from_rotvec(lam[:, None] * R_ij).as_matrix()
    angle = Rotation.from_matrix(np.swapaxes(R_interp, 1, 2) @ R[i + 1 : j]).magnitude()
    return float(distance.max()), float(angle.max())


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
