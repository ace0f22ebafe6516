"""Time-optimal path parameterization under the joint limits (the paper's outlook).

TOPP-RA (Pham & Pham 2018, the ``toppra`` package) finds the fastest σ̇(σ) along
the joint path q(σ) from the path IK, rest to rest, subject to

    |q′_k σ̇| ≤ q̇_max,k                      joint velocity,
    |q″_k σ̇² + q′_k σ̈| ≤ q̈_max,k             joint acceleration,
    σ̇ ≤ v_cap                                the process speed (TCP or flange),
    |σ̈| ≤ a_path                             the path acceleration limit.

The last two enter as a seventh, virtual joint q_7 = σ (q′_7 = 1, q″_7 = 0) with
velocity limit v_cap and acceleration limit a_path. q′ and q″ are exact (the Jacobian,
``robot.jacobian``). The result has piecewise-constant σ̈, so its acceleration
jumps: ``jerk_stage`` turns it into a jerk-limited law. An expected failure is a
return value with a reason (``ToppProfile.ok``), as in toppra itself.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from offline_prog.timing.joint_timing import JointRates

# Most grid points TOPP-RA solves on (the joint rates' grid is thinned to this): the
# solve time grows linearly with them; ~1 mm spacing on the demo seams.
TOPP_GRID_POINTS = 1000


@dataclasses.dataclass(frozen=True)
class ToppProfile:
    """TOPP-RA's answer on its grid.

    Attributes:
        sigma: (G,) grid [m].
        speed: (G,) time-optimal σ̇ [m/s] (0 at both ends).
        duration: rest-to-rest time of that profile [s] (no jerk limit).
        solve_s: wall time of the solve [s].
        ok: TOPP-RA found a parameterization; reason: why not (else "").
    """

    sigma: np.ndarray
    speed: np.ndarray
    duration: float
    solve_s: float
    ok: bool
    reason: str = ""


class _GridPath:
    """toppra's geometric-path interface over precomputed exact values on a grid
    (TOPP-RA evaluates the path at its grid points only)."""

    def __init__(self, sigma, q, dq, ddq):
        self.sigma, self._values = sigma, (q, dq, ddq)

    def __call__(self, ss, order=0):
        values = self._values[order]
        index = np.clip(np.searchsorted(self.sigma, ss), 0, len(self.sigma) - 1)
        if np.allclose(self.sigma[index], ss, rtol=0, atol=1e-12):
            return values[index]
        return np.column_stack(
            [np.interp(ss, self.sigma, values[:, k]) for k in range(values.shape[1])]
        )

    @property
    def dof(self) -> int:
        return self._values[0].shape[1]

    @property
    def path_interval(self) -> np.ndarray:
        return np.array([self.sigma[0], self.sigma[-1]])

    @property
    def waypoints(self):
        return None


def _speed_curve(v_max: np.ndarray, dof: int, a_max: np.ndarray | None = None):
    """A toppra constraint σ̇ ≤ v_max (G,) at the grid points, and |σ̈| ≤ a_max (G,)
    on the step after each if given, vectorised (toppra's
    JointVelocityConstraintVarying calls Python once per grid point)."""
    from toppra.constraint import LinearConstraint

    class SpeedCurve(LinearConstraint):
        def __init__(self):
            super().__init__()
            self.dof = dof

        def compute_constraint_params(self, path, gridpoints):
            xbound = np.column_stack([np.zeros(len(v_max)), v_max**2])
            ubound = None if a_max is None else np.column_stack([-a_max, a_max])
            return None, None, None, None, None, ubound, xbound

    return SpeedCurve()


def profile_duration(sigma: np.ndarray, speed: np.ndarray) -> float:
    """Time to run the profile [s]: constant σ̈ between grid points, so each step
    takes 2 Δσ / (σ̇_i + σ̇_i+1)."""
    mean = 0.5 * (speed[1:] + speed[:-1])
    return float(np.sum(np.diff(sigma) / np.maximum(mean, 1e-300)))


def topp_profile(
    rates: JointRates,
    *,
    qd_max: np.ndarray,
    qdd_max: np.ndarray,
    v_cap: float,
    a_path: float,
    v_steady: np.ndarray | None = None,
    a_curve: np.ndarray | None = None,
    grid_points: int = TOPP_GRID_POINTS,
) -> ToppProfile:
    """The time-optimal σ̇(σ) under the module's constraints (see the module doc).

    Args:
        rates: q, q′, q″ on a σ grid over [0, length], in the controller's axes.
        qd_max, qdd_max: (6,) joint velocity [rad/s] and acceleration [rad/s²] limits.
        v_cap: the process speed cap on σ̇ [m/s].
        a_path: the path acceleration limit on |σ̈| [m/s²].
        v_steady: (G,) optional further cap on σ̇ on the rates' grid [m/s] (the jerk
            stage's steady-speed jerk limit, |q‴σ̇³| ≤ q⃛_max: TOPP-RA knows no jerk).
        a_curve: (G,) optional further cap on |σ̈| on the rates' grid [m/s²] (the
            filtered stage lowers it where its window's speed changes are too hard).
        grid_points: most grid points of the solve.
    """
    import toppra.algorithm as algorithm  # 0.3 s (it imports matplotlib): only here
    import toppra.constraint as constraint

    keep = np.unique(np.linspace(0, len(rates.sigma) - 1, min(grid_points, len(rates.sigma))))
    keep = keep.round().astype(int)
    sigma = rates.sigma[keep]
    ones = np.ones((len(sigma), 1))
    path = _GridPath(
        sigma,
        np.hstack([rates.q[keep], sigma[:, None]]),
        np.hstack([rates.dq[keep], ones]),
        np.hstack([rates.ddq[keep], 0 * ones]),
    )
    v = np.append(qd_max, v_cap)
    a = np.append(qdd_max, a_path)
    constraints = [
        constraint.JointVelocityConstraint(np.column_stack([-v, v])),
        constraint.JointAccelerationConstraint(
            np.column_stack([-a, a]),
            discretization_scheme=constraint.DiscretizationType.Interpolation,
        ),
    ]
    if v_steady is not None or a_curve is not None:
        v_curve = np.full(len(sigma), v_cap) if v_steady is None else v_steady[keep]
        a_step = None if a_curve is None else np.minimum(a_curve[keep], a_path)
        constraints.append(_speed_curve(np.minimum(v_curve, v_cap), path.dof, a_step))
    start = time.perf_counter()
    solver = algorithm.TOPPRA(constraints, path, gridpoints=sigma, solver_wrapper="seidel")
    _, sd, _ = solver.compute_parameterization(0.0, 0.0)
    solve_s = time.perf_counter() - start
    code = solver.problem_data.return_code
    if sd is None or str(code.name) != "Ok":
        return ToppProfile(sigma, np.zeros_like(sigma), np.inf, solve_s, False, str(code))
    speed = np.clip(np.asarray(sd, dtype=float), 0.0, v_cap)
    return ToppProfile(sigma, speed, profile_duration(sigma, speed), solve_s, True)
