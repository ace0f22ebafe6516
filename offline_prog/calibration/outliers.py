"""One gross outlier among the touches: found, named and left out.

A wrong touch (the pointer beside the tip, a mistyped angle, a point named for
another) pulls the least-squares fit towards it, so its own residual understates it.
Each touch is therefore judged by the fit of the others (leave one out): touch i is an
outlier when its distance from that fit exceeds both ``OUTLIER_SIGMAS`` times the
others' noise per axis and ``OUTLIER_FLOOR_MM``. Only the ``OUTLIER_CANDIDATES``
touches farthest from the fit of all are tried, and only when one of them is beyond the
floor at all (clean touches cost one fit). Of the candidates, the one farthest from its
fit in units of the others' noise is taken. A candidate whose removal leaves the
touches degenerate (too few, too alike) cannot be judged and is skipped.

After one outlier is left out the search runs once more: a second outlier is not
guessed at but refused in one line naming both touches.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.calibration.estimate import Estimate, fit
from offline_prog.calibration.limits import OUTLIER_CANDIDATES, OUTLIER_FLOOR_MM, OUTLIER_SIGMAS
from offline_prog.calibration.measurement import Problem
from offline_prog.errors import InputError


@dataclasses.dataclass(frozen=True)
class Outlier:
    """A touch left out: its index in the file's touches, line, target, its residual
    (3,) under the fit of the others [mm], that distance and it in units of their
    noise."""

    index: int
    line: int
    target: str
    residual: np.ndarray
    distance_mm: float
    sigmas: float


def _worst(estimate: Estimate) -> tuple[int, Estimate, float, float] | None:
    """(i, the fit without touch i, i's distance [mm], in noise units) of the touch
    most likely an outlier, or None when no candidate is beyond the floor."""
    distances = np.linalg.norm(estimate.residuals, axis=1)
    order = np.argsort(distances)[::-1][:OUTLIER_CANDIDATES]
    best = None
    for i in order:
        if distances[i] <= OUTLIER_FLOOR_MM:
            break
        problem = estimate.problem.without(int(i))
        try:
            others = fit(problem)
        except InputError:  # without it the touches are degenerate: cannot judge it
            continue
        # The unknowns are the same without it: the whole problem's residual at x.
        distance = float(np.linalg.norm(estimate.problem.residuals(others.x)[i]))
        ratio = distance / max(others.noise, 1e-12)
        if best is None or ratio > best[3]:
            best = (int(i), others, distance, ratio)
    return best


def _is_outlier(distance: float, ratio: float) -> bool:
    return distance > OUTLIER_FLOOR_MM and ratio > OUTLIER_SIGMAS


def robust_fit(problem: Problem) -> tuple[Estimate, Outlier | None]:
    """The fit of the touches without their one gross outlier (if any), and that one.

    Raises:
        InputError: degenerate touches (``estimate.fit``), or two gross outliers.
    """
    estimate = fit(problem)
    worst = _worst(estimate)
    if worst is None or not _is_outlier(worst[2], worst[3]):
        return estimate, None
    i, cleaned, distance, ratio = worst
    touches = problem.touches
    residual = problem.residuals(cleaned.x)[i]
    outlier = Outlier(i, touches.lines[i], touches.targets[i], residual, distance, ratio)
    second = _worst(cleaned)
    if second is not None and _is_outlier(second[2], second[3]):
        j = second[0] + (second[0] >= i)  # its index among all touches
        raise InputError(
            touches.file,
            "",
            f"more than one touch is off the others: {touches.where(i)} by "
            f"{distance:.2f} mm and {touches.where(j)} by {second[2]:.2f} mm; check or "
            "touch them again",
        )
    return cleaned, outlier
