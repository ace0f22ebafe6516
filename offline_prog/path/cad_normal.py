"""The surface-normal field of a seam from a CAD model, fitted until it holds the
model's normals within ``path.normal_tolerance_deg``.

CSV normals are fitted on the path's own knots and the fit is only measured. A model's
normals are exact, and where a fillet meets a flat face the normal's turn rate jumps
(0 on the face, 1/r on the fillet); the path's knots, chosen for the position
tolerance, are too far apart there. Here the knot spans whose points are off by more
than the tolerance are halved until none is (the points gather at edge ends, see
``cad.seam_samples``), so the field follows the model as closely as the user asked;
a tight tolerance turns the tool faster there, a loose one smooths it.
"""

from __future__ import annotations

import numpy as np

from offline_prog.path.arc_length import ArcLengthPath, compose_derivatives
from offline_prog.path.bspline_fit import fit_on_knots

MAX_REFINEMENTS = 16  # halvings of the worst spans before the fit is taken as it is


def _knots(breaks: np.ndarray, degree: int, *, closed: bool, period: float) -> np.ndarray:
    """Knot vector from distinct breakpoints (both ends included)."""
    if not closed:
        return np.concatenate([np.full(degree, breaks[0]), breaks, np.full(degree, breaks[-1])])
    tau = breaks[:-1]
    m = len(tau)
    return np.concatenate([tau[m - degree :] - period, tau, [period], tau[1 : degree + 1] + period])


def _angles(spline, u, unit, period, closed) -> np.ndarray:
    value = spline(np.mod(u, period) if closed else u)
    value /= np.linalg.norm(value, axis=1, keepdims=True)
    return np.arccos(np.clip(np.einsum("ij,ij->i", value, unit), -1.0, 1.0))


def model_normal(path: ArcLengthPath, normals_P: np.ndarray, tolerance_rad: float):
    """The normal field s ↦ [n, n', n''] of exact normals at the fit's points.

    Args:
        path: the arc-length path (its fit's parameters u_data and knots to start from).
        normals_P: (N, 3) unit normals into the surface at the fit's points, in P.
        tolerance_rad: largest angle from a given normal to the field.
    """
    fitted = path.fitted
    degree, period, closed, u = fitted.degree, fitted.period, fitted.closed, fitted.u_data
    breaks = fitted.breakpoints
    for _ in range(MAX_REFINEMENTS):
        knots = _knots(breaks, degree, closed=closed, period=period)
        spline = fit_on_knots(u, normals_P, knots, degree, closed=closed)
        off = _angles(spline, u, normals_P, period, closed) > tolerance_rad
        if not off.any():
            break
        spans = np.unique(np.clip(np.searchsorted(breaks, u[off], side="right") - 1, 0, None))
        spans = spans[spans < len(breaks) - 1]
        # the span of each bad point and its neighbours: the error spreads one span
        spans = np.unique(
            np.clip(np.concatenate([spans - 1, spans, spans + 1]), 0, len(breaks) - 2)
        )
        middles = (breaks[spans] + breaks[spans + 1]) / 2
        breaks = np.unique(np.concatenate([breaks, middles]))

    def field(s: np.ndarray) -> list[np.ndarray]:
        v = path.parameter(s, order=2)
        uu = np.mod(v[0], period) if closed else v[0]
        return compose_derivatives([spline(uu, nu=k) for k in range(3)], v)

    return field
