"""General inverse kinematics with Drake's InverseKinematics: the fallback and the baseline.

One flange pose X_IE is reached by a nonlinear program in the robot's joints q (6,):
position constraints put three points of the flange frame E on their targets in I,
joint limits come from the plant, and a quadratic cost |q − q_seed|² keeps the solver on
the seed's configuration branch. SNOPT solves it when available, else IPOPT (Drake's
ChooseBestSolver). Success is then checked with Drake FK against the position and angle
tolerances. Along a path each sample is seeded with the previous solution: the obvious
baseline that the analytic path IK (``path_ik``) is benchmarked against.

Why points and not AddOrientationConstraint: Drake writes that constraint as
trace(R) ≥ 1 + 2 cos θ_bound, which is flat at θ = 0 (trace(R) ≈ 3 − θ²), so a solver
that meets it to 1e−12 leaves θ ≈ 1e−6 rad; SNOPT stopped at 2–5e−6 rad on these robots.
Constraints on points of E are linear in the pose error and converge in a few Newton
steps. They are also the one target Drake lets us change after building the program
(``PositionConstraint.set_bounds``), so the program is built once per cell.

The points are the origin Eo (all three coordinates in I), Q1 = Eo + L x_E (the two
coordinates of I across x_E; with Eo they fix x_E) and Q2 = Eo + L y_E (the coordinate of
I most along z_E, which fixes the turn about x_E): six equations for six joints, none
redundant, so the problem is regular at the solution. They are equalities, not boxes of
±tolerance: boxes 1e−9 wide change nothing in the answer but give the solver a vertex to
find; without restarts SNOPT missed 5 of 3,000 regular test poses with boxes, 1 with
equalities.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
from pydrake.math import RigidTransform
from pydrake.multibody.inverse_kinematics import InverseKinematics
from pydrake.solvers import (
    ChooseBestSolver,
    IpoptSolver,
    MakeSolver,
    SnoptSolver,
    SolverId,
    SolverOptions,
)

from offline_prog.scene.drake_cell import DrakeCell

DEFAULT_POSITION_TOL_M = 1e-9  # largest distance |p_IE − p_IE,target| of a solution [m]
DEFAULT_ANGLE_TOL_RAD = 1e-9  # largest angle between R_IE and its target [rad]
LEVER_ARM_M = 1.0  # L: distance of Q1, Q2 from Eo [m]
SEED_COST_WEIGHT = 1.0  # w in w |q − q_seed|² [1/rad²]
# Solvers stop once constraints hold to this [m]; their defaults (SNOPT 1e−6, IPOPT
# 1e−4) stop about 1e−8 m short, outside the default tolerances.
SOLVER_FEASIBILITY_TOL = 1e-12
# Restarts from the last iterate when it misses the tolerances: SNOPT sometimes stalls
# 1e−9..1e−7 short (about 1 pose in 1,000); one restart fixed all of 12,000 test poses.
MAX_RESTARTS = 1
# Points of E [m]: Eo, Q1 on x_E, Q2 on y_E.
_P_EQ = np.array([[0.0, 0.0, 0.0], [LEVER_ARM_M, 0.0, 0.0], [0.0, LEVER_ARM_M, 0.0]])


@dataclasses.dataclass(frozen=True)
class PathIkResult:
    """Sequential Drake IK along a flange path.

    Attributes:
        q: (N, 6) joint path [rad]; where success is False, the solver's last iterate.
        success: (N,) q inside the joint limits and the pose within tolerance (Drake FK).
        max_position_error_m: largest |p_IE − target| over all N samples [m].
        max_angle_error_rad: largest angle between R_IE and its target, all samples [rad].
        seconds: wall time of the whole path, program building included [s].
    """

    q: np.ndarray
    success: np.ndarray
    max_position_error_m: float
    max_angle_error_rad: float
    seconds: float


class PoseIk:
    """One IK program for a cell, built once and re-aimed at each target pose.

    Args:
        cell: the Drake cell; the robot's six joints are the plant's positions.
        position_tol_m: accepted distance of Eo from its target [m].
        angle_tol_rad: accepted angle between R_IE and its target [rad].
        solver_id: force a solver (e.g. ``IpoptSolver.id()``); default Drake's choice.

    Raises:
        ValueError: a tolerance is not a positive finite number.
    """

    def __init__(
        self,
        cell: DrakeCell,
        *,
        position_tol_m: float = DEFAULT_POSITION_TOL_M,
        angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD,
        solver_id: SolverId | None = None,
    ):
        for name, value in (("position_tol_m", position_tol_m), ("angle_tol_rad", angle_tol_rad)):
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name}: expected a positive finite number, got {value!r}")
        self.position_tol_m = float(position_tol_m)
        self.angle_tol_rad = float(angle_tol_rad)
        plant = cell.plant
        # The diagram's context (not a plant-only one) leaves room for collision constraints.
        self._diagram_context = cell.diagram.CreateDefaultContext()
        plant_context = plant.GetMyMutableContextFromRoot(self._diagram_context)
        self._ik = InverseKinematics(plant, plant_context, with_joint_limits=True)
        self._q = self._ik.q()
        frame_E, frame_I = cell.frame_E, plant.world_frame()
        self._points = [
            self._ik.AddPositionConstraint(frame_E, p_EQ, frame_I, np.zeros(3), np.zeros(3))
            for p_EQ in _P_EQ
        ]
        self._prog = self._ik.get_mutable_prog()
        self._seed_cost = self._prog.AddQuadraticErrorCost(
            SEED_COST_WEIGHT * np.eye(6), np.zeros(6), self._q
        )
        self._solver = MakeSolver(ChooseBestSolver(self._prog) if solver_id is None else solver_id)
        self._options = SolverOptions()
        self._options.SetOption(
            SnoptSolver.id(), "Major feasibility tolerance", SOLVER_FEASIBILITY_TOL
        )
        self._options.SetOption(IpoptSolver.id(), "constr_viol_tol", SOLVER_FEASIBILITY_TOL)
        self._options.SetOption(IpoptSolver.id(), "bound_relax_factor", 0.0)  # limits exact
        self._q_lower = plant.GetPositionLowerLimits()
        self._q_upper = plant.GetPositionUpperLimits()
        self._plant, self._frame_E = plant, frame_E
        self._fk_context = plant.CreateDefaultContext()

    @property
    def solver_id(self) -> SolverId:
        """The solver in use (SNOPT when available, else IPOPT, unless forced)."""
        return self._solver.solver_id()

    def solve(
        self, p_IE: np.ndarray, R_IE: np.ndarray, q_seed: np.ndarray
    ) -> tuple[np.ndarray, bool, float, float]:
        """Joints that put E at (p_IE, R_IE), starting from and staying near q_seed.

        Args:
            p_IE: (3,) target position of Eo in I [m].
            R_IE: (3, 3) target orientation of E in I.
            q_seed: (6,) initial guess and cost centre [rad].

        Returns:
            q (6,) [rad], success, position error [m], angle error [rad] (errors from
            Drake FK of q). Success is checked, not taken from the solver's status: q
            inside the joint limits and both errors within tolerance.
        """
        self._aim(p_IE, R_IE)
        w = SEED_COST_WEIGHT
        self._seed_cost.evaluator().UpdateCoefficients(
            2.0 * w * np.eye(6), -2.0 * w * q_seed, w * q_seed @ q_seed, is_convex=True
        )
        q_guess = q_seed
        for _ in range(1 + MAX_RESTARTS):
            result = self._solver.Solve(self._prog, q_guess, self._options)
            q = result.GetSolution(self._q)
            position_error, angle_error = self._pose_errors(q, p_IE, R_IE)
            success = (
                np.all((self._q_lower <= q) & (q <= self._q_upper))
                and position_error <= self.position_tol_m
                and angle_error <= self.angle_tol_rad
            )
            if success or not np.all(np.isfinite(q)):
                break
            q_guess = q
        return q, bool(success), position_error, angle_error

    def _aim(self, p_IE: np.ndarray, R_IE: np.ndarray) -> None:
        """Puts the three point constraints on the target pose."""
        p_IQ = p_IE + _P_EQ @ R_IE.T  # (3, 3): Eo, Q1, Q2 in I [m]
        free = np.zeros((3, 3))  # inf: that coordinate of I is left free
        # Q1: the two axes of I farthest from x_E (Q1 can only move across x_E).
        free[1, np.argmax(np.abs(R_IE[:, 0]))] = np.inf
        # Q2: only the axis of I nearest z_E (a turn about x_E moves Q2 along z_E).
        free[2] = np.inf
        free[2, np.argmax(np.abs(R_IE[:, 2]))] = 0.0
        for binding, p, h in zip(self._points, p_IQ, free, strict=True):
            binding.evaluator().set_bounds(p - h, p + h)

    def _pose_errors(self, q: np.ndarray, p_IE: np.ndarray, R_IE: np.ndarray):
        self._plant.SetPositions(self._fk_context, q)
        X_IE = self._frame_E.CalcPoseInWorld(self._fk_context)
        position_error = float(np.linalg.norm(X_IE.translation() - p_IE))
        return position_error, rotation_angle(R_IE.T @ X_IE.rotation().matrix())


def rotation_angle(R: np.ndarray) -> float:
    """Angle of the rotation matrix R (3, 3) [rad], accurate near 0 and near π."""
    sin = 0.5 * np.linalg.norm([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return float(np.arctan2(sin, 0.5 * (np.trace(R) - 1.0)))


def solve_pose(
    cell: DrakeCell,
    X_IE: RigidTransform,
    q_seed: np.ndarray,
    *,
    position_tol_m: float = DEFAULT_POSITION_TOL_M,
    angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD,
) -> tuple[np.ndarray, bool]:
    """One Drake IK solve for the flange pose X_IE near q_seed.

    Args:
        cell: the Drake cell.
        X_IE: target pose of the flange E in I.
        q_seed: (6,) initial guess, also the centre of the cost |q − q_seed|² [rad].
        position_tol_m: accepted distance of Eo from its target [m].
        angle_tol_rad: accepted angle between R_IE and its target [rad].

    Returns:
        q: (6,) joints [rad] (the solver's last iterate if not successful); success:
        q inside the joint limits and the pose within tolerance by Drake FK.
        An unreachable pose gives success False, not an exception.

    Raises:
        ValueError: q_seed is not 6 finite numbers, or a tolerance is not positive.
    """
    q_seed = _checked("q_seed", q_seed, (6,))
    ik = PoseIk(cell, position_tol_m=position_tol_m, angle_tol_rad=angle_tol_rad)
    q, success, _, _ = ik.solve(X_IE.translation(), X_IE.rotation().matrix(), q_seed)
    return q, success


def solve_path(
    cell: DrakeCell,
    p_IE: np.ndarray,
    R_IE: np.ndarray,
    q_start: np.ndarray,
    *,
    position_tol_m: float = DEFAULT_POSITION_TOL_M,
    angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD,
) -> PathIkResult:
    """Sequential Drake IK along a flange path, each sample seeded with the previous one.

    The program is built once; each sample only moves the point targets and the cost
    centre. A failed sample does not become a seed: the next one starts from the last
    success (q_start at first).

    Args:
        cell: the Drake cell.
        p_IE: (N, 3) flange positions in I [m].
        R_IE: (N, 3, 3) flange orientations in I.
        q_start: (6,) seed of the first sample [rad]; it picks the branch.
        position_tol_m, angle_tol_rad: accepted pose error per sample [m], [rad].

    Returns:
        The joint path, per-sample success, worst pose errors and the wall time.

    Raises:
        ValueError: an argument has the wrong shape or non-finite values, or a
            tolerance is not positive.
    """
    start = time.perf_counter()
    p_IE = _checked("p_IE", p_IE, (-1, 3))
    R_IE = _checked("R_IE", R_IE, (len(p_IE), 3, 3))
    q_seed = _checked("q_start", q_start, (6,))
    ik = PoseIk(cell, position_tol_m=position_tol_m, angle_tol_rad=angle_tol_rad)
    n = len(p_IE)
    q, success, errors = np.zeros((n, 6)), np.zeros(n, dtype=bool), np.zeros((n, 2))
    for i in range(n):
        q[i], success[i], position_error, angle_error = ik.solve(p_IE[i], R_IE[i], q_seed)
        errors[i] = position_error, angle_error
        if success[i]:
            q_seed = q[i]
    worst = errors.max(axis=0) if n else np.zeros(2)
    return PathIkResult(q, success, float(worst[0]), float(worst[1]), time.perf_counter() - start)


def _checked(name: str, value, shape: tuple[int, ...]) -> np.ndarray:
    """value as a float array of the given shape (−1: any length), else ValueError."""
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected numbers, got {value!r}") from None
    if array.ndim != len(shape) or any(
        s not in (-1, a) for s, a in zip(shape, array.shape, strict=True)
    ):
        expected = "(" + ", ".join("N" if s == -1 else str(s) for s in shape) + ")"
        raise ValueError(f"{name}: expected shape {expected}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name}: expected finite values, got {value!r}")
    return array
