"""A seam sampled on a model: points, normals and the exact reference, in P [mm].

Both model kinds (STEP, mesh) hand the seam source one :class:`SeamSamples`; the seam
source scales it to metres and turns the outward normals into the surface.
"""

from __future__ import annotations

import dataclasses

import numpy as np

# Points handed to the B-spline fit are this far apart along the edge [mm] ...
FIT_SPACING_MM = 0.5
# ... and closer near the edges' ends, growing from this [mm]: where a fillet meets a
# line the curvature and the normal's turn rate jump, and the fit's knots gather where
# its points do.
FIT_END_SPACING_MM = 0.01
# ... and the reference the fit error is measured against, this far [mm] (its chords
# are within r·(1 − cos(δ/2r)) ≈ δ²/8r of the exact edge: 0.25 µm for r = 5 mm).
REFERENCE_SPACING_MM = 0.1
# Neighbouring edges whose tangents differ by more than this meet at a corner [deg].
CORNER_DEG = 1.0


@dataclasses.dataclass(frozen=True)
class SeamSamples:
    """A seam on a model, in the part frame P [mm].

    Attributes:
        p: (N, 3) points on the seam, FIT_SPACING_MM apart (a closed seam's first point
            not repeated at the end).
        outward: (N, 3) unit outward normals of the normal's face at the points.
        closed: the seam comes back to its start.
        length_mm: the exact length of the seam (before any offset) [mm].
        reference: (M, 3) points on the exact seam, REFERENCE_SPACING_MM apart
            (offset like ``p``), closed like ``p``.
        tolerance_mm: how far ``reference`` may be from the model's exact seam [mm]
            (its own chords for a STEP model; the tessellation for a mesh).
        edges: the model's numbers of the edges run, in order.
        corners: (position (3,) [mm], turn [deg]) where neighbouring edges meet at an
            angle larger than CORNER_DEG (a cusp in the path).
    """

    p: np.ndarray
    outward: np.ndarray
    closed: bool
    length_mm: float
    reference: np.ndarray
    tolerance_mm: float
    edges: tuple[int, ...]
    corners: tuple = ()


def join_pieces(pieces: list[np.ndarray], *, closed: bool) -> np.ndarray:
    """(N, 3) consecutive pieces (each (n_k, 3), the next starting where one ends) as
    one polyline; a closed one without its repeated first point."""
    joined = np.vstack([pieces[0]] + [piece[1:] for piece in pieces[1:]])
    return joined[:-1] if closed else joined


def corners(ends: list[tuple[np.ndarray, np.ndarray, np.ndarray]], *, closed: bool) -> tuple:
    """Corners between consecutive pieces given as (end point, end tangent, start tangent
    of the next piece); the last wraps to the first when closed."""
    found = []
    for k, (point, t_end, t_next) in enumerate(ends):
        if k == len(ends) - 1 and not closed:
            break
        turn = np.rad2deg(np.arccos(np.clip(np.dot(t_end, t_next), -1.0, 1.0)))
        if turn > CORNER_DEG:
            found.append((np.asarray(point), float(turn)))
    return tuple(found)
