"""UR-form parameters (UR's Denavit-Hartenberg lengths, ``kinematics_ur``) of a chain.

A UR-type arm has axis 1 along z of base_link, axes 2, 3, 4 parallel and perpendicular
to it, axis 5 perpendicular to axis 4 and axis 6 perpendicular to axis 5; with UR's
zero pose and joint directions (``kinematics_ur`` has no offsets or sign corrections)
its flange pose is a function of six lengths. The lengths are read off the joint axes
at q = 0 as a first guess and then fitted to the chain's own FK by least squares on
seeded configurations; the fit is accepted only when it reproduces the chain exactly
(QUICK_CHECK_TOL_M), and :mod:`.verify` checks it again on 1,000 configurations.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from offline_prog.robot import kinematics_ur
from offline_prog.robot.kinematics_ur import UrParameters
from offline_prog.robot_import.chain import Chain, chain_forward
from offline_prog.robot_import.derive import (
    QUICK_CHECK_TOL_M,
    STRUCTURE_TOL,
    _clean,
    axes_at_zero,
)

FIT_SAMPLES = 20


def _line_distance(p_a, p_b, u) -> float:
    """Distance between two lines parallel to unit u through p_a and p_b [m]."""
    d = p_b - p_a
    return float(np.linalg.norm(d - (d @ u) * u))


def derive_ur(chain: Chain) -> UrParameters | None:
    """The UR parameter record of ``chain``, or None when it is not a UR-type arm."""
    u, p, X_BE = axes_at_zero(chain)
    z, tol = np.array([0.0, 0.0, 1.0]), STRUCTURE_TOL
    parallel = all(abs(abs(u[1] @ u[k]) - 1) < tol for k in (2, 3))
    if abs(abs(u[0] @ z) - 1) > tol or not parallel or abs(u[0] @ u[1]) > tol:
        return None
    if abs(u[3] @ u[4]) > tol or abs(u[4] @ u[5]) > tol:
        return None
    rng = np.random.default_rng(0)
    lower = np.array([j.lower for j in chain.revolute])
    upper = np.array([j.upper for j in chain.revolute])
    q = rng.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi), size=(FIT_SAMPLES, 6))
    X_chain = np.array([chain_forward(chain, row)[-1].GetAsMatrix4() for row in q])

    def residual(x):
        return (kinematics_ur.forward(UrParameters(*x), q) - X_chain)[:, :3, :].ravel()

    l2, l3 = _line_distance(p[1], p[2], u[1]), _line_distance(p[2], p[3], u[1])
    d4 = abs((p[3] - p[1]) @ u[1])
    d5 = abs((p[4] - p[3]) @ u[3])
    d6 = abs((X_BE[:3, 3] - p[5]) @ u[5])
    best = None
    for s2 in (-1, 1):
        for s3 in (-1, 1):
            x0 = [p[1][2], s2 * l2, s3 * l3, d4, d5, d6]
            fit = least_squares(residual, x0, xtol=1e-15, ftol=1e-15, gtol=1e-15)
            if best is None or fit.cost < best.cost:
                best = fit
    x = np.array([_clean(v) for v in best.x])
    return UrParameters(*x) if np.abs(residual(x)).max() <= QUICK_CHECK_TOL_M else None
