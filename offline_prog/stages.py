"""The stages of :func:`offline_prog.plan.plan_cell`, each a function with typed inputs
and outputs (the dataclasses below), in the paper's order:

``load_inputs`` (§2) → ``fit_path`` (§2, §4) → ``flange_paths`` (§3, §4) →
``build_scene`` → ``attempt_motion`` (§4, joints, collisions) → ``avoid``.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform

from offline_prog.collision.avoidance import Attempt, avoid_collisions, turn_tool_along_path
from offline_prog.collision.check import check_trajectory
from offline_prog.config.calibration_keys import check_controller_frames
from offline_prog.config.cell import ApproachConfig, Cell, load_cell, seam_moves_m, transform
from offline_prog.config.checks import check_cell
from offline_prog.config.job_checks import check_process_io
from offline_prog.config.process_speed import ProcessSpeed, process_speed
from offline_prog.config.robot_search import find_robot, search_path
from offline_prog.constants import LIMIT_CHECK_RATE_HZ, MAX_SAMPLES
from offline_prog.errors import InputError, PlanFailedError
from offline_prog.joints.joint_plan import plan_joint_trajectory, tool_rotations
from offline_prog.path.arc_length import ArcLengthPath
from offline_prog.path.bspline_fit import FittedSpline, fit_bspline
from offline_prog.path.cusps import Cusp, SmoothedFlangePath, find_cusps
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.path.inputs import NormalFit, check_normal_fit, load_points, normal_field
from offline_prog.path.lead import LeadPath, unwrapped
from offline_prog.path.process_frames import NormalField, NormalTangentError
from offline_prog.path.sources import PathPoints
from offline_prog.path.tool_turn import SmoothTurn, smooth_turn_of
from offline_prog.process.registry import process_model
from offline_prog.process.timing_bound import ProcessCaps, process_caps
from offline_prog.robot.model import RobotModel, load_robot
from offline_prog.scene.drake_cell import DrakeCell, build_cell_model
from offline_prog.scene.shapes import ShapeError
from offline_prog.timing.fallback_walk import kept_slowed, slowed_rank, walk_fallbacks
from offline_prog.timing.lead_length import fallbacks, slowed_end, with_leads
from offline_prog.timing.path_timing import PathLimits
from offline_prog.timing.trajectory import TimeLawParameter

# Grid spacing for the checks of the fitted path [m] and the largest tangent turn
# between neighbours on it before the path counts as doubling back.
CHECK_GRID_SPACING_M = 2.5e-4
MAX_TANGENT_TURN_RAD = np.deg2rad(90.0)
# Fewest grid points of that check, and of the check that frames exist everywhere
# (a short path still gets a dense look).
MIN_CHECK_POINTS = 2001


@dataclasses.dataclass
class Inputs:
    """Stage ``load``: the checked cell and what it names."""

    file: Path
    cell: Cell
    points: PathPoints | None  # None for a job (seams:); see job.seams.seam_inputs
    robot: RobotModel
    X_IB: RigidTransform  # robot base B in I
    X_IT: RigidTransform  # fixed tool T in I
    X_PE: RigidTransform  # flange E in the part P
    # The seam's process speed (config.process_speed); None for a job's (seams:) inputs.
    speed: ProcessSpeed | None = None
    # The process model's caps on the process stretch's time law (process.timing_bound);
    # False plans under the user's caps alone (the trade-off's comparison).
    process_bound: bool = True
    # The seam's normal (tangent) approach and retract distances [m] (0: another kind),
    # which its leads may take over (timing.lead_length); job.seams.seam_inputs sets them.
    normal_moves_m: tuple[float, float] = (0.0, 0.0)
    tangent_moves_m: tuple[float, float] = (0.0, 0.0)


@dataclasses.dataclass
class FittedPath:
    """Stage ``fit``: the B-spline, its arc-length path σ ↦ p_PF(σ) and the normals."""

    fitted: FittedSpline
    path: ArcLengthPath
    normal: NormalField  # normal field n(σ) in P
    normal_fit: NormalFit  # the angle from each given normal to the fitted field


@dataclasses.dataclass
class FlangePaths:
    """Stage ``frames``: the flange path for each tool rotation φ [rad], best first."""

    rotations: list[tuple[float, FlangePath]]
    cusps: list[Cusp]


def load_inputs(file: Path, robots_dir: Path, cell: Cell | None = None) -> Inputs:
    """Read and check the cell file; load the path points and the robot.

    Args:
        cell: the file's cell, already read (the API's edited cell): checked, not read
            again; ``file`` still resolves its relative paths and names it in errors.
    """
    cell = load_cell(file) if cell is None else cell
    check_cell(file, cell, robots_dir)
    points = load_points(file, cell) if cell.path is not None else None
    try:
        folders = search_path(robots_dir, cell_file=file, robots_dir=cell.robot.robots_dir)
        folder = find_robot(cell.robot.model, folders)
        robot = load_robot(cell.robot.model, folder.parent if folder else robots_dir)
    except ValueError as error:
        raise InputError(file, "robot.model", str(error)) from None
    check_process_io(file, cell, robot.language)
    check_controller_frames(file, cell, robot.language)
    return Inputs(
        file,
        cell,
        points,
        robot,
        transform(cell.robot.X_IB),
        transform(cell.tool.X_IT),
        transform(cell.part.X_PE),
        process_speed(cell, 0) if cell.path is not None else None,
        # A path: cell's seam: the default approach and retract (job.seams.job_seams).
        **(seam_moves_m(ApproachConfig(), ApproachConfig()) if cell.path is not None else {}),
    )


def _check_turns(file: Path, path: ArcLengthPath) -> None:
    """Reject paths that stop or double back (a tangent flip makes frames undefined)."""
    if path.map.min_speed <= 0.0:
        raise InputError(file, "path", "the fitted curve stops (zero tangent)")
    n = max(MIN_CHECK_POINTS, int(path.length / CHECK_GRID_SPACING_M))
    s = np.linspace(0.0, path.length, n)
    _, t = path(s, order=1)
    cos_turn = np.einsum("ij,ij->i", t[:-1], t[1:])
    worst = int(np.argmin(cos_turn))
    if cos_turn[worst] < np.cos(MAX_TANGENT_TURN_RAD):
        turn = np.rad2deg(np.arccos(np.clip(cos_turn[worst], -1.0, 1.0)))
        raise InputError(
            file,
            "path",
            f"the path stops and turns back (tangent turns {turn:.0f}° "
            f"within {s[1] * 1e3:.2f} mm at σ = {s[worst]:.4f} m); split it or "
            "check the point order",
        )


def fit_path(inputs: Inputs) -> FittedPath:
    """B-spline fit of the points (paper §2, eqs. 1–3), true arc length (§4), normals."""
    file, spec = inputs.file, inputs.cell.path
    try:
        fitted = fit_bspline(
            inputs.points.p_PR,
            closed=spec.closed,
            degree=spec.degree,
            tolerance_m=spec.fit_tolerance_mm * 1e-3,
            n_control_points=spec.n_control_points,
        )
    except ValueError as error:
        raise InputError(file, "path", str(error)) from None
    path = ArcLengthPath(fitted)
    if spec.closed and spec.overlap_mm > 0:  # the seam runs on over its first overlap_mm
        path.length += spec.overlap_mm * 1e-3
    _check_turns(file, path)
    normal = normal_field(file, inputs.cell, inputs.points, path)
    normal_fit = check_normal_fit(file, inputs.cell, inputs.points, path, normal)
    return FittedPath(fitted, path, normal, normal_fit)


def flange_paths(inputs: Inputs, fit: FittedPath) -> FlangePaths:
    """Process frames and flange paths X_IE(σ) (paper §3, eqs. 5–8), one per tool
    rotation about a symmetric tool's axis, best first; cusps of the first (§4)."""
    cell, file = inputs.cell, inputs.file
    try:
        flange = FlangePath(fit.path, fit.normal, X_IT=inputs.X_IT, X_PE=inputs.X_PE)
        flange(np.linspace(0.0, fit.path.length, MIN_CHECK_POINTS))  # frames everywhere?
        rotations = [(0.0, flange)]
        if cell.tool.free_rotation_deg > 0:
            rotations = tool_rotations(
                inputs.robot,
                inputs.X_IB,
                fit.path,
                fit.normal,
                X_IT=inputs.X_IT,
                X_PE=inputs.X_PE,
                bound_rad=np.deg2rad(cell.tool.free_rotation_deg),
                axis=cell.tool.symmetry_axis,
                smooth_turn=smooth_turn(inputs, fit),
            )
        cusps = find_cusps(rotations[0][1])
    except NormalTangentError as error:
        raise InputError(file, "path.normal", str(error)) from None
    if cell.motion.speed_reference == "flange" and any(c.kind == "cusp" for c in cusps):
        first = next(c for c in cusps if c.kind == "cusp")
        raise InputError(
            file,
            "motion.speed_reference",
            f"flange: the flange stops at a "
            f"cusp at σ = {first.sigma_m:.4f} m; use tcp or motion.cusp_smoothing_mm",
        )
    return FlangePaths(rotations, cusps)


