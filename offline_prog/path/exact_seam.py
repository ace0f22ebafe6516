"""The exact seam a model gives, and how far the fitted path is from it.

A seam taken from a CAD model (``cad:``) is known exactly, not only at the points the
B-spline fit sees: its reference polyline lies within ``tolerance_m`` of the model's
edge (the chords of a dense sampling of the B-rep curve, or the tessellation of a
mesh). The fit error reported for such a seam is measured against it along the whole
fitted path, not at the fit's own points.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial import cKDTree

# The fitted path is compared with the reference at this spacing [m].
COMPARE_SPACING_M = 1e-4


@dataclasses.dataclass(frozen=True)
class ExactSeam:
    """A seam on the part's model, in P [m].

    Attributes:
        reference_P: (M, 3) points on the exact seam, consecutive points joined by
            chords (a closed seam's last point joins its first).
        closed: the seam comes back to its start.
        tolerance_m: how far the chords may be from the model's exact seam [m].
        length_m: the model's exact length of the seam [m].
        model: the model file and what was picked (``bracket.step, edges 3, 7``).
        corners: (position (3,) [m], turn [deg]) where the seam's edges meet at a corner.
    """

    reference_P: np.ndarray
    closed: bool
    tolerance_m: float
    length_m: float
    model: str
    corners: tuple = ()


def distances_to_reference(exact: ExactSeam, points_P: np.ndarray) -> np.ndarray:
    """(N,) distance [m] from each point to the reference polyline (nearest vertex's two
    chords: exact for points nearer the polyline than half its spacing)."""
    ref = exact.reference_P
    _, nearest = cKDTree(ref).query(points_P)
    best = np.full(len(points_P), np.inf)
    count = len(ref)
    for shift in (-1, 0):
        i = nearest + shift
        if exact.closed:
            a, b = ref[i % count], ref[(i + 1) % count]
            valid = np.ones(len(i), bool)
        else:
            valid = (i >= 0) & (i + 1 < count)
            i = np.clip(i, 0, count - 2)
            a, b = ref[i], ref[i + 1]
        ab = b - a
        t = np.clip(np.einsum("ij,ij->i", points_P - a, ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
        d = np.linalg.norm(points_P - (a + t[:, None] * ab), axis=1)
        best = np.where(valid, np.minimum(best, d), best)
    return best


def path_to_reference(exact: ExactSeam, path) -> tuple[float, float, float]:
    """Max and RMS distance [m] of the fitted arc-length path from the exact seam, and
    the largest angle [rad] between the path's tangent and the exact seam's (at the
    nearest reference vertex), on a COMPARE_SPACING_M grid over its whole length."""
    s = np.linspace(0.0, path.length, max(2, int(path.length / COMPARE_SPACING_M) + 1))
    r, t = path(s, 1)
    d = distances_to_reference(exact, r)
    return float(d.max()), float(np.sqrt(np.mean(d**2))), float(_tangent_error(exact, r, t).max())


def _tangent_error(exact: ExactSeam, points_P: np.ndarray, t_P: np.ndarray) -> np.ndarray:
    """(N,) angle [rad] between unit tangents t_P (N, 3) and the exact seam's at the
    reference vertex nearest each of points_P (N, 3) [m]: the central difference of its
    neighbours (a closed seam wraps; an open one's ends take the one-sided chord)."""
    ref = exact.reference_P
    count = len(ref)
    _, i = cKDTree(ref).query(points_P)
    if exact.closed:
        before, after = ref[(i - 1) % count], ref[(i + 1) % count]
    else:
        before, after = ref[np.maximum(i - 1, 0)], ref[np.minimum(i + 1, count - 1)]
    # The reference's tangent at vertex i: the central difference (second order).
    tangent = after - before
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    cos = np.abs(np.einsum("ij,ij->i", tangent, t_P))
    return np.arccos(np.clip(cos, -1.0, 1.0))
