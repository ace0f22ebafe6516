"""The exact response of a first-order lag to a piecewise-linear input.

A dispenser (or any first-order element) with time constant τ obeys
``τ · y'(t) + y(t) = u(t)``. With ``u`` linear between samples (slope m on
[t_k, t_k + h]), the solution is exact in closed form (first-order hold):

    y(t_k + h) = u_{k+1} − m·τ + (y_k − u_k + m·τ) · e^{−h/τ}

so the recursion y_{k+1} = a_k · y_k + g_k with a_k = e^{−h_k/τ} has no
discretisation error at the samples, whatever the (non-uniform) steps.
"""

from __future__ import annotations

import numpy as np

MAX_DECAY = 600.0  # Σ h/τ per block: e^{-600} is far from float64's underflow


def first_order_response(t: np.ndarray, u: np.ndarray, tau_s: float, y0: float | None = None):
    """y(t_k) of ``τ y' + y = u`` with u linear between the samples.

    Args:
        t: (N,) increasing sample times [s].
        u: (N,) the input at those times (any unit).
        tau_s: the time constant τ [s]; 0 gives y = u.
        y0: y at t[0] (default u[0], the element at rest).

    Returns:
        (N,) y at the samples, in u's unit.

    The linear recursion is solved in closed form, vectorised, by blocks whose total
    decay stays representable: y_n = P_n · (y_0 + Σ_{k<n} g_k / P_{k+1}), P = Π a.
    """
    t, u = np.asarray(t, float), np.asarray(u, float)
    if tau_s <= 0 or len(t) < 2:
        return u.copy()
    h = np.diff(t)
    a = np.exp(-h / tau_s)
    slope_tau = np.divide(np.diff(u) * tau_s, h, out=np.zeros_like(h), where=h > 0)
    g = u[1:] - slope_tau - (u[:-1] - slope_tau) * a  # y_{k+1} = a_k y_k + g_k
    y = np.empty_like(u)
    y[0] = u[0] if y0 is None else y0
    decay = np.cumsum(h / tau_s)
    start = 0
    while start < len(h):
        stop = int(np.searchsorted(decay, decay[start] - h[start] / tau_s + MAX_DECAY))
        stop = max(stop, start + 1)
        log_p = -(decay[start:stop] - (decay[start] - h[start] / tau_s))  # log P_{k+1}
        p = np.exp(log_p)
        y[start + 1 : stop + 1] = p * (y[start] + np.cumsum(g[start:stop] / p))
        start = stop
    return y