def smooth_turn(inputs: Inputs, fit: FittedPath) -> SmoothTurn | None:
    """The tool turn that spreads the path's bends over tool.turn_smoothing_mm, if set."""
    tool = inputs.cell.tool
    if tool.turn_smoothing_mm == 0.0:
        return None
    return smooth_turn_of(
        fit.path, fit.normal, axis=tool.symmetry_axis, width_m=tool.turn_smoothing_mm * 1e-3
    )


def build_scene(inputs: Inputs) -> DrakeCell:
    """Robot, part, tool (at the cell's own X_IT) and obstacles in one Drake plant."""
    try:
        return build_cell_model(inputs.cell, inputs.file, inputs.robot)
    except ShapeError as error:
        raise InputError(inputs.file, error.key, error.reason) from None


def attempt_motion(
    inputs: Inputs, scene: DrakeCell, rotation: float, flange, branch: int | None = None
) -> Attempt:
    """One joint plan for one flange path: time law (§4), path IK on a branch, joint
    retiming (:func:`plan_motion`), and the collision check of every sample and step
    (:func:`check_attempt`).

    Raises:
        PlanFailedError: the robot cannot follow the path (σ, t and why).
    """
    return check_attempt(inputs, scene, plan_motion(inputs, rotation, flange, branch))


