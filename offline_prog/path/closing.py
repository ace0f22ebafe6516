"""How a closed contour's point list meets its start: a repeated point or a gap.

CAD and measuring tools write a closed contour in one of two ways: the last point
repeats the first (within the fit tolerance), or the list stops one step short and the
closing stroke is implied, as a polygon's last side is. The repeated point is dropped.
A gap is accepted when it is comparable to the point spacing beside it, at most
``CLOSING_GAP_STEP_RATIO`` times the larger of the first and last steps; the caller
then closes it (the periodic B-spline fit through CSV points; the straight closing
side a DXF's closed flag would draw). A larger gap is a stretch of the contour that is
missing, and :class:`OpenEndsError` names the gap and the spacing.
"""

from __future__ import annotations

import numpy as np

from offline_prog.constants import CLOSING_GAP_STEP_RATIO
from offline_prog.errors import TravellingError

# Consecutive points closer than this are one point [m].
DUPLICATE_POINT_M = 1e-9


class OpenEndsError(TravellingError, ValueError):
    """A closed contour whose ends are too far apart to close: gap_m [m], and the
    spacing at the ends, first_step_m and last_step_m [m]."""

    def __init__(self, gap_m: float, first_step_m: float, last_step_m: float):
        self.gap_m, self.first_step_m, self.last_step_m = gap_m, first_step_m, last_step_m
        super().__init__(
            f"the ends are {gap_m * 1e3:.3f} mm apart, more than {CLOSING_GAP_STEP_RATIO:g} × "
            f"the point spacing there (first step {first_step_m * 1e3:.3f} mm, last step "
            f"{last_step_m * 1e3:.3f} mm): a stretch of the contour is missing"
        )


def end_steps(p: np.ndarray) -> tuple[float, float]:
    """(first step, last step) [m]: the first and the last nonzero chord of ``p`` (N, 3)."""
    chords = np.linalg.norm(np.diff(p, axis=0), axis=1)
    chords = chords[chords > DUPLICATE_POINT_M]
    return (float(chords[0]), float(chords[-1])) if len(chords) else (0.0, 0.0)


def repeats_first(p: np.ndarray, tolerance_m: float) -> bool:
    """Whether a closed contour's points ``p`` (N, 3) [m] end on their first point.

    Returns:
        True when the last point repeats the first within ``tolerance_m`` (drop it);
        False when the ends are a gap the caller closes (at most CLOSING_GAP_STEP_RATIO
        times the larger of the first and last steps).

    Raises:
        OpenEndsError: the gap is larger: a stretch is missing.
    """
    if len(p) < 2:
        return False
    gap = float(np.linalg.norm(p[-1] - p[0]))
    if gap <= max(tolerance_m, DUPLICATE_POINT_M):
        return True
    first, last = end_steps(p)
    if gap > CLOSING_GAP_STEP_RATIO * max(first, last):
        raise OpenEndsError(gap, first, last)
    return False
