"""True arc-length parameterization of a curve (paper §4).

Paper eq. 2 only approximates arc length by the data polygon; the time law needs
σ to be the real arc length so that σ̇ is the speed at the TCP. Here
s(u) = ∫ g(v) dv with g = |dr/du| is integrated by Gauss–Legendre quadrature on a
fine grid between the spline's knots, and u(s) is found by Newton's method to
machine precision, with analytic derivatives u', u'', u''' from g and its
u-derivatives (so no finite differences anywhere downstream).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
from scipy.interpolate import CubicHermiteSpline

from offline_prog.constants import ARC_LENGTH_TOLERANCE_M

_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)

SpeedFunction = Callable[..., tuple]
"""(u (N,), order) ↦ (g, dg/du, d²g/du²)[: order + 1] with g = |dr/du| > 0."""


class ArcLengthMap:
    """s(u) = ∫_{u0}^{u} g(v) dv and its inverse u(s), with derivatives.

    Args:
        speed: the SpeedFunction g of the curve.
        breakpoints: (K,) increasing parameters where g may lose smoothness (knots);
            the domain is [breakpoints[0], breakpoints[-1]].
        periodic: s wraps modulo the total length.
        subdivisions: quadrature cells per breakpoint interval.
    """

    def __init__(
        self,
        speed: SpeedFunction,
        breakpoints: np.ndarray,
        *,
        periodic: bool,
        subdivisions: int = 8,
    ):
        self.speed = speed
        self.periodic = periodic
        fractions = np.arange(subdivisions) / subdivisions
        starts, widths = breakpoints[:-1], np.diff(breakpoints)
        grid = (starts[:, None] + widths[:, None] * fractions).ravel()
        self._grid = np.concatenate([grid, breakpoints[-1:]])
        cell_lengths = self._integral(self._grid[:-1], self._grid[1:])
        self._cumulative = np.concatenate([[0.0], np.cumsum(cell_lengths)])
        self.length = float(self._cumulative[-1])
        g_grid = speed(self._grid, 0)[0]
        self.min_speed = float(g_grid.min())
        # Initial guess for Newton: cubic Hermite u(s) with the exact slopes du/ds = 1/g,
        # so that one or two Newton steps reach machine precision.
        self._guess = None
        if self.min_speed > 0.0:
            self._guess = CubicHermiteSpline(self._cumulative, self._grid, 1.0 / g_grid)

    @property
    def u_min(self) -> float:
        return float(self._grid[0])

    @property
    def u_max(self) -> float:
        return float(self._grid[-1])

    def _integral(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """(N,) ∫_a^b g by 8-point Gauss–Legendre, vectorized over intervals."""
        half = 0.5 * (b - a)
        nodes = (0.5 * (a + b))[:, None] + half[:, None] * _GL_X
        g = self.speed(nodes.ravel(), 0)[0].reshape(nodes.shape)
        return half * (g @ _GL_W)

    def s_of_u(self, u: np.ndarray) -> np.ndarray:
        """(N,) arc length from the curve's start to parameter u [m]."""
        u = np.clip(np.asarray(u, dtype=float), self.u_min, self.u_max)
        cell = np.clip(np.searchsorted(self._grid, u, side="right") - 1, 0, len(self._grid) - 2)
        return self._cumulative[cell] + self._integral(self._grid[cell], u)

    def wrap(self, s: np.ndarray) -> np.ndarray:
        """Arc length reduced to [0, length] (modulo the length when periodic)."""
        s = np.asarray(s, dtype=float)
        if self.periodic:
            return np.mod(s, self.length)
        return np.clip(s, 0.0, self.length)

    def u_of_s(self, s: np.ndarray, order: int = 3) -> list[np.ndarray]:
        """Parameter u(s) and its s-derivatives.

        Args:
            s: (N,) arc length [m] (wrapped when periodic, clipped otherwise).
            order: highest derivative wanted, 0..3 (3 needs d²g/du²).

        Returns:
            [u, du/ds, d²u/ds², d³u/ds³][: order + 1], each (N,).
        """
        s = self.wrap(s)
        if self._guess is None:
            u = np.interp(s, self._cumulative, self._grid)
        else:
            u = np.clip(self._guess(s), self.u_min, self.u_max)
        for _ in range(8):
            error = self.s_of_u(u) - s
            if np.max(np.abs(error), initial=0.0) < ARC_LENGTH_TOLERANCE_M:
                break
            u = np.clip(u - error / self.speed(u, 0)[0], self.u_min, self.u_max)
        g_derivatives = self.speed(u, min(order, 3) - 1) if order > 0 else ()
        out = [u]
        if order >= 1:
            g = g_derivatives[0]
            out.append(1.0 / g)
        if order >= 2:
            out.append(-g_derivatives[1] / g**3)
        if order >= 3:
            g1, g2 = g_derivatives[1], g_derivatives[2]
            out.append(-g2 / g**4 + 3.0 * g1**2 / g**5)
        return out