def first_joints(inputs: Inputs, flanges: FlangePaths) -> Attempt:
    """Stage ``joints``: :func:`plan_motion` on the first (best) tool rotation's path."""
    rotation, flange = flanges.rotations[0]
    return plan_motion(inputs, rotation, flange)


def plan_motion(
    inputs: Inputs,
    rotation: float,
    flange,
    branch: int | None = None,
    *,
    run: MotionSetup | None = None,
    branches: list | None = None,
) -> Attempt:
    """Time law (§4), path IK on a branch and joint retiming for one flange path (not
    collision-checked), under ``motion:``'s caps lowered by ``process_caps`` unless
    ``inputs.process_bound`` is False; leads that fail or are slowed (``slowed_end``)
    give way to their fallbacks (``timing.fallback_walk``); where the process model
    ``flies_slowed``, the least-slowed flying leads that ran rather than rest. ``run``,
    ``branches``: ``motion_setup`` of ``flange`` and every IK branch's verdict
    (``path_branches``), when an untimed option has them.

    Raises:
        PlanFailedError: the robot cannot follow the path (σ, t and why).
    """
    first = motion_setup(inputs, flange) if run is None else run
    v = inputs.speed.v_m_s

    def timed(run: MotionSetup):
        known = branches if run is first else None  # the verdicts are the first path's
        joints = _joint_trajectory(inputs, run, branch, known)
        return joints, slowed_end(run.flange, joints.retiming.reductions, v)

    rank = slowed_rank(process_model(inputs.cell.process), v)
    walk = walk_fallbacks(first, timed, setup=functools.partial(motion_setup, inputs), rank=rank)
    run, joints = walk.last
    if walk.missed:  # flying, slowed: the process keeps its band, at rest it would not
        run = dataclasses.replace(run, flange=kept_slowed(run.flange, walk.missed))
    return Attempt(rotation, run.flange, run.limits, joints, None)


def _joint_trajectory(inputs: Inputs, run, branch: int | None, branches: list | None = None):
    motion = inputs.cell.motion
    return plan_joint_trajectory(
        inputs.robot,
        inputs.X_IB,
        run.flange,
        run.parameter,
        run.limits,
        rate_hz=motion.sample_rate_hz,
        branch=branch,
        time_law=motion.time_law,
        process=motion.process,
        process_caps=run.caps,
        branches=branches,
    )


@dataclasses.dataclass(frozen=True)
class MotionSetup:
    """What :func:`plan_motion` runs on: the flange path as run (cusps smoothed when
    ``motion.cusp_smoothing_mm`` is set), σ ↦ s, the process model's caps and the
    path's limits (the seam's process speed, the caps, the robot's joint limits; their
    nominal law is built once, ``PathLimits.nominal``)."""

    flange: LeadPath  # over a FlangePath or SmoothedFlangePath
    parameter: TimeLawParameter
    caps: ProcessCaps
    limits: PathLimits


