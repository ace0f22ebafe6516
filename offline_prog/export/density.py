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

from offline_prog.export.deviation import segment_deviations

DEFAULT_CHORD_TOL_M = 0.05e-3
DEFAULT_ANGLE_TOL_RAD = np.deg2rad(0.1)


@dataclasses.dataclass(frozen=True)
class Selection:
    """Chosen sample indices (first and last included) and the achieved deviations."""

    indices: np.ndarray
    max_chord_m: float
    max_angle_rad: float


def select_points(
    p: np.ndarray,
    R: np.ndarray,
    *,
    chord_tol_m: float = DEFAULT_CHORD_TOL_M,
    angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD,
) -> Selection:
    """Fewest samples of a dense pose path that LIN segments follow within tolerance.

    From each chosen sample i: double the segment while it fits, then bisect for the
    last end that fits. The deviations the search asks for are evaluated in batches
    (``export.deviation``): the doublings up to a few times the last segment's length
    at once, the next levels of the bisection at once; the search itself and so the
    points chosen are those of asking one segment at a time.

    Args:
        p: (N, 3) positions [m]; R: (N, 3, 3) orientations, in one frame.
        chord_tol_m, angle_tol_rad: largest allowed deviation of any dense sample.
    """
    n = len(p)
    chosen, i, last = [0], 0, 1
    worst_d = worst_a = 0.0
    while i < n - 1:
        known = {i + 1: (0.0, 0.0)}  # (distance, angle) of segment (i, j) by j

        def ask(ends: list[int], i=i, known=known) -> None:
            ends = [j for j in dict.fromkeys(ends) if j not in known]
            if ends:
                d, a = segment_deviations(p, R, np.full(len(ends), i), np.asarray(ends))
                known.update(zip(ends, zip(d.tolist(), a.tolist(), strict=True), strict=True))

        def fits(j: int, known=known) -> bool:
            d, a = known[j]
            return d <= chord_tol_m and a <= angle_tol_rad

        step = 1
        while i + 2 * step < n:
            if i + 2 * step not in known:
                ask(_likely(i, n, last) if step == 1 else _doublings(i, step, n, reach=4 * last))
            if not fits(i + 2 * step):
                break
            step *= 2
        lo, hi = i + step, min(i + 2 * step, n - 1)  # lo fits; find the last that fits
        if hi == n - 1:
            ask([hi])
            if fits(hi):
                lo = hi
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if mid not in known:
                ask(_bisections(lo, hi, levels=_levels(hi - i)))
            lo, hi = (mid, hi) if fits(mid) else (lo, mid)
        d, a = known[lo]
        worst_d, worst_a = max(worst_d, d), max(worst_a, a)
        chosen.append(lo)
        last, i = lo - i, lo
    return Selection(np.asarray(chosen), worst_d, worst_a)


_BATCH_SAMPLES = 4096  # inner samples per batch of bisection candidates


def _likely(i: int, n: int, last: int) -> list[int]:
    """The ends a search from i asks for if its segment is about as long as the last
    one (``last`` samples): the doublings up to 4·last, and the bisection between the
    last doubling that would then fit and the first that would not (guess, 2·guess),
    with the path's last sample when it lies there."""
    guess = 1 << (last.bit_length() - 1)
    ends = _doublings(i, 1, n, reach=4 * last) + ([n - 1] if i + 2 * guess >= n - 1 else [])
    return ends + _bisections(i + guess, min(i + 2 * guess, n - 1), levels=_levels(2 * guess))


def _doublings(i: int, step: int, n: int, *, reach: int) -> list[int]:
    """The next doubled ends i + 2·step, i + 4·step, ... below n, as far as ``reach``
    samples from i (at least the first)."""
    ends, end = [], i + 2 * step
    while end < n and (not ends or end - i <= reach):
        ends.append(end)
        end = i + 2 * (end - i)
    return ends


def _levels(length: int) -> int:
    """How many levels of a bisection to evaluate at once for segments about
    ``length`` samples long (2^levels − 1 of them within _BATCH_SAMPLES, at least 1)."""
    return max(1, int(np.log2(_BATCH_SAMPLES / max(length, 1) + 1)))


def _bisections(lo: int, hi: int, *, levels: int) -> list[int]:
    """The midpoints a bisection of (lo, hi) may ask for in its next ``levels`` steps."""
    if levels == 0 or hi - lo <= 1:
        return []
    mid = (lo + hi) // 2
    return [mid, *_bisections(lo, mid, levels=levels - 1), *_bisections(mid, hi, levels=levels - 1)]
