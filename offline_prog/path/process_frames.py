"""Process orientation frames F along the path (paper §3.1).

R_PF(s) = [t n b] with t = dr/ds (unit because s is arc length, paper eq. 4),
n the surface normal pointing into the surface the tool presses on, made
orthogonal to t (Gram–Schmidt), and b = t × n. The first and second s-derivatives
of R_PF are propagated analytically for the flange velocity and acceleration.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.interpolate import BSpline

from offline_prog.constants import MIN_NORMAL_TANGENT_ANGLE_RAD
from offline_prog.errors import TravellingError
from offline_prog.path.arc_length import ArcLengthPath, compose_derivatives
from offline_prog.path.bspline_fit import fit_on_knots

NormalField = Callable[[np.ndarray], list[np.ndarray]]
"""s (N,) ↦ [n_raw, dn_raw/ds, d²n_raw/ds²], each (N, 3) in P (not yet unit/orthogonal)."""


class NormalTangentError(TravellingError, ValueError):
    """The surface normal is (anti)parallel to the tangent; the frame is undefined."""

    def __init__(self, s: float, angle_rad: float):
        self.s = s
        super().__init__(
            f"surface normal within {np.rad2deg(angle_rad):.2f}° of the path tangent at "
            f"s = {s:.4f} m (need ≥ {np.rad2deg(MIN_NORMAL_TANGENT_ANGLE_RAD):.0f}°)"
        )


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)[:, None]


def normalize_with_derivatives(m, m1, m2):
    """v = m/|m| and its first two derivatives, all (N, 3), from m, m', m''."""
    rho = np.linalg.norm(m, axis=1)[:, None]
    v = m / rho
    rho1 = _dot(v, m1)
    v1 = (m1 - rho1 * v) / rho
    rho2 = (_dot(m1, m1) + _dot(m, m2) - rho1**2) / rho
    v2 = (m2 - rho2 * v - 2.0 * rho1 * v1) / rho
    return v, v1, v2


def constant_normal(n_P: np.ndarray) -> NormalField:
    """A fixed surface normal n in P (a flat part)."""
    n_P = np.asarray(n_P, dtype=float)

    def field(s: np.ndarray) -> list[np.ndarray]:
        value = np.broadcast_to(n_P, (len(s), 3)).copy()
        return [value, np.zeros_like(value), np.zeros_like(value)]

    return field


def spline_normal(path: ArcLengthPath, normals_P: np.ndarray) -> NormalField:
    """Normals given at the data points, fitted on the path's own knots.

    Args:
        path: the arc-length processing path (its spline's u_data and knots are reused).
        normals_P: (N, 3) normals at the given points, in P, pointing into the surface.
    """
    fitted = path.fitted
    unit = normals_P / np.linalg.norm(normals_P, axis=1, keepdims=True)
    spline: BSpline = fit_on_knots(
        fitted.u_data, unit, fitted.spline.t, fitted.degree, closed=fitted.closed
    )

    def field(s: np.ndarray) -> list[np.ndarray]:
        u = path.parameter(s, order=2)
        uu = np.mod(u[0], fitted.period) if fitted.closed else u[0]
        return compose_derivatives([spline(uu, nu=k) for k in range(3)], u)

    return field


def normal_fit_angles(path: ArcLengthPath, normals_P: np.ndarray, field: NormalField):
    """(N,) angle [rad] between each given normal and the fitted field at that point.

    The point's place on the path is the fit's own parameter of it (u_data, the
    parameter spline_normal fitted at), mapped to arc length.
    """
    given = normals_P / np.linalg.norm(normals_P, axis=1, keepdims=True)
    fitted = field(path.map.s_of_u(path.fitted.u_data))[0]
    sin = np.linalg.norm(np.cross(given, fitted), axis=1)
    return np.arctan2(sin, np.einsum("ij,ij->i", given, fitted))


def mesh_normals(mesh, points_P: np.ndarray) -> np.ndarray:
    """(N, 3) normals into the surface of a trimesh part at its closest points.

    The face normal of the closest triangle is flipped (trimesh faces point out of
    the solid; the process normal points into the surface the tool presses on).
    """
    import trimesh  # heavy import, only for mesh-based normals

    _, _, face = trimesh.proximity.closest_point(mesh, points_P)
    return -np.asarray(mesh.face_normals)[face]


def process_frames(path: ArcLengthPath, normal: NormalField, s: np.ndarray):
    """R_PF(s) and its first two s-derivatives (paper §3.1).

    Args:
        path: the arc-length processing path in P.
        normal: the surface normal field.
        s: (N,) arc length [m].

    Returns:
        (R, R1, R2): each (N, 3, 3), R = R_PF = [t n b] columns, R1 = dR_PF/ds [1/m],
        R2 = d²R_PF/ds² [1/m²].

    Raises:
        NormalTangentError: where n is within MIN_NORMAL_TANGENT_ANGLE_RAD of ±t.
    """
    _, t, t1, t2 = path(s, order=3)
    n, n1, n2 = normal(s)
    n_unit = n / np.linalg.norm(n, axis=1, keepdims=True)
    sin_angle = np.linalg.norm(np.cross(t, n_unit), axis=1)
    worst = int(np.argmin(sin_angle))
    if sin_angle[worst] < np.sin(MIN_NORMAL_TANGENT_ANGLE_RAD):
        raise NormalTangentError(float(s[worst]), float(np.arcsin(sin_angle[worst])))
    # Gram–Schmidt: m = n − (n·t) t, with its derivatives.
    k, k1 = _dot(n, t), _dot(n1, t) + _dot(n, t1)
    k2 = _dot(n2, t) + 2.0 * _dot(n1, t1) + _dot(n, t2)
    m = n - k * t
    m1 = n1 - k1 * t - k * t1
    m2 = n2 - k2 * t - 2.0 * k1 * t1 - k * t2
    nn, nn1, nn2 = normalize_with_derivatives(m, m1, m2)
    b = np.cross(t, nn)
    b1 = np.cross(t1, nn) + np.cross(t, nn1)
    b2 = np.cross(t2, nn) + 2.0 * np.cross(t1, nn1) + np.cross(t, nn2)
    return (
        np.stack([t, nn, b], axis=2),
        np.stack([t1, nn1, b1], axis=2),
        np.stack([t2, nn2, b2], axis=2),
    )
