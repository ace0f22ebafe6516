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

import time
from collections.abc import Callable
from pathlib import Path

from offline_prog.collision.avoidance import Attempt
from offline_prog.collision.profile import distance_profile
from offline_prog.errors import InputError, PlanFailedError
from offline_prog.job.assemble import lay_out
from offline_prog.job.process_io import IoPlacementError, io_columns
from offline_prog.job.records import JobPlan, Plan
from offline_prog.job.stages import (
    check_job,
    choose_order,
    home_pose,
    job_pieces,
    seam_options,
    tool_speed,
)
from offline_prog.joints.path_timing import without_joint_limits
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.scene.drake_cell import DrakeCell
from offline_prog.stages import (
    FittedPath,
    FlangePaths,
    Inputs,
    attempt_motion,
    avoid,
    build_scene,
    fit_path,
    flange_paths,
    load_inputs,
    with_normal_hint,
)


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
    stage = StageTimer(progress)
    inputs = stage("load", "reading the cell", load_inputs, file, robots_dir)
    scene = stage("scene", "building the Drake cell", build_scene, inputs)
    return plan_seam(inputs, scene, stage)


class StageTimer:
    """Runs named stages, tells ``progress`` and keeps each stage's wall time [s]."""

    def __init__(self, progress: Callable[[str], None], prefix: str = ""):
        self.progress, self.prefix, self.timings_s = progress, prefix, {}

    def __call__(self, name: str, description: str, function, *args):
        self.progress(description)
        start = time.perf_counter()
        result = function(*args)
        key = self.prefix + name
        self.timings_s[key] = self.timings_s.get(key, 0.0) + time.perf_counter() - start
        return result


def plan_seam(
    inputs: Inputs, scene: DrakeCell, stage: StageTimer, *, clearance_profile: bool = True
) -> Plan:
    """The single-seam pipeline on loaded inputs and a built scene: fit, frames, joints,
    collision avoidance, clearance profile unless told not to (paper §§2–4)."""
    fit = stage("fit", "fitting the B-spline", fit_path, inputs)
    flanges = stage("frames", "process frames and flange path", flange_paths, inputs, fit)
    return plan_flanges(inputs, scene, fit, flanges, stage, clearance_profile=clearance_profile)


def plan_flanges(
    inputs: Inputs, scene: DrakeCell, fit: FittedPath, flanges: FlangePaths, stage: StageTimer,
    *, first: Attempt | None = None, clearance_profile: bool = True,
) -> Plan:  # fmt: skip
    """:func:`plan_seam` after the flange paths: joints (or the caller's ``first`` joint
    plan), collision avoidance, and the clearance profile unless told not to."""
    file = inputs.file
    rotation, flange = flanges.rotations[0]
    try:
        first = first or stage(
            "joints", "joint trajectory and collision check", attempt_motion, inputs, scene,
            rotation, flange,
        )  # fmt: skip
    except PlanFailedError as error:
        raise with_normal_hint(error, inputs, fit, scene) from None
    chosen, avoidance = stage(
        "collision", "collision avoidance", avoid, inputs, fit, flanges, scene, first,
        stage.progress,
    )  # fmt: skip
    traj = chosen.joints.trajectory
    profile = None
    if clearance_profile:
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
        stage.timings_s,
        inputs.robot,
        chosen.joints,
        without_joint_limits(chosen.nominal, inputs.cell.motion.time_law)[0],
        chosen.rotation,
        chosen.collisions,
        avoidance,
        profile,
        fit.normal_fit,
    )


def plan_job(
    cell_file: str | Path,
    *,
    robots_dir: Path = ROBOTS_DIR,
    progress: Callable[[str], None] = lambda stage: None,
) -> JobPlan:
    """A whole job (issue 13): every seam by the one-seam pipeline, approach and
    retract, seam order, collision-free links from home and back, process I/O, and the
    collision check of the whole job.

    Raises:
        InputError: bad input (one line; exit 2).
        PlanFailedError: a seam the robot cannot do, or a link not found (exit 1).
    """
    stage = StageTimer(progress)
    inputs = stage("load", "reading the cell", load_inputs, Path(cell_file), robots_dir)
    return plan_loaded_job(inputs, stage)


def plan_loaded_job(
    inputs: Inputs,
    stage: StageTimer,
    *,
    clearance_profile: bool = True,
    fits: dict[tuple[int, bool], FittedPath] | None = None,
) -> JobPlan:
    """:func:`plan_job` on loaded inputs (a placement candidate's cell, in memory).

    Args:
        clearance_profile: compute the whole job's clearance profile (clearance.csv).
        fits: (seam index, reversed) ↦ the seam's fitted path, kept by the caller: a
            fit found here is used, one computed here is added (a path on the part does
            not change with the placement).
    """
    progress = stage.progress
    scene = stage("scene", "building the Drake cell", build_scene, inputs)
    q_home = stage("home", "checking the home pose", home_pose, inputs, scene)
    fits = {} if fits is None else fits

    def one_seam(k: int, reverse: bool, seam_inputs: Inputs, seam_scene: DrakeCell) -> Plan:
        seam_stage = StageTimer(progress)
        if (k, reverse) not in fits:
            fits[k, reverse] = seam_stage("fit", "fitting the B-spline", fit_path, seam_inputs)
        fit = fits[k, reverse]
        flanges = seam_stage(
            "frames", "process frames and flange path", flange_paths, seam_inputs, fit
        )
        return plan_flanges(
            seam_inputs, seam_scene, fit, flanges, seam_stage, clearance_profile=False
        )

    options = stage("seams", "planning the seams", seam_options, inputs, scene, one_seam, progress)
    order = stage("order", "choosing the seam order", choose_order, inputs, options, q_home)
    flat = [option for seam in options for option in seam]
    chosen = [flat[i] for i in order.sequence]
    pieces, links = stage(
        "links", "linking moves", job_pieces, inputs, scene, chosen, q_home, progress
    )
    samples = lay_out(pieces)
    tcp_speed = tool_speed(inputs, samples, chosen)
    lengths = {option.name: option.plan.path.length for option in chosen}
    try:
        io = io_columns(samples, inputs.cell.tool.process_io, lengths, tcp_speed)
    except IoPlacementError as error:
        raise InputError(inputs.file, error.key, error.reason) from None
    collisions = stage(
        "check", "collision check of the whole job", check_job, inputs, scene, samples
    )
    profile = None
    if clearance_profile:
        profile = stage(
            "clearance", "clearance profile", distance_profile, scene, samples.q, samples.t
        )
    return JobPlan(
        inputs.file, inputs.cell, inputs.robot, q_home, options, chosen, order, links, samples,
        tcp_speed, io, collisions, stage.timings_s, profile,
    )  # fmt: skip