def motion_setup(inputs: Inputs, flange) -> MotionSetup:
    """The flange path as run, its parameter, caps and limits (:class:`MotionSetup`).

    Raises:
        InputError: ``motion.cusp_smoothing_mm`` that does not fit the path, or a plan of
            more than MAX_SAMPLES samples.
    """
    motion = inputs.cell.motion
    leads = flange if isinstance(flange, LeadPath) else None  # its entry decided
    flange = unwrapped(flange)
    if motion.cusp_smoothing_mm is not None:
        try:
            flange = SmoothedFlangePath(flange, motion.cusp_smoothing_mm * 1e-3)
        except ValueError as error:
            raise InputError(inputs.file, "motion.cusp_smoothing_mm", str(error)) from None
    speed = inputs.speed.v_m_s
    user = dict(v_process=speed, a_max=motion.max_acceleration, j_max=motion.max_jerk)
    bounded = process_caps(process_model(inputs.cell.process), **user)
    caps = bounded if inputs.process_bound else process_caps(None, **user)
    # The leads are sized for the bound either way: planned without it (the trade-off's
    # comparison), the job runs the same path, only its time law is the user's.
    flange = with_leads(inputs, flange, bounded, leads)
    parameter = TimeLawParameter(flange, motion.speed_reference)
    limits = PathLimits.of(
        inputs.robot, parameter.length, v_process=speed, a_max=caps.a_max, j_max=caps.j_max
    )
    nominal = limits.nominal
    samples = nominal.duration * max(motion.sample_rate_hz, LIMIT_CHECK_RATE_HZ)
    if samples > MAX_SAMPLES:  # memory: every sample holds poses, joints, distances
        raise InputError(
            inputs.file,
            "motion",
            f"{nominal.duration:.0f} s at {max(motion.sample_rate_hz, LIMIT_CHECK_RATE_HZ):g} Hz"
            f" is {samples:,.0f} samples, more than {MAX_SAMPLES:,}; raise "
            f"{inputs.speed.key} or lower motion.sample_rate_hz",
        )
    return MotionSetup(flange, parameter, caps, limits)


def check_attempt(inputs: Inputs, scene: DrakeCell, attempt: Attempt) -> Attempt:
    """Stage ``check``: the attempt with the collision check of every sample and step at
    the cell's clearances. A flying seam that collides is planned again with leads that
    keep their own lift (where they took a normal move over, ``timing.lead_length``),
    then at rest: the first of these that is free is the attempt."""
    checked = _checked(inputs, scene, attempt)
    if checked.collisions.collision_free or not getattr(attempt.flange, "flying", False):
        return checked
    for flange in fallbacks(attempt.flange, "the lead-in or lead-out collides"):
        try:
            retry = plan_motion(inputs, attempt.rotation, flange, attempt.joints.branch)
        except PlanFailedError:
            continue
        retry = _checked(inputs, scene, retry)
        if retry.collisions.collision_free:
            return retry
    return checked


def _checked(inputs: Inputs, scene: DrakeCell, attempt: Attempt) -> Attempt:
    motion, joints = inputs.cell.motion, attempt.joints
    collisions = check_trajectory(
        scene,
        joints.q,
        joints.trajectory.t,
        joints.trajectory.s,
        clearance=motion.clearance,
        self_clearance=motion.self_clearance,
    )
    return dataclasses.replace(attempt, collisions=collisions)


def avoid(
    inputs: Inputs,
    fit: FittedPath,
    flanges: FlangePaths,
    scene: DrakeCell,
    first: Attempt,
    progress: Callable[[str], None],
) -> tuple[Attempt, dict | None]:
    """Collision avoidance where the first plan collides: other branches and tool
    rotations, then a tool turned along the path by Drake IK with a minimum distance."""
    if first.collisions.collision_free:
        return first, None

    def attempt(rotation, flange, branch=None):
        return attempt_motion(inputs, scene, rotation, flange, branch)

    progress("collision avoidance: other tool rotations and branches")
    chosen, record = avoid_collisions(first, flanges.rotations, attempt)
    if not chosen.collisions.collision_free and inputs.cell.tool.free_rotation_deg > 0:
        progress("collision avoidance: Drake IK with a minimum-distance constraint")
        chosen = turn_tool_along_path(chosen, record, attempt, scene, fit.path, fit.normal, inputs)
    return chosen, record
