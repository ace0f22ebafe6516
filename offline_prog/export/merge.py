"""Merging motion statements too short for a robot programmer along the planned path.

A writer that splits a seam's linear moves for its I/O (FANUC: a motion starts where
the flow's value steps, ``export.fanuc.fanuc_io``) can end up with motions of a few µm
where the tool speeds up from rest: ``L P[17] 1mm/sec`` over 0.001 mm. No programmer
writes those, and a controller runs them at its minimum speed. :func:`merge_short`
drops the end points of motions shorter than ``MIN_MOTION_M`` (the programmed TCP's
travel) where the plan allows it: the point is not pinned (the seam's start and end,
a point a switch is attached to or the flow's edge starts at) and the merged motion
still holds the path tolerance against the planned samples it now passes (the
caller's ``fits``, e.g. ``export.points.lin_deviations``). Where neither end may go
(a pinned switch point next to a point the tolerance needs, e.g. a flow edge 0.4 mm
after a point on a curved lead-in), the free end slides along the planned samples,
away from the pinned one, until the motion is long enough, if both motions it then
ends still hold the tolerance (the caller's ``holds``). Every point kept is a planned
sample, so the program still moves through the plan.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Collection

import numpy as np

from offline_prog.export.points import lin_deviations

MIN_MOTION_M = 0.5e-3  # the shortest motion statement a writer leaves where it may merge


def merge_short(
    points: list[int],
    p_tcp: np.ndarray,
    *,
    pinned: Collection[int],
    fits: Callable[[int, int, int], bool],
    min_length_m: float = MIN_MOTION_M,
    holds: Callable[[int, int], bool] | None = None,
) -> list[int]:
    """The points with the ends of short motions merged away where the plan allows.

    A motion a → b shorter than ``min_length_m`` loses b (it joins the next motion) if
    b is not pinned and a → (b's successor) fits; otherwise it loses a (joining the
    previous motion) under the same rule; otherwise a free end slides (``_slid``);
    otherwise it stays (the plan allows no merge there).

    Args:
        points: sorted sample indices of the motions' ends (the first is where the
            robot already is; first and last are kept).
        p_tcp: (N, 3) the programmed TCP's position at each sample [m], one frame.
        pinned: sample indices that stay points.
        fits: whether point k may go from between points i and j (the motion from
            sample i to sample j holds the path tolerance), called as fits(i, k, j).
        min_length_m: the shortest motion wanted [m].
        holds: whether the motion from sample i to sample j holds the path tolerance,
            called as holds(i, j) (None: no end slides).

    Returns:
        The remaining points, sorted (a subset of ``points``).
    """
    out = list(points)
    keep = set(pinned) | {out[0], out[-1]}
    k = 1
    while k < len(out):
        a, b = out[k - 1], out[k]
        if np.linalg.norm(p_tcp[b] - p_tcp[a]) >= min_length_m:
            k += 1
            continue
        for drop in (k, k - 1):
            if out[drop] not in keep and fits(out[drop - 1], out[drop], out[drop + 1]):
                del out[drop]
                k = max(1, drop)  # look at the merged motion again
                break
        else:
            slid = None if holds is None else _slid(out, k, p_tcp, keep, fits, holds, min_length_m)
            if slid is not None:
                out = slid
            k += 1
    return out


def _slid(out, k, p_tcp, keep, fits, holds, min_length_m) -> list[int] | None:
    """The points with the free end of the short motion out[k−1] → out[k] moved to the
    nearest planned sample away from its other end that makes the motion at least
    ``min_length_m`` long, leaving the motion on its far side that long too, where the
    moved-over point may go (``fits``) and that far motion holds the tolerance
    (``holds``); None where no sample does."""
    for end, far, step in ((k - 1, k - 2, -1), (k, k + 1, 1)):
        if out[end] in keep or not 0 <= far < len(out):
            continue
        fixed = out[k] if end == k - 1 else out[k - 1]  # the motion's other end
        for sample in range(out[end] + step, out[far], step):
            if np.linalg.norm(p_tcp[sample] - p_tcp[fixed]) < min_length_m:
                continue
            if np.linalg.norm(p_tcp[out[far]] - p_tcp[sample]) < min_length_m:
                break  # the far motion would be the short one
            i, j = sorted((sample, fixed))
            near = sorted((sample, out[far]))
            if fits(i, out[end], j) and holds(*near):
                return [*out[:end], sample, *out[end + 1 :]]
            break  # a sample further on spans more of the curve: it holds no better
    return None


@dataclasses.dataclass(frozen=True)
class PathCheck:
    """LIN motions between planned samples against the plan, for merging and for the
    deviation a program states.

    Attributes:
        X_BP: (N, 4, 4) the pose the controller interpolates at each sample (the part P
            in the base B, flange style).
        X_BT: (4, 4) the fixed tool T in B.
        chord_tol_m, angle_tol_rad: the tolerances a merged motion must hold, measured
            at the samples [m, rad].
    """

    X_BP: np.ndarray
    X_BT: np.ndarray
    chord_tol_m: float
    angle_tol_rad: float

    @functools.cached_property
    def X_PT(self) -> np.ndarray:
        """(N, 4, 4) the tool frame T in P at each sample."""
        return np.linalg.inv(self.X_BP) @ self.X_BT

    def deviations(self, i: np.ndarray, j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(S,) distances [m] and (S,) angles [rad] of the motions (i, j) (S,) from the
        samples they pass (``points.lin_deviations``)."""
        i, j = np.asarray(i, dtype=int), np.asarray(j, dtype=int)
        return lin_deviations(self.X_BP, self.X_BT, self.X_PT, i, j)

    def fits(self, i: int, j: int) -> bool:
        """Whether the motion from sample i to sample j holds the tolerances."""
        d, a = self.deviations(np.array([i]), np.array([j]))
        return bool(d[0] <= self.chord_tol_m and a[0] <= self.angle_tol_rad)

    def merge(
        self,
        points: list[int],
        pinned: Collection[int],
        also: Callable[[int, int, int], bool] = lambda i, k, j: True,
    ) -> list[int]:
        """merge_short with this check and ``also`` (the writer's own condition on
        dropping point k from between i and j: its process output's), the TCP the
        origin of X_BP; a free end may slide where this check holds."""

        def fits(i: int, k: int, j: int) -> bool:
            return also(i, k, j) and self.fits(i, j)

        return merge_short(points, self.X_BP[:, :3, 3], pinned=pinned, fits=fits, holds=self.fits)
