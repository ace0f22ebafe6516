"""The session's pipeline: :func:`~offline_prog.plan.plan_seam` with each stage cached
on exactly the parameters it reads, so a change re-runs only what it invalidates.

=================  =====================================================  ==============
stage              reads                                                  re-run when
=================  =====================================================  ==============
load               the cell file, the path points, the robot              never (once)
fit                the path points of the active seam                     seam
frames             fit, X_IT, X_PE, free tool rotation                    + X_IT, X_PE,
                                                                          free rotation
scene              X_IT (tool welded), X_PE (part welded to the flange)   X_IT, X_PE
joints             frames, the process speed                              + speed
check              joints, scene, the clearance                           + clearance
=================  =====================================================  ==============

A clearance change keeps the joint trajectory and re-runs only its collision check;
collision avoidance (when the first joint plan collides) follows as in ``plan``. The
clearance profile (a plot of the plan folder) is computed on export only.

``progress`` is called between stages with the stage's description; it may raise
:class:`SupersededError` (a newer request is waiting), which ends the plan there.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from pathlib import Path

from offline_prog.collision.avoidance import Attempt
from offline_prog.collision.check import check_trajectory
from offline_prog.config.cell import Cell, transform
from offline_prog.config.checks import check_cell
from offline_prog.config.edits import CellValues, apply, initial_values
from offline_prog.errors import InputError, PlanFailedError, PlanFailure
from offline_prog.job.records import Plan
from offline_prog.job.seams import job_seams, seam_inputs
from offline_prog.plan import StageTimer, plan_flanges
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import (
    Inputs,
    attempt_motion,
    build_scene,
    fit_path,
    flange_paths,
    load_inputs,
    with_normal_hint,
)


class SupersededError(Exception):
    """A newer request replaced the one being planned."""


@dataclasses.dataclass
class SessionPlan:
    """The answer to one request: the plan, or why there is none.

    Attributes:
        state: the parameters planned.
        cell: the cell they make.
        plan: the Plan (feasible or failing its collision check), or None.
        failure: the PlanFailure (σ, t, why) when the joints could not be planned.
        error: the one-line reason when there is no plan (a failure or bad input).
        ran: the stages that ran (the others were reused), in order.
        seconds: wall time of the request [s].
        scene: the Drake cell the plan was checked in (None without a plan).
    """

    state: CellValues
    cell: Cell
    plan: Plan | None
    failure: PlanFailure | None
    error: str
    ran: list[str]
    seconds: float
    scene: object = None


class Replanner:
    """The cached pipeline of one cell file (one seam of it at a time).

    Not thread-safe: one worker thread plans.
    """

    def __init__(self, cell_file: Path, robots_dir: Path = ROBOTS_DIR):
        self.file, self.robots_dir = Path(cell_file), robots_dir
        start = time.perf_counter()
        self.base = load_inputs(self.file, robots_dir)
        self.seam_names = [seam.name for seam in job_seams(self.base.cell)]
        self.initial = initial_values(self.base.cell)
        # Each stage's last run [s] (report.json of an export lists them).
        self.timings_s = {"load": time.perf_counter() - start}
        self._seams: dict[int, Inputs] = {}  # the original cell's seam inputs
        self._fits: dict[int, object] = {}
        self._cache: dict[str, tuple] = {}  # stage -> (key, value)

    def cell(self, state: CellValues) -> Cell:
        return apply(self.base.cell, self.initial, state)

    def inputs(self, state: CellValues) -> Inputs:
        """The active seam's Inputs for ``state`` (the cell's checks run again).

        Raises:
            InputError: the state makes a cell that ``plan`` would refuse.
        """
        cell = self.cell(state)
        check_cell(self.file, cell, self.robots_dir)
        poses = {"X_IT": transform(cell.tool.X_IT), "X_PE": transform(cell.part.X_PE)}
        k = state.seam
        if k not in self._seams:  # the seam's points are read once
            self._seams[k] = seam_inputs(self.base, k)
        seam = self._seams[k]
        motion = dataclasses.replace(cell.motion, speed=state.speed)
        seam_cell = dataclasses.replace(seam.cell, tool=cell.tool, part=cell.part, motion=motion)
        return dataclasses.replace(seam, cell=seam_cell, **poses)

    def _cached(self, stage: str, key: tuple, compute: Callable):
        """The stage's value for ``key``: kept, or computed (a PlanFailedError too)."""
        kept = self._cache.get(stage)
        if kept is None or kept[0] != key:
            try:
                kept = (key, compute(), None)
            except PlanFailedError as error:
                kept = (key, None, error)
            self._cache[stage] = kept
        if kept[2] is not None:
            raise kept[2]
        return kept[1]

    def plan(
        self, state: CellValues, progress: Callable[[str], None] = lambda stage: None
    ) -> SessionPlan:
        """Plan the state's active seam, reusing every stage whose inputs did not change.

        Raises:
            SupersededError: from ``progress``.
        """
        start = time.perf_counter()
        stage = StageTimer(progress)
        cell = self.cell(state)
        try:
            plan, scene = self._plan(state, stage)
            failure, error = None, ""
        except PlanFailedError as failed:
            plan, scene, failure, error = None, None, failed.failure, str(failed)
        except InputError as bad:
            plan, scene, failure, error = None, None, None, str(bad)
        self.timings_s.update(stage.timings_s)
        # "collision" always runs; it does work only when the first plan collides.
        ran = [name for name in stage.timings_s if name != "collision"]
        if plan is not None and plan.avoidance is not None:
            ran.append("avoidance")
        seconds = time.perf_counter() - start
        return SessionPlan(state, cell, plan, failure, error, ran, seconds, scene)

    def _plan(self, state: CellValues, stage: StageTimer) -> tuple[Plan, object]:
        inputs = self.inputs(state)
        k = state.seam
        if k not in self._fits:
            self._fits[k] = stage("fit", "fitting the B-spline", fit_path, inputs)
        fit = self._fits[k]
        poses = (state.p_IT, state.rpy_IT_deg, state.p_PE, state.rpy_PE_deg)
        frames_key = (k, *poses, state.free_rotation_deg, state.turn_smoothing_mm)
        flanges = self._cached("frames", frames_key, lambda: stage(
            "frames", "process frames and flange path", flange_paths, inputs, fit))  # fmt: skip
        scene = self._cached("scene", poses, lambda: stage(
            "scene", "building the Drake cell", build_scene, inputs))  # fmt: skip
        rotation, flange = flanges.rotations[0]

        def joints() -> Attempt:
            return stage("joints", "joint trajectory and collision check", attempt_motion,
                         inputs, scene, rotation, flange)  # fmt: skip

        joints_key = (*frames_key, state.speed)
        kept = self._cache.get("first")
        try:
            if kept and kept[0] == joints_key and kept[1] is not None:
                first = kept[1]
                if first.collisions.clearance_m != state.clearance:
                    first = stage("check", "collision check", recheck, inputs, scene, first)
            else:
                first = self._cached("first", joints_key, joints)
            self._cache["first"] = (joints_key, first, None)
        except PlanFailedError as error:
            raise with_normal_hint(error, inputs, fit, scene) from None
        stage.progress("collision avoidance and results")
        plan = plan_flanges(inputs, scene, fit, flanges, stage, first=first,
                            clearance_profile=False)  # fmt: skip
        return plan, scene


def recheck(inputs: Inputs, scene, attempt: Attempt) -> Attempt:
    """``attempt`` with its collision check run again at the cell's clearances (the
    check that :func:`~offline_prog.stages.attempt_motion` ends with)."""
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
