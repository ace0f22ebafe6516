"""Picking a face, loop or edge of a model by a point near it (``*_near_mm`` keys).

The nearest candidate wins, unless the point is far from the model or two candidates
are nearly as near: both are errors naming the point and the candidates, so a seam is
never taken from a face or edge the user did not mean.
"""

from __future__ import annotations

import numpy as np

from offline_prog.errors import TravellingError

# Two candidates nearer than this to equal distance are ambiguous [mm] ...
AMBIGUOUS_MM = 0.5
# ... and a point farther than this from every candidate is off the model [mm].
FAR_MM = 5.0


class PickError(TravellingError, ValueError):
    """A point that picks nothing, or two things; ``key`` is the cell-file key's tail
    below the seam (``cad.loop.face_near_mm``), str() is one line."""

    def __init__(self, key: str, reason: str):
        self.key, self.reason = key, reason
        super().__init__(f"{key}: {reason}")


def _mm(point) -> str:
    return "[" + ", ".join(f"{v:g}" for v in np.round(np.asarray(point, float), 3)) + "]"


def pick(point_mm, distances_mm, labels: list[str], *, what: str, key: str) -> int:
    """The index of the candidate nearest ``point_mm``.

    Args:
        point_mm: (3,) the point given in the cell file [mm].
        distances_mm: (K,) distance from it to each candidate [mm].
        labels: (K,) each candidate's name (``face 3 (plane)``), for the message.
        what: the kind picked (``face``, ``edge``), for the message.
        key: the cell-file key that gave the point.

    Raises:
        PickError: nothing within FAR_MM, or a second candidate within AMBIGUOUS_MM of
            the nearest one's distance.
    """
    d = np.asarray(distances_mm, float)
    if d.size == 0:
        raise PickError(key, f"the model has no {what} to pick")
    order = np.argsort(d, kind="stable")
    best = int(order[0])
    nearest = ", ".join(f"{labels[i]} at {d[i]:.2f} mm" for i in order[:3])
    if d[best] > FAR_MM:
        raise PickError(
            key,
            f"{_mm(point_mm)} is {d[best]:.2f} mm from the nearest {what}, more than "
            f"{FAR_MM:g} mm (nearest: {nearest})",
        )
    if d.size > 1 and d[order[1]] - d[best] < AMBIGUOUS_MM:
        raise PickError(
            key,
            f"{_mm(point_mm)} is ambiguous: {labels[best]} and {labels[int(order[1])]} are "
            f"within {AMBIGUOUS_MM:g} mm of the same distance ({nearest}); move the point "
            f"onto the {what} you mean",
        )
    return best
