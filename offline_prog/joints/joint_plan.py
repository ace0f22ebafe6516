"""From the flange trajectory to a joint trajectory q(t) within the robot's limits.

Stages: pick one configuration branch and 2π start for the whole path
(``path_ik``), get q′(σ), q″(σ) exactly from the flange path's analytic
σ-derivatives through the robot's Jacobian (``robot.jacobian``), time the path
under the joint limits (``time_optimal`` + ``jerk_stage``, or the paper's sin²
law with ``joint_timing``; the time-optimal law's joint jerk checked once more on the
output samples with the exact path, ``jerk_check``), and sample the final trajectory
with its joint positions, speeds, accelerations, singularity distances and joint steps
(σ: the seam's). Failures are results that say where (σ, t) and why.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.constants import ProcessIntent, TimeLaw
from offline_prog.errors import Failure, PlanFailedError, PlanFailure
from offline_prog.joints.jerk_check import verified_timing
from offline_prog.joints.path_ik import (
    BranchResult,
    base_poses,
    branch_results,
    branch_table,
    choose_branch,
    first_outside,
    singularity_distances,
    singularity_report,
)
from offline_prog.process.timing_bound import ProcessCaps
from offline_prog.robot.jacobian import joint_path_rates, urdf_chain
from offline_prog.robot.kinematics_opw import wrap_to_pi
from offline_prog.robot.model import RobotModel
from offline_prog.timing.joint_timing import JointRates
from offline_prog.timing.path_timing import PathLimits, PathTiming, time_path
from offline_prog.timing.time_law import Sin2TimeLaw
from offline_prog.timing.trajectory import (
    TimeLawParameter,
    WorkspaceTrajectory,
    sample_workspace_trajectory,
)

# σ grid for branch choice and joint rates [m].
GRID_SPACING_M = 5e-4
# Fewest path-IK grid points, however short the path (a short seam still gets a fine look).
MIN_GRID_POINTS = 2001
# Time grid that inverts σ(t) for failure messages (t to ~duration / 20000).
TIME_INVERSION_POINTS = 20001


class JointPlanError(PlanFailedError):
    """The robot cannot follow the path: σ [m], t [s], why and the kind of failure."""

    def __init__(self, sigma: float, t: float, reason: str, kind: Failure):
        super().__init__(PlanFailure(kind, float(sigma), float(t), reason))


@dataclasses.dataclass(frozen=True)
class JointTrajectory:
    """The joint trajectory on the final samples (rows match ``trajectory``).

    Attributes:
        trajectory: the retimed workspace trajectory.
        branch: the chosen solution index; branches: every branch's verdict.
        q, qd, qdd: (N, 6) joint positions [rad], speeds [rad/s], accelerations [rad/s²].
        margin_rad: (6,) smallest distance of each joint to its limits [rad].
        largest_step: (joint index, σ, step [rad]) between neighbouring samples.
        singularities: per kind, (min distance, σ at it) and the near stretches.
        retiming: the speed reductions the joints needed.
        process_caps: the path caps the process model set (``process.timing_bound``;
            None: the user's alone).
        unbounded_s: the duration of the same path timed under the user's own caps
            [s], when the process model lowered them (None: it did not).
    """

    trajectory: WorkspaceTrajectory
    branch: int
    branches: list[BranchResult]
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    margin_rad: np.ndarray
    largest_step: tuple[int, float, float]
    singularities: dict
    retiming: PathTiming
    process_caps: ProcessCaps | None = None
    unbounded_s: float | None = None


class BranchPath:
    """q(σ) on one branch, evaluated exactly by the analytic IK of the flange pose."""

    def __init__(self, robot: RobotModel, X_IB, flange, parameter: TimeLawParameter, branch: int):
        self.robot, self.X_IB, self.flange = robot, X_IB, flange
        self.parameter, self.branch = parameter, branch

    def poses(self, sigma: np.ndarray) -> np.ndarray:
        """(N, 4, 4) X_BE at σ."""
        f = self.flange(self.parameter.s(sigma)[0])
        return base_poses(self.X_IB, f.p_IE, f.R_IE)

    def q(self, sigma: np.ndarray, q_near: np.ndarray) -> np.ndarray:
        """(N, 6) the branch's solution at σ, taken as the 2π-equivalent nearest q_near."""
        raw = self.robot.inverse_branch(self.poses(sigma), self.branch)
        return q_near + wrap_to_pi(raw - q_near)

    def singularity_distances(self, q: np.ndarray, sigma: np.ndarray) -> dict:
        """Wrist, elbow and shoulder distances (``path_ik.singularity_distances``)."""
        return singularity_distances(self.robot, q, self.poses(sigma))

    def rates(self, sigma: np.ndarray, q_near: np.ndarray) -> JointRates:
        """q at σ by the exact IK; q′ and q″ exactly, through the Jacobian, from the
        flange path's analytic σ-derivatives (``robot.jacobian.joint_path_rates``)."""
        q = self.q(sigma, q_near)
        s, ds, dds = self.parameter.s(sigma)
        f = self.flange(s)
        R_BI = self.X_IB.rotation().inverse().matrix()
        # Twist rates per σ in I (chain rule through s(σ)), then expressed in B.
        w1 = f.w_s * ds[:, None]
        v1 = f.dp_IE * ds[:, None]
        w2 = f.dw_s * (ds**2)[:, None] + f.w_s * dds[:, None]
        v2 = f.ddp_IE * (ds**2)[:, None] + f.dp_IE * dds[:, None]
        V1 = np.hstack([w1 @ R_BI.T, v1 @ R_BI.T])
        V2 = np.hstack([w2 @ R_BI.T, v2 @ R_BI.T])
        dq, ddq = joint_path_rates(
            urdf_chain(self.robot.urdf_path, self.robot.joint_names), q, V1, V2
        )
        return JointRates(sigma, q, dq, ddq)


# Step between tried tool rotations [rad] and the σ grid for trying them: a point every
# ROTATION_TRIAL_SPACING_M, from ROTATION_MIN_TRIAL_POINTS (the continuity test sees a
# full turn of the wrist in 3.6° steps) to ROTATION_TRIAL_POINTS (a long seam).
ROTATION_STEP_RAD = np.deg2rad(5.0)
ROTATION_TRIAL_POINTS = 400
ROTATION_MIN_TRIAL_POINTS = 100
ROTATION_TRIAL_SPACING_M = 3e-3


def rotation_trial_points(length_m: float) -> int:
    """How many σ samples :func:`tool_rotations` tries each turn on, for a path of
    ``length_m`` [m]: the rotations' IK is most of a short seam's planning."""
    wanted = int(np.ceil(length_m / ROTATION_TRIAL_SPACING_M)) + 1
    return int(np.clip(wanted, ROTATION_MIN_TRIAL_POINTS, ROTATION_TRIAL_POINTS))


def tool_rotations(
    robot: RobotModel, X_IB, path, normal, *, X_IT, X_PE, bound_rad, axis="y", smooth_turn=None
):
    """Turns φ₀ ∈ [−bound, bound] of a symmetric tool about its axis, best first.

    The process frame is laid onto T·R_axis(φ₀) instead of T, which a tool
    symmetric about that axis cannot tell apart. A constant φ₀ keeps the flange
    path exactly as smooth as with φ₀ = 0; with ``smooth_turn`` (a
    ``path.tool_turn.SmoothTurn``) the tool turns by φ₀ + θ − θ̄ along the path, and
    φ₀ keeps the whole turn within ±bound (if θ − θ̄ spans more than 2·bound, a
    share of it is taken up, about the middle φ₀). Ranked by the joint-limit margin
    of each φ₀'s best branch (the smaller |φ₀| on ties; a robot of family drake has no
    analytic IK to rank with: smallest |φ₀| first); the collision check may move on to
    the next.

    Returns:
        [(φ₀ [rad], the FlangePath built with it), ...], best first.
    """
    from pydrake.common.eigen_geometry import AngleAxis
    from pydrake.math import RigidTransform, RotationMatrix

    from offline_prog.path.fixed_tcp import FlangePath

    unit = np.eye(3)["xyz".index(axis)]
    lo, hi, scale = -bound_rad, bound_rad, 1.0
    if smooth_turn is not None:
        low, high = smooth_turn.span_rad
        scale = min(1.0, 2.0 * bound_rad / max(high - low, 1e-12))
        lo, hi = -bound_rad - scale * low, bound_rad - scale * high
        if scale < 1.0:  # the whole free rotation is taken up: one φ₀
            lo = hi = 0.5 * (lo + hi)
    count = int(np.ceil((hi - lo) / (2.0 * ROTATION_STEP_RAD)))
    angles = np.linspace(lo, hi, 2 * count + 1) if count else np.array([lo])
    s = np.linspace(0.0, path.length, rotation_trial_points(path.length))
    flanges = []
    for phi in sorted(angles, key=abs):
        if smooth_turn is None:
            X_IT_phi = X_IT @ RigidTransform(RotationMatrix(AngleAxis(phi, unit)), np.zeros(3))
            flange = FlangePath(path, normal, X_IT=X_IT_phi, X_PE=X_PE)
        else:
            turn = smooth_turn.with_offset(float(phi), scale)
            flange = FlangePath(path, normal, X_IT=X_IT, X_PE=X_PE, tool_turn=turn, axis=unit)
        flanges.append((float(phi), flange))
    if robot.family == "drake":  # no analytic IK to rank with: smallest |φ₀| first
        return flanges
    # Every φ₀'s trial poses through the analytic IK at once (per-call overhead, not
    # arithmetic, dominates 400 poses), then each φ₀'s branches.
    X_BE = _trial_poses(flanges, s, X_IB, X_PE, fixed_turn=smooth_turn is None)
    solutions = robot.inverse(X_BE).reshape(len(flanges), len(s), 8, 6)
    table = branch_table(robot, solutions)  # every turn's branches at once
    ranked = []
    for a, (phi, flange) in enumerate(flanges):
        ranked.append((_turn_score(robot, table, a), -abs(phi), phi, flange))
    ranked.sort(key=lambda r: (r[0], r[1]), reverse=True)
    return [(phi, flange) for _, _, phi, flange in ranked]


def _trial_poses(flanges, s: np.ndarray, X_IB, X_PE, *, fixed_turn: bool) -> np.ndarray:
    """(A·N, 4, 4) every turn's flange poses X_BE at s (N,): each FlangePath's own
    ``poses`` numbers; for fixed turns from one look-up of the part's side of the path
    (``part_in_tool``) instead of one per turn."""
    from offline_prog.path.fixed_tcp import part_in_tool

    if not fixed_turn:
        return np.concatenate([base_poses(X_IB, *flange.poses(s)) for _, flange in flanges])
    path, normal = flanges[0][1].path, flanges[0][1].normal
    _, _, p_TE_T, _, _, M, _, _ = part_in_tool(path, normal, X_PE, s)
    poses = []
    for _, flange in flanges:  # FlangePath.poses' own arithmetic (einsum's rounding
        # depends on its operands' layout): bit for bit the same poses
        G = np.broadcast_to(flange.X_IT.rotation().matrix(), (len(s), 3, 3))
        p_IE = flange.X_IT.translation() + np.einsum("nij,nj->ni", G, p_TE_T)
        poses.append(base_poses(X_IB, p_IE, G @ M))
    return np.concatenate(poses)


def _turn_score(robot: RobotModel, table, a: int) -> tuple:
    """(feasible, its margin, or how far it gets) of turn a's best branch, as
    ``choose_branch(branch_results(...))`` scores it, from the turns' BranchTable."""
    feasible = table.feasible[a]
    if feasible.any():
        return True, float(table.margin[a][feasible].max())
    best = None
    for b in range(8):
        margin = float(table.margin[a, b])
        if not table.reachable[a, b].all():
            sample, margin = int(table.first_unreachable[a, b]), -np.inf
        elif table.first_jump[a, b] >= 0:
            sample = int(table.first_jump[a, b])
        else:  # a joint limit
            joint = int(np.argmin(table.margins[a, b]))
            sample = first_outside(robot, table.q[a, b], joint)
        best = max(best or (sample, margin), (sample, margin))
    return False, best[0]


def _time_at(law: Sin2TimeLaw, sigma: float) -> float:
    t = np.linspace(0.0, law.duration, TIME_INVERSION_POINTS)
    return float(np.interp(sigma, law(t)[0], t))


def path_branches(
    robot: RobotModel,
    X_IB,
    flange,
    parameter: TimeLawParameter,
    branch: int | None = None,
    *,
    results: list[BranchResult] | None = None,
) -> tuple[np.ndarray, list[BranchResult], BranchResult, BranchPath]:
    """The path IK on the σ grid, before any time law: (grid (M,) σ [m], every branch's
    verdict on it, the chosen one (``branch`` if given, else the best; its ``q`` (M, 6)
    [rad] on the grid), the chosen branch's exact q(σ)). A robot of family drake has
    one verdict, Drake IK's along the grid. ``results``: the verdicts of an earlier
    call on the same flange path and parameter (analytic IK), not computed again."""
    length = parameter.length
    grid = np.linspace(0.0, length, max(MIN_GRID_POINTS, int(np.ceil(length / GRID_SPACING_M)) + 1))
    if robot.family == "drake":  # no closed form: Drake InverseKinematics along the grid
        from offline_prog.joints.drake_path import DrakeIkPath

        path = DrakeIkPath(robot, X_IB, flange, parameter)
        chosen = path.choose(grid)
        return grid, [chosen], chosen, path
    if results is None:
        results = branch_results(robot, BranchPath(robot, X_IB, flange, parameter, 0).poses(grid))
    chosen = choose_branch(results) if branch is None else results[branch]
    return grid, results, chosen, BranchPath(robot, X_IB, flange, parameter, chosen.branch)


def plan_joint_trajectory(
    robot: RobotModel,
    X_IB,
    flange,
    parameter: TimeLawParameter,
    limits: PathLimits,
    *,
    rate_hz: float,
    branch: int | None = None,
    time_law: TimeLaw = TimeLaw.SIN2,
    process: ProcessIntent = ProcessIntent.CONSTANT_SPEED,
    process_caps: ProcessCaps | None = None,
    branches: list[BranchResult] | None = None,
) -> JointTrajectory:
    """Joint trajectory for the flange path, or JointPlanError (σ, t, why).

    Args:
        robot: the robot record (analytic IK; Drake IK for family "drake").
        X_IB: robot base in I.
        flange: the flange path X_IE(s).
        parameter: σ ↦ s for the time law's speed reference.
        limits: the path's process speed and caps and the robot's joint limits (its
            ``nominal`` law: the process time law before joint limits).
        rate_hz: output sample rate.
        branch: use this analytic branch (if feasible) instead of the best one.
        time_law: TimeLaw.TIME_OPTIMAL (TOPP-RA, then the jerk stage) or TimeLaw.SIN2
            (the paper's law, plateaus lowered where the joints need it).
        process: the time-optimal intent (ProcessIntent).
        process_caps: the caps ``limits`` hold (``process.timing_bound``); where
            they are below the user's, the same path is timed under the user's caps
            too, for the trade-off in cycle time (``JointTrajectory.unbounded_s``).
        branches: every branch's verdict on this path's grid, when known
            (``path_branches``' results): the path IK is not run again.
    """
    grid, results, chosen, path = path_branches(
        robot, X_IB, flange, parameter, branch, results=branches
    )
    if not chosen.feasible:
        sigma = float(grid[chosen.sample])
        raise JointPlanError(sigma, _time_at(limits.nominal, sigma), chosen.reason, chosen.kind)
    rates = path.rates(grid, chosen.q)
    # Speed and acceleration limits hold for the controller's joints (a linear map).
    controller = JointRates(
        rates.sigma, *(robot.controller_joints(v) for v in (rates.q, rates.dq, rates.ddq))
    )
    retiming, controller = verified_timing(
        lambda rates: time_path(rates, limits, time_law, process),
        controller,
        path,
        robot,
        chosen.q,
        rate_hz=rate_hz,
    )
    if not retiming.feasible:
        joint, sigma, use = retiming.worst
        jerk = retiming.law_kind is TimeLaw.TIME_OPTIMAL
        kinds = "speed/acceleration/jerk" if jerk else "speed/acceleration"
        raise JointPlanError(
            sigma,
            _time_at(retiming.law, sigma),
            f"joint {kinds} limit on axis {joint + 1} ({use:.2f}× the limit) even at reduced speed",
            Failure.JOINT_RATE_LIMIT,
        )
    unbounded_s = None
    if process_caps is not None and process_caps.bounded:
        unbounded = dataclasses.replace(
            limits,
            a_max=process_caps.user_a_max,
            j_max=process_caps.user_j_max,
        )
        other = time_path(controller, unbounded, time_law, process)
        unbounded_s = float(other.law.duration) if other.feasible else None
    trajectory = sample_workspace_trajectory(flange, parameter, retiming.law, rate_hz=rate_hz)
    sigma, sd, sdd, _ = retiming.law(trajectory.t)
    q_near = np.column_stack([np.interp(sigma, grid, chosen.q[:, j]) for j in range(6)])
    final = path.rates(sigma, q_near)
    q = final.q
    qd = final.dq * sd[:, None]
    qdd = final.ddq * (sd**2)[:, None] + final.dq * sdd[:, None]
    q_c = robot.controller_joints(q)
    margin = np.minimum(q_c.min(axis=0) - robot.q_lower, robot.q_upper - q_c.max(axis=0))
    if margin.min() < 0:  # the grid missed a limit between its points
        joint = int(np.argmin(margin))
        i = first_outside(robot, q, joint)
        raise JointPlanError(
            float(sigma[i]),
            float(trajectory.t[i]),
            f"joint limit on axis {joint + 1}",
            Failure.JOINT_LIMIT,
        )
    steps = np.abs(np.diff(q, axis=0))
    i, j = np.unravel_index(np.argmax(steps), steps.shape)
    distances = path.singularity_distances(q, sigma)
    singular = singularity_report(distances, sigma + parameter.start)  # the seam's σ
    return JointTrajectory(
        trajectory,
        chosen.branch,
        results,
        q,
        qd,
        qdd,
        margin,
        (int(j), float(sigma[i + 1] + parameter.start), float(steps[i, j])),
        singular,
        retiming,
        process_caps,
        unbounded_s,
    )
