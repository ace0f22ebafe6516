"""The planning pipeline: cell file → processing path → flange trajectory → files.

Each stage lives in its own module (bspline_fit, arc_length, process_frames,
fixed_tcp, time_law, trajectory, cusps); this module checks what the cell asks
for, runs the stages in order, and turns stage failures into PlanErrors that
name the cell file and key.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from offline_prog.arc_length import ArcLengthPath
from offline_prog.avoidance import Attempt, avoid_collisions, turn_profile
from offline_prog.bspline_fit import FittedSpline, fit_bspline
from offline_prog.cell import Cell, CellError, load_cell, transform
from offline_prog.collision import CollisionResult, check_trajectory, distance_profile
from offline_prog.cusps import Cusp, SmoothedFlangePath, find_cusps
from offline_prog.drake_cell import build_cell_model
from offline_prog.fixed_tcp import FlangePath
from offline_prog.geometry import ShapeError
from offline_prog.inputs import check_cell, load_points, normal_field
from offline_prog.joint_plan import (
    JointPlanError,
    JointTrajectory,
    plan_joint_trajectory,
    tool_rotations,
)
from offline_prog.path_sources import PathPoints
from offline_prog.process_frames import NormalTangentError
from offline_prog.robot_model import ROBOTS_DIR, RobotModel, load_robot
from offline_prog.time_law import sin2_time_law
from offline_prog.trajectory import TimeLawParameter, WorkspaceTrajectory

log = logging.getLogger(__name__)

# Grid spacing for the checks of the fitted path [m] and the largest tangent turn
# between neighbours on it before the path counts as doubling back.
CHECK_GRID_SPACING_M = 2.5e-4
MAX_TANGENT_TURN_RAD = np.deg2rad(90.0)


@dataclasses.dataclass
class Plan:
    """Everything a plan produced, for the writers and the tests."""

    cell_file: Path
    cell: Cell
    points: PathPoints
    fitted: FittedSpline
    path: ArcLengthPath
    flange: FlangePath | SmoothedFlangePath
    trajectory: WorkspaceTrajectory
    cusps: list[Cusp]
    timings_s: dict[str, float]
    robot: RobotModel
    joints: JointTrajectory
    nominal_duration_s: float
    tool_rotation_rad: float
    collisions: CollisionResult
    avoidance: dict | None = None  # what the collision avoidance tried and changed
    # (t_k, {pair group: smallest distance [m]}) for the distance-over-time plot.
    clearance_profile: tuple | None = None

    @property
    def feasible(self) -> bool:
        """Every check passed (collision-free at the clearance)."""
        return self.collisions.collision_free

    @property
    def failure(self) -> str:
        """Why the plan failed, one line ("" if it did not)."""
        return self.collisions.message


class PlanInfeasibleError(CellError):
    """The cell is valid but the robot cannot do the path (σ, t and why)."""

    def __init__(self, file: Path, reason: str):
        super().__init__(file, "", reason)


def _check_turns(file: Path, path: ArcLengthPath) -> None:
    """Reject paths that stop or double back (a tangent flip makes frames undefined)."""
    if path.map.min_speed <= 0.0:
        raise CellError(file, "path", "the fitted curve stops (zero tangent)")
    s = np.linspace(0.0, path.length, max(2001, int(path.length / CHECK_GRID_SPACING_M)))
    _, t = path(s, order=1)
    cos_turn = np.einsum("ij,ij->i", t[:-1], t[1:])
    worst = int(np.argmin(cos_turn))
    if cos_turn[worst] < np.cos(MAX_TANGENT_TURN_RAD):
        turn = np.rad2deg(np.arccos(np.clip(cos_turn[worst], -1.0, 1.0)))
        raise CellError(
            file,
            "path",
            f"the path stops and turns back (tangent turns {turn:.0f}° "
            f"within {s[1] * 1e3:.2f} mm at σ = {s[worst]:.4f} m); split it or "
            "check the point order",
        )


def plan_cell(
    cell_file: str | Path,
    *,
    robots_dir: Path = ROBOTS_DIR,
    progress: Callable[[str], None] = lambda stage: None,
) -> Plan:
    """Run the fixed-TCP pipeline on a cell file (paper §§2–4).

    Args:
        cell_file: the cell YAML.
        robots_dir: folder of robot descriptions.
        progress: called with the name of each stage as it starts.

    Raises:
        CellError: bad input or geometry the method cannot handle (one line).
    """
    file = Path(cell_file)
    timings: dict[str, float] = {}
    clock = time.perf_counter()

    def lap(name, next_stage=None):
        nonlocal clock
        now = time.perf_counter()
        timings[name] = now - clock
        clock = now
        if next_stage:
            progress(next_stage)

    progress("reading the cell")

    cell = load_cell(file)
    check_cell(file, cell, robots_dir)
    points = load_points(file, cell)
    lap("load", "fitting the B-spline")
    try:
        fitted = fit_bspline(
            points.p_PR,
            closed=cell.path.closed,
            degree=cell.path.degree,
            tolerance_m=cell.path.fit_tolerance_mm * 1e-3,
            n_control_points=cell.path.n_control_points,
        )
    except ValueError as error:
        raise CellError(file, "path", str(error)) from None
    path = ArcLengthPath(fitted)
    _check_turns(file, path)
    lap("fit", "process frames and flange path")
    normal = normal_field(file, cell, points, path)
    X_IT, X_PE = transform(cell.tool.X_IT), transform(cell.part.X_PE)
    try:
        robot = load_robot(cell.robot.model, robots_dir)
    except ValueError as error:
        raise CellError(file, "robot.model", str(error)) from None
    X_IB = transform(cell.robot.X_IB)
    try:
        flange = FlangePath(path, normal, X_IT=X_IT, X_PE=X_PE)
        flange(np.linspace(0.0, path.length, 2001))  # frames defined everywhere?
        rotations = [(0.0, flange)]
        if cell.tool.free_rotation_deg > 0:
            rotations = tool_rotations(
                robot,
                X_IB,
                path,
                normal,
                X_IT=X_IT,
                X_PE=X_PE,
                bound_rad=np.deg2rad(cell.tool.free_rotation_deg),
                axis=cell.tool.symmetry_axis,
            )
        rotation, flange = rotations[0]
        cusps = find_cusps(flange)
    except NormalTangentError as error:
        raise CellError(file, "path.normal", str(error)) from None
    motion = cell.motion
    if motion.speed_reference == "flange" and any(c.kind == "cusp" for c in cusps):
        first = next(c for c in cusps if c.kind == "cusp")
        raise CellError(
            file,
            "motion.speed_reference",
            f"flange: the flange stops at a "
            f"cusp at σ = {first.sigma_m:.4f} m; use tcp or motion.cusp_smoothing_mm",
        )
    lap("frames", "joint trajectory within the robot's limits")
    try:
        drake = build_cell_model(cell, file, robot)  # the tool at the cell's own X_IT
    except ShapeError as error:
        raise CellError(file, error.key, error.reason) from None

    def attempt(rotation: float, flange, branch: int | None = None) -> Attempt:
        if motion.cusp_smoothing_mm is not None:
            try:
                flange = SmoothedFlangePath(flange, motion.cusp_smoothing_mm * 1e-3)
            except ValueError as error:
                raise CellError(file, "motion.cusp_smoothing_mm", str(error)) from None
        parameter = TimeLawParameter(flange, motion.speed_reference)
        nominal = sin2_time_law(
            parameter.length,
            v_max=motion.speed,
            a_max=motion.max_acceleration,
            j_max=motion.max_jerk,
        )
        joints = plan_joint_trajectory(
            robot, X_IB, flange, parameter, nominal, rate_hz=motion.sample_rate_hz, branch=branch
        )
        traj = joints.trajectory
        collisions = check_trajectory(
            drake, joints.q, traj.t, traj.sigma, clearance=motion.clearance
        )
        return Attempt(rotation, flange, nominal, joints, collisions)

    try:
        chosen = attempt(rotation, flange)
    except JointPlanError as error:
        raise PlanInfeasibleError(file, str(error)) from None
    lap("joints", "collision check")
    avoidance = None
    if not chosen.collisions.collision_free:
        progress("collision avoidance: other tool rotations and branches")
        chosen, avoidance = avoid_collisions(chosen, rotations, attempt)
    if not chosen.collisions.collision_free and cell.tool.free_rotation_deg > 0:
        progress("collision avoidance: Drake IK with a minimum-distance constraint")
        axis = np.eye(3)["xyz".index(cell.tool.symmetry_axis)]
        turn = turn_profile(
            drake,
            path,
            normal,
            X_IT=X_IT,
            s_plan=chosen.joints.trajectory.s,
            q_plan=chosen.joints.q,
            axis=axis,
            bound_rad=np.deg2rad(cell.tool.free_rotation_deg),
            clearance=motion.clearance,
        )
        if turn is not None:
            turned = FlangePath(path, normal, X_IT=X_IT, X_PE=X_PE, tool_turn=turn, axis=axis)
            phi = turn(np.linspace(0.0, path.length, 200))[0]
            try:
                trial = attempt(float(phi[0]), turned)
            except JointPlanError:
                trial = None
            avoidance["attempts"] += 1
            if trial is not None and trial.collisions.collision_free:
                chosen = trial
                avoidance["resolved"] = True
                avoidance["change"] = (
                    "tool turned along the path (Drake IK with a minimum-distance "
                    f"constraint): φ from {np.rad2deg(phi.min()):.1f}° to "
                    f"{np.rad2deg(phi.max()):.1f}°"
                )
    traj = chosen.joints.trajectory
    profile = distance_profile(drake, chosen.joints.q, traj.t)
    lap("collision")
    return Plan(
        file,
        cell,
        points,
        fitted,
        path,
        chosen.flange,
        chosen.joints.trajectory,
        cusps,
        timings,
        robot,
        chosen.joints,
        chosen.nominal.duration,
        chosen.rotation,
        chosen.collisions,
        avoidance,
        profile,
    )