def compose_derivatives(c: list[np.ndarray], u: list[np.ndarray]) -> list[np.ndarray]:
    """Faà di Bruno up to order 3: derivatives of r(s) = c(u(s)).

    Args:
        c: [c, dc/du, d²c/du², d³c/du³][:k], each (N, d).
        u: [u, u', u'', u'''][:k], each (N,) (u[0] unused).

    Returns:
        [r, r', r'', r'''][:k] with ' = d/ds.
    """
    out = [c[0]]
    if len(c) > 1:
        out.append(c[1] * u[1][:, None])
    if len(c) > 2:
        out.append(c[2] * (u[1] ** 2)[:, None] + c[1] * u[2][:, None])
    if len(c) > 3:
        out.append(
            c[3] * (u[1] ** 3)[:, None] + 3.0 * c[2] * (u[1] * u[2])[:, None] + c[1] * u[3][:, None]
        )
    return out


def curve_speed(derivatives: Callable[[np.ndarray, int], np.ndarray]) -> SpeedFunction:
    """SpeedFunction g = |c'|, g' = c'·c''/g, g'' = (|c''|² + c'·c''' − g'²)/g."""
    return CurveSpeed(derivatives)


@dataclasses.dataclass(frozen=True)
class CurveSpeed:
    """:func:`curve_speed`'s SpeedFunction, an object rather than a closure so that a
    path can be pickled (``offline_prog.forked``)."""

    derivatives: Callable[[np.ndarray, int], np.ndarray]  # (u (N,), k) ↦ c⁽ᵏ⁾(u) (N, 3)

    def __call__(self, u: np.ndarray, order: int = 2):
        c1 = self.derivatives(u, 1)
        g = np.linalg.norm(c1, axis=1)
        if order == 0:
            return (g,)
        c2 = self.derivatives(u, 2)
        g1 = np.einsum("ij,ij->i", c1, c2) / g
        if order == 1:
            return g, g1
        c3 = self.derivatives(u, 3)
        g2 = (np.einsum("ij,ij->i", c2, c2) + np.einsum("ij,ij->i", c1, c3) - g1**2) / g
        return g, g1, g2


class ArcLengthPath:
    """The processing path r(s) = _P r_PF in P, parameterized by true arc length s.

    Call ``path(s, order)`` for [r, dr/ds, d²r/ds², d³r/ds³][: order + 1], each
    (N, 3) in P [m, 1, 1/m, 1/m²]; |dr/ds| = 1 by construction.
    """

    def __init__(self, fitted):
        self.fitted = fitted
        self.closed = fitted.closed
        self.map = ArcLengthMap(curve_speed(fitted), fitted.breakpoints, periodic=fitted.closed)
        self.length = self.map.length
        self._last: tuple[np.ndarray, list[np.ndarray]] | None = None
        # (u, [c, dc/du, ...]): the spline's last evaluation, kept with the u it was at
        # (the flange path asks for order 2, then the process frames for order 3).
        self._spline: tuple[np.ndarray, list[np.ndarray]] | None = None

    def parameter(self, s: np.ndarray, order: int = 3) -> list[np.ndarray]:
        """[u, u', u'', u'''][: order + 1] of the fitted spline at arc length s.

        The flange path, the process frames and the normal field ask for the same
        s in turn; the last answer is kept so that the Newton solve runs once.
        """
        s = np.asarray(s, dtype=float)
        if self._last is None or not np.array_equal(self._last[0], s):
            self._last = (s.copy(), self.map.u_of_s(s, 3))
        return self._last[1][: order + 1]

    def __call__(self, s: np.ndarray, order: int = 3) -> list[np.ndarray]:
        u = self.parameter(s, max(order, 1))
        kept = self._spline  # one read: threads may replace it
        c = kept[1] if kept is not None and kept[0] is u[0] else []
        if len(c) <= order:
            c = c + [self.fitted(u[0], nu) for nu in range(len(c), order + 1)]
            self._spline = (u[0], c)
        # r itself is c's first array: a copy, so no caller changes the kept one.
        return compose_derivatives([c[0].copy(), *c[1 : order + 1]], u)
