"""The continuous plan between its samples, for the Cartesian point selection.

The plan is sampled in time (``motion.sample_rate_hz``): at 1 Hz two samples can lie
100 mm apart on a curve, and a LIN segment through samples can leave the path between
them by millimetres while every sample fits. The plan therefore also holds the tool
frames X_PT (the process frames) of the continuous path on a fine grid of s
(``dense_grid``). :func:`densify` inserts the grid points into the sample intervals
where the path leaves the interval's own chord by more than ``DENSIFY_SHARE`` of a
tolerance; the others
differ from their chord by at most the returned residual. A LIN segment within d of the
points it passes is then within d + residual of the continuous path (the distance to a
segment is convex), so the writers select with the tolerance less the residual and
state d + residual.

Inserted rows: s and X_PT from the grid, X_BE = X_BT · X_PT⁻¹ · X_EP⁻¹, t by monotone
interpolation of t(s), q the plan's joints at the grid point (``q_dense``, planned once
by ``robot.dense_joints``: the writers run no inverse kinematics), speeds interpolated.
A plan made before plans stored q_dense gets them from the robot's IK here.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.interpolate import CubicHermiteSpline, PchipInterpolator
from scipy.spatial.transform import Rotation

from offline_prog.export.deviation import rotation_angles, rotation_matrices
from offline_prog.export.program import ProgramData

DENSE_SPACING_M = 1e-4  # grid step along s; its own chord error is ~h²/(8r) = 1.3 µm at r = 1 mm
MAX_DENSE_POINTS = 200_000
DENSIFY_SHARE = 0.1  # refine an interval whose chord misses the path by 10 % of a tolerance


def dense_grid(length_m: float) -> np.ndarray:
    """(M,) s values [m] from 0 to length_m, DENSE_SPACING_M apart (at most MAX_DENSE_POINTS)."""
    n = int(min(max(np.ceil(length_m / DENSE_SPACING_M) + 1, 2), MAX_DENSE_POINTS))
    return np.linspace(0.0, length_m, n)


@dataclasses.dataclass(frozen=True)
class Densified:
    """The plan with grid points inserted, and the residual deviation [m, rad] of the
    continuous path from what the points show (None: the plan has no grid)."""

    data: ProgramData
    residual_chord_m: float | None
    residual_angle_rad: float | None
    n_inserted: int

    def selection_tolerances(self, chord_tol_m: float, angle_tol_rad: float):
        """The tolerances [m, rad] to select points with, so that the selection's
        deviation plus the residual stays within the given ones."""
        return (
            max(chord_tol_m - (self.residual_chord_m or 0.0), 0.5 * chord_tol_m),
            max(angle_tol_rad - (self.residual_angle_rad or 0.0), 0.5 * angle_tol_rad),
        )

    def bound(self, chord_m: float, angle_rad: float) -> tuple[float, float]:
        """A measured deviation [m, rad] plus the residual: a bound on the true one."""
        return chord_m + (self.residual_chord_m or 0.0), angle_rad + (
            self.residual_angle_rad or 0.0
        )

    @property
    def basis(self) -> str:
        """What the stated deviation is measured against, for the program header."""
        if self.residual_chord_m is None:
            return "measured at the plan samples only (old plan.npz: re-plan for a bound)"
        return "bound against the continuous plan"


def _chord_deviation(p, R, a, b, x, R_x) -> tuple[np.ndarray, np.ndarray]:
    """(K,) distance [m] of points x from segments a→b, and (K,) angle [rad] of R_x from
    the slerp of R[a]→R[b] at the same share (positions (n, 3), rotations (n, 3, 3))."""
    chord = p[b] - p[a]
    length2 = np.einsum("kc,kc->k", chord, chord)
    lam = np.clip(np.einsum("kc,kc->k", x - p[a], chord) / np.maximum(length2, 1e-30), 0, 1)
    distance = np.linalg.norm(x - p[a] - lam[:, None] * chord, axis=1)
    # Each segment's rotation once (many points share one: the grid in a sample interval).
    _, first, which = np.unique(a * len(p) + b, return_index=True, return_inverse=True)
    R_ab = np.swapaxes(R[a[first]], 1, 2) @ R[b[first]]
    rotvec = Rotation.from_matrix(R_ab).as_rotvec()[which]
    R_lam = R[a] @ rotation_matrices(lam[:, None] * rotvec)
    return distance, rotation_angles(np.swapaxes(R_lam, 1, 2) @ R_x)


def grid_error(X_PT_dense: np.ndarray) -> tuple[float, float]:
    """Bound [m, rad] of the continuous path's deviation from the grid's own chords: each
    odd point against the chord of its neighbours (twice the step, four times the
    error), divided by four."""
    if len(X_PT_dense) < 3:
        return 0.0, 0.0
    p, R = X_PT_dense[:, :3, 3], X_PT_dense[:, :3, :3]
    k = np.arange(1, len(p) - 1, 2)
    d, a = _chord_deviation(p, R, k - 1, k + 1, p[k], R[k])
    return float(d.max()) / 4.0, float(a.max()) / 4.0


def densify(data: ProgramData, chord_tol_m: float, angle_tol_rad: float) -> Densified:
    """Insert the grid points where the sample intervals miss the continuous path."""
    s_d, X_d = data.path_dense_m, data.X_PT_dense
    if len(s_d) == 0:
        return Densified(data, None, None, 0)
    s, p, R = data.path_m, data.X_PT[:, :3, 3], data.X_PT[:, :3, :3]
    i = np.searchsorted(s, s_d, side="right") - 1
    inside = (i >= 0) & (i < len(s) - 1) & (s_d > s[np.clip(i, 0, len(s) - 1)])
    inside &= s_d < s[np.clip(i + 1, 0, len(s) - 1)]
    k, i = np.flatnonzero(inside), i[inside]
    d, a = _chord_deviation(p, R, i, i + 1, X_d[k, :3, 3], X_d[k, :3, :3])
    worst_d, worst_a = np.zeros(len(s)), np.zeros(len(s))  # per sample interval
    np.maximum.at(worst_d, i, d)
    np.maximum.at(worst_a, i, a)
    refine = (worst_d > DENSIFY_SHARE * chord_tol_m) | (worst_a > DENSIFY_SHARE * angle_tol_rad)
    grid_d, grid_a = grid_error(X_d)
    residual_d = float(worst_d[~refine].max(initial=0.0)) + grid_d
    residual_a = float(worst_a[~refine].max(initial=0.0)) + grid_a
    new = k[refine[i]]
    if len(new) == 0:
        return Densified(data, residual_d, residual_a, 0)
    return Densified(_insert(data, new), residual_d, residual_a, len(new))


def _insert(data: ProgramData, new: np.ndarray) -> ProgramData:
    """The plan's rows plus the grid points ``new`` (K,) (indices into path_dense_m)."""
    s_new, X_PT_new = data.path_dense_m[new], data.X_PT_dense[new]
    rising = np.concatenate([[True], np.diff(data.path_m) > 0])
    t_new = PchipInterpolator(data.path_m[rising], data.t[rising])(s_new)
    qd_new = CubicHermiteSpline(data.t, data.q, data.qd, axis=0)(t_new, 1)
    X_BE_new = data.X_BT @ np.linalg.inv(X_PT_new) @ np.linalg.inv(data.X_EP)
    q_new = (
        data.q_dense[new] if len(data.q_dense) == len(data.path_dense_m) else _old_plan(data)[new]
    )
    order = np.argsort(np.concatenate([data.path_m, s_new]), kind="stable")

    def merged(old, new):
        return np.concatenate([old, new])[order]

    return dataclasses.replace(
        data,
        t=merged(data.t, t_new),
        path_m=merged(data.path_m, s_new),
        q=merged(data.q, q_new),
        qd=merged(data.qd, qd_new),
        X_BE=merged(data.X_BE, X_BE_new),
        X_PT=merged(data.X_PT, X_PT_new),
        tcp_speed=merged(data.tcp_speed, np.interp(s_new, data.path_m, data.tcp_speed)),
    )


def _old_plan(data: ProgramData) -> np.ndarray:
    """(M, 6) q_dense of a plan made before plans stored it, from the robot's IK."""
    from offline_prog.robot.dense_joints import dense_joints

    X_BE_dense = data.X_BT @ np.linalg.inv(data.X_PT_dense) @ np.linalg.inv(data.X_EP)
    args = (data.path_m, data.t, data.q, data.qd, data.X_BE, data.path_dense_m, X_BE_dense)
    return dense_joints(data.load_robot(), *args)
