"""The planning pipeline: cell file → processing path → flange path → joints → checks.

:func:`plan_cell` reads as the paper's method, one named stage per line (Drake's
``hardware_sim.run`` is the model); each stage is a function with typed inputs and
outputs, and the stage timings in report.json fall out of that list:

1. ``load``: the cell file, its semantic checks, the path points, the robot (§2).
2. ``fit``: B-spline fit (degree ≥ 5) re-parameterized by true arc length (§2, §4).
3. ``frames``: process frames [t n b] and the flange path X_IE = X_IT · X_PF⁻¹ · X_PE,
   for each free tool rotation; cusps (§3, §4).
4. ``scene``: robot, part, tool and obstacles as a Drake MultibodyPlant.
5. ``joints``: time law, path IK, joint-limit retiming and the collision check.
6. ``collision``: collision avoidance where the first plan collides; clearance profile.

Bad input is an :class:`~offline_prog.errors.InputError` naming the file and key; a
valid cell the robot cannot do is a :class:`~offline_prog.errors.PlanFailedError`
(joints) or a :class:`Plan` whose ``failure`` says why (a collision: the reports are
still written).
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable
from pathlib import Path

from offline_prog.collision.check import CollisionResult
from offline_prog.collision.profile import distance_profile
from offline_prog.config.cell import Cell
from offline_prog.errors import Failure, PlanFailedError
from offline_prog.joints.joint_plan import JointTrajectory
from offline_prog.path.arc_length import ArcLengthPath
from offline_prog.path.bspline_fit import FittedSpline
from offline_prog.path.cusps import Cusp, SmoothedFlangePath
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.path.inputs import NormalFit
from offline_prog.path.sources import PathPoints
from offline_prog.robot.model import ROBOTS_DIR, RobotModel
from offline_prog.stages import (
    attempt_motion,
    avoid,
    build_scene,
    fit_path,
    flange_paths,
    load_inputs,
    with_normal_hint,
)
from offline_prog.timing.trajectory import WorkspaceTrajectory

log = logging.getLogger(__name__)


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
    normal_fit: NormalFit | None = None  # given normals vs the fitted normal field

    @property
    def feasible(self) -> bool:
        """Every check passed (collision-free at the clearance)."""
        return self.collisions.collision_free

    @property
    def failure(self) -> str:
        """Why the plan failed, one line ("" if it did not)."""
        return self.collisions.message

    @property
    def failure_kind(self) -> Failure | None:
        """The Failure of a finished plan that fails a check (a collision), or None.
        Failures that leave no plan (reach, limits, singularities) are PlanFailedErrors."""
        return None if self.feasible else Failure.COLLISION


def plan_cell(
    cell_file: str | Path,
    *,
    robots_dir: Path = ROBOTS_DIR,
    progress: Callable[[str], None] = lambda stage: None,
) -> Plan:
    """Run the fixed-TCP pipeline on a cell file (paper §§2–4), stage by stage.

    Args:
        cell_file: the cell YAML.
        robots_dir: folder of robot descriptions.
        progress: called with the name of each stage as it starts.

    Raises:
        InputError: bad input or geometry the method cannot handle (one line).
        PlanFailedError: the robot cannot follow the path (σ, t and why).
    """
    file = Path(cell_file)
    timings: dict[str, float] = {}

    def stage(name: str, description: str, function, *args):
        progress(description)
        start = time.perf_counter()
        result = function(*args)
        timings[name] = time.perf_counter() - start
        return result

    inputs = stage("load", "reading the cell", load_inputs, file, robots_dir)
    fit = stage("fit", "fitting the B-spline", fit_path, inputs)
    flanges = stage("frames", "process frames and flange path", flange_paths, inputs, fit)
    scene = stage("scene", "building the Drake cell", build_scene, inputs)
    rotation, flange = flanges.rotations[0]
    try:
        first = stage(
            "joints", "joint trajectory and collision check", attempt_motion, inputs, scene,
            rotation, flange,
        )  # fmt: skip
    except PlanFailedError as error:
        raise with_normal_hint(error, inputs, fit, scene) from None
    chosen, avoidance = stage(
        "collision", "collision avoidance", avoid, inputs, fit, flanges, scene, first, progress
    )
    traj = chosen.joints.trajectory
    profile = stage(
        "clearance", "clearance profile", distance_profile, scene, chosen.joints.q, traj.t
    )
    return Plan(
        file,
        inputs.cell,
        inputs.points,
        fit.fitted,
        fit.path,
        chosen.flange,
        traj,
        flanges.cusps,
        timings,
        inputs.robot,
        chosen.joints,
        chosen.nominal.duration,
        chosen.rotation,
        chosen.collisions,
        avoidance,
        profile,
        fit.normal_fit,
    )
