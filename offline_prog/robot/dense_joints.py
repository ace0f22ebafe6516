"""The plan's joints on its fine grid of s, computed once at plan time.

``plan.npz`` keeps the process frames X_PF of the continuous path on a 0.1 mm grid of s
(``export.densify.dense_grid``); the program writers insert grid points between the
samples where a LIN chord would leave the path. The joints of those points are planned
here, with the robot's inverse kinematics, so that the writers only read them (issue 24:
writers do not run IK).

Per grid point: t by monotone interpolation of t(s), q Hermite-interpolated from the
samples' (q, qd), then replaced by the IK solution on the configuration branch of the
sample before it, at the 2π turn nearest the Hermite q (so configuration bits are
exact); where no such solution exists (or the robot has no closed form) the Hermite q
stays.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicHermiteSpline, PchipInterpolator

from offline_prog.robot.model import RobotModel


def dense_joints(
    robot: RobotModel,
    sigma: np.ndarray,
    t: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    X_BE: np.ndarray,
    sigma_dense: np.ndarray,
    X_BE_dense: np.ndarray,
) -> np.ndarray:
    """(M, 6) joints [rad] at the grid points.

    Args:
        robot: the plan's robot.
        sigma: (N,) the samples' s [m]; t: (N,) their times [s].
        q, qd: (N, 6) the samples' joints [rad] and joint speeds [rad/s].
        X_BE: (N, 4, 4) the samples' flange poses in the base B [m].
        sigma_dense: (M,) the grid's s [m]; X_BE_dense: (M, 4, 4) its flange poses in B.
    """
    if len(sigma_dense) == 0:
        return np.empty((0, 6))
    rising = np.concatenate([[True], np.diff(sigma) > 0])
    t_dense = PchipInterpolator(sigma[rising], t[rising])(sigma_dense)
    q_dense = CubicHermiteSpline(t, q, qd, axis=0)(t_dense)
    if robot.params is None:
        return q_dense
    left = np.clip(np.searchsorted(sigma, sigma_dense, side="right") - 1, 0, len(sigma) - 1)
    branch = _nearest(robot.inverse(X_BE), q)[1][left]  # (M,) each sample's branch
    solutions = np.empty((len(sigma_dense), 6))  # (M, 6): each point's branch alone
    for b in np.unique(branch):
        rows = branch == b
        solutions[rows] = robot.inverse_branch(X_BE_dense[rows], int(b))
    wrapped = q_dense + (solutions - q_dense + np.pi) % (2 * np.pi) - np.pi
    ok = np.isfinite(wrapped).all(axis=1)
    q_dense[ok] = wrapped[ok]
    return q_dense


def _nearest(solutions: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per row: the gap [rad] and index of the IK solution (K, 8, 6) nearest q (K, 6),
    each joint taken at its 2π turn nearest q."""
    wrapped = q[:, None] + (solutions - q[:, None] + np.pi) % (2 * np.pi) - np.pi
    gap = np.nan_to_num(np.abs(wrapped - q[:, None]).max(axis=2), nan=np.inf)
    return gap.min(axis=1), gap.argmin(axis=1)
