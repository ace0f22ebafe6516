"""One candidate placement, judged: a cheap screen by the analytic path IK, and the
full planning pipeline of ``plan`` (minus the exports and the clearance plot).

The objective is lexicographic (issue 16), :meth:`Evaluation.key`:

1. feasible: reach, joint limits, one branch along the path, collision-free at the
   cell's clearances. An infeasible candidate keeps its reason and how far it is from
   feasible (``tier``, ``violation``), so a search can climb out of an infeasible
   start: tier 1 collides (violation: depth below the clearance [m]), tier 2 cannot
   follow the path (violation: share of the path out of reach plus the mean distance
   beyond reach [m] (``path_ik.reach_excess``), share on a flipping branch, joint-limit
   excess / π [rad], and the share of the path not done), tier 3 makes geometry the
   method refuses (violation 1).
2. cycle time [s], resolved to CYCLE_RESOLUTION_S, then
3. the smallest joint-limit margin [deg] (larger is better),
4. the distance to the wrist and elbow singularities [deg] (larger is better),
5. the clearance [mm] (larger is better).
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw

from offline_prog.config.cell import Cell, transform
from offline_prog.errors import Failure, InputError, PlanFailedError
from offline_prog.joints.path_ik import (
    base_poses,
    branch_results,
    reach_excess,
    singularity_distances,
)
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.path.process_frames import NormalTangentError
from offline_prog.placement.payload import CellPayload, unpack
from offline_prog.placement.space import Candidate, Pose
from offline_prog.plan import Plan, StageTimer, plan_flanges
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.session.state import SessionState, apply, initial_state, schema_transform
from offline_prog.stages import (
    FittedPath,
    Inputs,
    build_scene,
    fit_path,
    flange_paths,
    load_inputs,
)

CYCLE_RESOLUTION_S = 0.01  # cycle times closer than this tie; the margins decide
SCREEN_SAMPLES = 1000  # σ samples of the path-IK screen (corners need ~10 each)
FEASIBLE, COLLIDES, CANNOT_FOLLOW, REFUSED = range(4)  # tiers


@dataclasses.dataclass(frozen=True)
class Evaluation:
    """A candidate and every objective term.

    Attributes:
        candidate: what was evaluated.
        stage: "screen" (analytic path IK only) or "plan" (the planning pipeline).
        tier: FEASIBLE, COLLIDES, CANNOT_FOLLOW or REFUSED; violation: how far from
            feasible within the tier (0 when feasible).
        reason: why it is infeasible, one line ("" when feasible).
        failure: its kind: a :class:`~offline_prog.errors.Failure` value
            ("out_of_reach", "joint_limit", "singularity", "collision", ...) or
            "refused" (geometry the method refuses); "" when feasible.
        cycle_time_s: the seam's duration [s] (NaN without a plan).
        joint_limit_margin_deg: smallest distance of a joint to its limits [deg].
        singularity_margin_deg: smallest wrist or elbow angle from singular [deg].
        clearance_mm: smallest distance of a checked pair [mm] (NaN without a plan).
        tool_rotation_deg: the free tool rotation chosen [deg].
        process_bound_s: the seam at the process speed with no joint slow-down (the
            time law's nominal duration) [s]: no placement is faster.
        slowed_share: share of the path the joints slowed below the process speed;
            limiting_axis: the axis (1..6) closest to its limit there (0: none).
        seconds: the evaluation's wall time [s].
    """

    candidate: Candidate
    stage: str
    tier: int
    violation: float
    reason: str
    failure: str = ""
    cycle_time_s: float = math.nan
    joint_limit_margin_deg: float = -math.inf
    singularity_margin_deg: float = 0.0
    clearance_mm: float = math.nan
    tool_rotation_deg: float = 0.0
    process_bound_s: float = math.nan
    slowed_share: float = 0.0
    limiting_axis: int = 0
    seconds: float = 0.0

    @property
    def feasible(self) -> bool:
        return self.tier == FEASIBLE

    def key(self) -> tuple:
        """The lexicographic objective: smaller is better."""
        cycle = self.cycle_time_s if math.isfinite(self.cycle_time_s) else math.inf
        return (
            self.tier,
            self.violation,
            round(cycle / CYCLE_RESOLUTION_S) if cycle < math.inf else math.inf,
            -self.joint_limit_margin_deg,
            -self.singularity_margin_deg,
            -(self.clearance_mm if math.isfinite(self.clearance_mm) else -math.inf),
        )


@dataclasses.dataclass
class Context:
    """What a worker keeps of the cell between candidates."""

    inputs: Inputs  # the cell as given
    fit: FittedPath  # the seam does not move on the part: fitted once
    initial: SessionState
    carried: tuple[int, ...]  # obstacles that stand with the tool (indices)
    screen_s: np.ndarray  # (SCREEN_SAMPLES,) σ [m]


_CONTEXTS: dict[str, Context] = {}  # per worker process: one loaded cell per payload


def context(payload: CellPayload) -> Context:
    """The worker's Context for ``payload``, loaded on first use."""
    kept = _CONTEXTS.get(payload.digest)
    if kept is None:
        _CONTEXTS.clear()
        inputs = load_inputs(unpack(payload), ROBOTS_DIR)
        fit = fit_path(inputs)
        cell = inputs.cell
        names = set(cell.place.moves_with_tool) if cell.place else set()
        carried = tuple(i for i, shape in enumerate(cell.obstacles) if shape.name in names)
        s = np.linspace(0.0, fit.path.length, SCREEN_SAMPLES)
        kept = _CONTEXTS[payload.digest] = Context(inputs, fit, initial_state(cell), carried, s)
    return kept


def _rigid(pose: Pose) -> RigidTransform:
    p, rpy = pose
    return RigidTransform(RollPitchYaw(np.deg2rad(rpy)), np.asarray(p, dtype=float))


def pose_of(X: RigidTransform) -> Pose:
    """(p [m], rpy [deg]) of a RigidTransform, rounded to 1 µm and 1e-6 deg."""
    p = tuple(round(float(v), 6) + 0.0 for v in X.translation())
    rpy = RollPitchYaw(X.rotation()).vector()
    return p, tuple(round(float(np.rad2deg(a)), 6) + 0.0 for a in rpy)


def placed_cell(ctx: Context, candidate: Candidate) -> Cell:
    """The cell with the candidate's X_IT and X_PE; obstacles that stand with the tool
    moved with it: X_IO' = X_IT' · X_IT⁻¹ · X_IO."""
    state = dataclasses.replace(
        ctx.initial,
        p_IT=candidate.X_IT[0], rpy_IT_deg=candidate.X_IT[1],
        p_PE=candidate.X_PE[0], rpy_PE_deg=candidate.X_PE[1],
    )  # fmt: skip
    cell = apply(ctx.inputs.cell, ctx.initial, state)
    if not ctx.carried:
        return cell
    X_TT = _rigid(candidate.X_IT) @ ctx.inputs.X_IT.inverse()  # old tool pose → new
    obstacles = list(cell.obstacles)
    for i in ctx.carried:
        moved = pose_of(X_TT @ transform(obstacles[i].pose))
        obstacles[i] = dataclasses.replace(obstacles[i], pose=schema_transform(*moved))
    return dataclasses.replace(cell, obstacles=obstacles)


def moved_obstacles(ctx: Context, candidate: Candidate) -> dict[int, Pose]:
    """{obstacle index: its pose in I (p, rpy)} of the obstacles that stand with the
    tool, for the candidate."""
    X_TT = _rigid(candidate.X_IT) @ ctx.inputs.X_IT.inverse()
    return {i: pose_of(X_TT @ transform(ctx.inputs.cell.obstacles[i].pose)) for i in ctx.carried}


def screen(ctx: Context, candidate: Candidate) -> Evaluation:
    """The analytic path IK along SCREEN_SAMPLES poses, tool rotation 0 (~ms)."""
    start = time.perf_counter()
    inputs, fit = ctx.inputs, ctx.fit
    try:
        flange = FlangePath(fit.path, fit.normal, X_IT=_rigid(candidate.X_IT),
                            X_PE=_rigid(candidate.X_PE))  # fmt: skip
        f = flange(ctx.screen_s)
    except NormalTangentError as error:
        return Evaluation(candidate, "screen", REFUSED, 1.0, str(error), "refused")
    X_BE = base_poses(inputs.X_IB, f.p_IE, f.R_IE)
    results = branch_results(inputs.robot, X_BE)
    reach = ~np.isnan(inputs.robot.inverse(X_BE)).any(axis=-1)  # (N, 8)

    excess = float(reach_excess(inputs.robot, X_BE).mean())  # [m]

    def violation(r) -> float:
        if r.feasible:
            return 0.0
        unreachable = 1.0 - reach[:, r.branch].mean() + excess
        flipped = (1.0 - r.sample / len(ctx.screen_s)) if r.reason.startswith("singularity") else 0
        beyond = max(0.0, -r.margin_rad) if math.isfinite(r.margin_rad) else math.pi
        return float(unreachable + flipped + beyond / math.pi)

    best = min(results, key=lambda r: (violation(r), -r.margin_rad))
    seconds = time.perf_counter() - start
    if not best.feasible:
        v = violation(best)
        kind = Failure.of(best.reason).value
        return Evaluation(candidate, "screen", CANNOT_FOLLOW, v, best.reason, kind,
                          seconds=seconds)  # fmt: skip
    margin = float(np.rad2deg(best.margin_rad))
    d = singularity_distances(inputs.robot, best.q, X_BE)
    singular = float(np.rad2deg(np.arcsin(min(1.0, d["wrist"].min(), d["elbow"].min()))))
    return Evaluation(candidate, "screen", FEASIBLE, 0.0, "",
                      cycle_time_s=speed_limited_time(ctx, best.q),
                      joint_limit_margin_deg=margin, singularity_margin_deg=singular,
                      seconds=seconds)  # fmt: skip


def speed_limited_time(ctx: Context, q: np.ndarray) -> float:
    """The screen's cycle-time estimate [s]: ∫ dσ / v(σ) with v the process speed,
    lowered where a joint would pass its speed or acceleration limit at steady speed,
    v ≤ q̇max_j / |q′_j(σ)| and v ≤ √(q̈max_j / |q″_j(σ)|) (q′, q″ by differences of
    the (N, 6) joint path q [rad] on the screen's σ grid). The time law's ramps are
    left out: it ranks candidates, ``evaluate`` times them."""
    s, robot = ctx.screen_s, ctx.inputs.robot
    ds = np.diff(s)
    d1 = np.diff(q, axis=0) / ds[:, None]  # q′ [rad/m] between samples, (N−1, 6)
    d2 = np.zeros_like(d1)
    d2[1:] = np.diff(d1, axis=0) / ((ds[1:] + ds[:-1]) / 2)[:, None]  # q″ [rad/m²]
    with np.errstate(divide="ignore"):
        by_speed = np.min(robot.qd_max / np.abs(d1), axis=1)
        by_acceleration = np.min(np.sqrt(robot.qdd_max / np.abs(d2)), axis=1)
    v = np.minimum(ctx.inputs.cell.motion.speed, np.minimum(by_speed, by_acceleration))
    return float(np.sum(ds / v))


def plan_candidate(ctx: Context, candidate: Candidate) -> Plan:
    """The candidate's :class:`~offline_prog.plan.Plan` by ``plan``'s pipeline: process
    frames, the Drake cell, path IK and timing, collision check and avoidance (no
    clearance plot).

    Raises:
        PlanFailedError: the robot cannot follow the path; InputError: the geometry.
    """
    cell = placed_cell(ctx, candidate)
    inputs = dataclasses.replace(
        ctx.inputs, cell=cell, X_IT=transform(cell.tool.X_IT), X_PE=transform(cell.part.X_PE)
    )
    flanges = flange_paths(inputs, ctx.fit)
    scene = build_scene(inputs)
    return plan_flanges(inputs, scene, ctx.fit, flanges, StageTimer(lambda stage: None),
                        clearance_profile=False)  # fmt: skip


def evaluate(ctx: Context, candidate: Candidate) -> Evaluation:
    """The candidate through ``plan``'s pipeline (:func:`plan_candidate`), judged."""
    start = time.perf_counter()
    try:
        plan = plan_candidate(ctx, candidate)
    except PlanFailedError as error:
        done = error.failure.sigma_m / ctx.fit.path.length
        screened = screen(ctx, candidate)
        return Evaluation(candidate, "plan", CANNOT_FOLLOW, screened.violation + 1.0 - done,
                          str(error.failure), error.failure.kind.value,
                          seconds=time.perf_counter() - start)  # fmt: skip
    except InputError as error:
        return Evaluation(candidate, "plan", REFUSED, 1.0, error.reason, "refused",
                          seconds=time.perf_counter() - start)  # fmt: skip
    joints, collisions = plan.joints, plan.collisions
    singular = [joints.singularities[k]["distance"] for k in ("wrist", "elbow")
                if k in joints.singularities]  # fmt: skip
    tier, violation = FEASIBLE, 0.0
    if not plan.feasible:
        tier, violation = COLLIDES, max(0.0, collisions.clearance_m - collisions.min_distance_m)
    slowed = sum(b - a for a, b, _ in joints.retiming.reductions) / ctx.fit.path.length
    return Evaluation(
        candidate,
        "plan",
        tier,
        violation,
        "" if plan.feasible else plan.failure,
        "" if plan.feasible else Failure.COLLISION.value,
        cycle_time_s=float(plan.trajectory.duration),
        joint_limit_margin_deg=float(np.rad2deg(np.min(joints.margin_rad))),
        singularity_margin_deg=float(min(singular)) if singular else 90.0,
        clearance_mm=float(collisions.min_distance_m * 1e3),
        tool_rotation_deg=float(np.rad2deg(plan.tool_rotation_rad)),
        process_bound_s=float(plan.nominal_duration_s),
        slowed_share=float(min(1.0, slowed)),
        limiting_axis=int(joints.retiming.worst[0]) + 1 if slowed > 0 else 0,
        seconds=time.perf_counter() - start,
    )
