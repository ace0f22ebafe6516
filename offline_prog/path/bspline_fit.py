"""B-spline approximation of the processing path (paper §2).

Given points r_j on the part (in P), fit a B-spline curve ``_P r_PF(u)`` of degree
p ≥ 5 by weighted least squares (paper eq. 3) over the chord-length parameter u
(paper eq. 2, with a = 0 and b = L so that u is the data-polygon length). Closed
contours get a periodic spline: position and all derivatives up to p−1 continuous
across the seam. The number of control points is chosen as the smallest that keeps
every given point within a distance tolerance of the curve.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.interpolate import BSpline, make_lsq_spline

from offline_prog.constants import (
    DEFAULT_FIT_TOLERANCE_M,
    DEFAULT_SPLINE_DEGREE,
    MIN_SPLINE_DEGREE,
)
from offline_prog.path.fit_hint import hint_key, keep_hint, read_hint


@dataclasses.dataclass(frozen=True)
class FittedSpline:
    """A fitted curve u ↦ r(u) on [0, period], with its fit statistics.

    Attributes:
        spline: scipy BSpline of degree p, values (d,) per parameter; periodic
            splines extrapolate periodically.
        closed: True for a periodic (closed) curve.
        period: parameter domain length b − a = data-polygon length L [m].
        u_data: (N,) chord-length parameter of each given point (paper eq. 2).
        max_error_m, rms_error_m: distance from the given points to the curve [m].
    """

    spline: BSpline
    closed: bool
    period: float
    u_data: np.ndarray
    max_error_m: float
    rms_error_m: float

    @property
    def degree(self) -> int:
        return int(self.spline.k)

    @property
    def n_control_points(self) -> int:
        """Distinct control points d_i (periodic copies counted once)."""
        n = len(self.spline.c)
        return n - self.degree if self.closed else n

    @property
    def breakpoints(self) -> np.ndarray:
        """(K,) distinct knots within [0, period], both ends included."""
        t = self.spline.t
        inside = t[(t >= 0.0) & (t <= self.period)]
        return np.unique(np.concatenate([[0.0], inside, [self.period]]))

    def __call__(self, u: np.ndarray, nu: int = 0) -> np.ndarray:
        """(N, d) value or nu-th derivative d^nu r / du^nu at parameters u (N,)."""
        u = np.asarray(u, dtype=float)
        if self.closed:
            u = np.mod(u, self.period)
        return self.spline(u, nu=nu)


def chord_length_parameter(points: np.ndarray, *, closed: bool) -> tuple[np.ndarray, float]:
    """Paper eq. 2 with a = 0, b = L: u_k is the polygon length up to point k.

    Args:
        points: (N, d) given points.
        closed: include the closing chord from the last point back to the first.

    Returns:
        u: (N,) parameters, u_0 = 0; period: L, the polygon length [m] (closing
        chord included when closed).
    """
    chords = np.linalg.norm(np.diff(points, axis=0), axis=1)
    u = np.concatenate([[0.0], np.cumsum(chords)])
    period = u[-1] + (np.linalg.norm(points[0] - points[-1]) if closed else 0.0)
    return u, float(period)


def open_knots(u: np.ndarray, n_control: int, degree: int) -> np.ndarray:
    """Clamped knot vector with interior knots by averaging (Piegl & Tiller eq. 9.69).

    Every knot span then holds at least one parameter, so the least-squares system
    satisfies the Schoenberg–Whitney condition.
    """
    n_points = len(u)
    d = n_points / (n_control - degree)
    j = np.arange(1, n_control - degree)
    i = np.floor(j * d).astype(int)
    alpha = j * d - i
    interior = (1.0 - alpha) * u[i - 1] + alpha * u[i]
    return np.concatenate([np.full(degree + 1, u[0]), interior, np.full(degree + 1, u[-1])])


def periodic_knots(u: np.ndarray, period: float, n_control: int, degree: int) -> np.ndarray:
    """Knots of a periodic spline with n_control distinct coefficients.

    The n_control breakpoints τ_0 = 0 < … < τ_{m−1} < period split the data into
    spans holding about N/m parameters each; p knots are wrapped on each side.
    """
    u_ext = np.concatenate([u, [period]])
    tau = np.interp(np.arange(n_control) * len(u) / n_control, np.arange(len(u_ext)), u_ext)
    tau = np.concatenate([tau, [period]])
    left = tau[n_control - degree : n_control] - period
    right = tau[1 : degree + 1] + period
    return np.concatenate([left, tau, right])


def _fit_periodic(u, points, weights, knots, degree) -> BSpline:
    """Weighted least squares (paper eq. 3) with coefficient c_{i+m} = c_i folded in."""
    n_coef = len(knots) - degree - 1
    m = n_coef - degree
    A = BSpline.design_matrix(u, knots, degree).toarray()
    A[:, :degree] += A[:, m:]
    A = A[:, :m]
    sw = np.sqrt(weights)[:, None]
    c, *_ = np.linalg.lstsq(A * sw, points * sw, rcond=None)
    return BSpline(knots, np.vstack([c, c[:degree]]), degree, extrapolate="periodic")


def fit_on_knots(u, values, knots, degree, *, closed, weights=None) -> BSpline:
    """Least-squares spline of ``values`` (N, d) over ``u`` on a given knot vector.

    Used for the path itself and for quantities that ride on it (surface normals).
    """
    weights = np.ones(len(u)) if weights is None else np.asarray(weights, dtype=float)
    if closed:
        return _fit_periodic(u, values, weights, knots, degree)
    return make_lsq_spline(u, values, knots, k=degree, w=weights, axis=0)


def point_curve_distances(curve, points: np.ndarray, u0: np.ndarray, lo: float, hi: float):
    """Distance from each point to the curve by Newton's foot-point projection.

    Args:
        curve: callable (u, nu) -> (N, d).
        points: (N, d); u0: (N,) start parameters (the fit parameters).
        lo, hi: parameter bounds for open curves (ignored effects when closed).

    Returns:
        (N,) distances [m]; never larger than the residual |r(u0) − point|.
    """
    diff = curve(u0, 0) - points
    best = np.linalg.norm(diff, axis=1)
    u = u0.copy()
    for _ in range(6):
        d1, d2 = curve(u, 1), curve(u, 2)
        grad = np.einsum("ij,ij->i", diff, d1)
        hess = np.einsum("ij,ij->i", d1, d1) + np.einsum("ij,ij->i", diff, d2)
        step = np.where(hess > 0, grad / np.where(hess > 0, hess, 1.0), 0.0)
        u = np.clip(u - step, lo, hi)
        diff = curve(u, 0) - points  # the residual at the new u: the next step's too
        best = np.minimum(best, np.linalg.norm(diff, axis=1))
    return best


def fit_bspline(
    points: np.ndarray,
    *,
    closed: bool,
    degree: int = DEFAULT_SPLINE_DEGREE,
    tolerance_m: float = DEFAULT_FIT_TOLERANCE_M,
    n_control_points: int | None = None,
    weights: np.ndarray | None = None,
) -> FittedSpline:
    """Fit a B-spline through the processing-path points (paper §2, eqs. 1–3).

    Args:
        points: (N, 3) points r_j on the part, in P [m]; for closed contours the
            first point must not be repeated at the end.
        closed: fit a periodic spline (C^{p−1} across the seam).
        degree: p ≥ 5.
        tolerance_m: max distance from a point to the curve when the number of
            control points is chosen automatically [m].
        n_control_points: fix the number of distinct control points instead.
        weights: (N,) positive weights w_j of eq. 3 (default all 1).

    Returns:
        The FittedSpline with its max and RMS distance error.

    Raises:
        ValueError: too few points for the degree, or the tolerance cannot be met.
    """
    points = np.asarray(points, dtype=float)
    if degree < MIN_SPLINE_DEGREE:
        raise ValueError(f"spline degree {degree} < {MIN_SPLINE_DEGREE} (paper §2 needs p ≥ 5)")
    n_points = len(points)
    if n_points < degree + 1:
        raise ValueError(f"{n_points} points; a degree-{degree} spline needs at least {degree + 1}")
    u, period = chord_length_parameter(points, closed=closed)
    if period <= 0.0:
        raise ValueError("all points coincide; the path has zero length")
    m_min, m_max = degree + 1, n_points

    def fit(m: int) -> FittedSpline:
        if closed:
            knots = periodic_knots(u, period, m, degree)
        else:
            knots = open_knots(u, m, degree)
        spline = fit_on_knots(u, points, knots, degree, closed=closed, weights=weights)
        result = FittedSpline(spline, closed, period, u, 0.0, 0.0)
        lo, hi = (-np.inf, np.inf) if closed else (0.0, period)
        dist = point_curve_distances(result, points, u, lo, hi)
        return dataclasses.replace(
            result, max_error_m=float(dist.max()), rms_error_m=float(np.sqrt(np.mean(dist**2)))
        )

    if n_control_points is not None:
        if not m_min <= n_control_points <= m_max:
            raise ValueError(
                f"n_control_points {n_control_points} outside [{m_min}, {m_max}] "
                f"for {n_points} points and degree {degree}"
            )
        return fit(n_control_points)

    # The count this search found on an earlier run (path.fit_hint): one fit, the same
    # numbers as the search's, if it holds the tolerance.
    key = hint_key(
        points,
        weights,
        closed=closed,
        degree=degree,
        tolerance_m=tolerance_m,
        source_file=__file__,
    )
    kept = read_hint(key)
    if kept is not None and m_min <= kept <= m_max:
        trial = fit(kept)
        if trial.max_error_m <= tolerance_m:
            return trial

    # Smallest m meeting the tolerance: double until it passes, then bisect.
    lo_m, hi_m, best = m_min - 1, None, None
    m = m_min
    while True:
        trial = fit(m)
        if trial.max_error_m <= tolerance_m:
            hi_m, best = m, trial
            break
        lo_m = m
        if m == m_max:
            extent = float(np.ptp(points, axis=0).max())
            if not np.isfinite(trial.max_error_m) or trial.max_error_m > extent:
                # An error beyond the points' own size: the fit diverged, not a tolerance.
                raise ValueError(
                    f"the points do not trace a curve a spline can follow (the fit "
                    f"diverges with {m_max} control points); check for repeated, "
                    "back-and-forth or scattered points"
                )
            raise ValueError(
                f"cannot fit within {tolerance_m * 1e3:.3g} mm even with {m_max} control "
                f"points (best {trial.max_error_m * 1e3:.3g} mm); raise the tolerance "
                "or give more points"
            )
        m = min(2 * m, m_max)
    while hi_m - lo_m > 1:
        mid = (lo_m + hi_m) // 2
        trial = fit(mid)
        if trial.max_error_m <= tolerance_m:
            hi_m, best = mid, trial
        else:
            lo_m = mid
    keep_hint(key, hi_m)
    return best
