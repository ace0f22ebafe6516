"""The session's pipeline: :func:`~offline_prog.plan.plan_seam` on the active seam, each
stage of :data:`~offline_prog.pipeline.SEAM_STAGES` kept in a
:class:`~offline_prog.pipeline.StageCache` and run again only when a value it depends on
changed (the table in :mod:`offline_prog.pipeline`): a speed change keeps the fit, the
flange paths and the Drake cell; a clearance change keeps the joint trajectory and
runs only its collision check; a tool move refits nothing. Collision avoidance (when
the first joint plan collides) follows as in ``plan``. The cell file is loaded once;
the clearance profile (a plot of the plan folder) is computed on export only.

``progress`` is called between stages with the stage's description; it may raise
:class:`SupersededError` (a newer request is waiting), which ends the plan there.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from pathlib import Path

from offline_prog.config.cell import Cell, transform
from offline_prog.config.checks import check_cell
from offline_prog.config.edits import CellValues, apply, initial_values
from offline_prog.config.process_speed import process_speed
from offline_prog.errors import InputError, PlanFailedError, PlanFailure
from offline_prog.job.records import Plan
from offline_prog.job.seams import job_seams, seam_inputs
from offline_prog.pipeline import StageCache
from offline_prog.plan import StageTimer, plan_seam
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.scene.drake_cell import DrakeCell
from offline_prog.session.heap import keep_freed_memory
from offline_prog.stages import Inputs, load_inputs


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
    scene: DrakeCell | None = None


class Replanner:
    """The cached pipeline of one cell file (one seam of it at a time).

    Not thread-safe: one worker thread plans.
    """

    def __init__(self, cell_file: Path, robots_dir: Path = ROBOTS_DIR):
        self.file, self.robots_dir = Path(cell_file), robots_dir
        keep_freed_memory()  # re-plans reuse their arrays' memory (session.heap)
        start = time.perf_counter()
        self.base = load_inputs(self.file, robots_dir)
        self.seam_names = [seam.name for seam in job_seams(self.base.cell)]
        self.initial = initial_values(self.base.cell)
        # Each stage's last run [s] (report.json of an export lists them).
        self.timings_s = {"load": time.perf_counter() - start}
        self._seams: dict[int, Inputs] = {}  # the original cell's seam inputs
        self.cache = StageCache()  # each stage's last result and the values it read

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
        seam_cell = dataclasses.replace(
            seam.cell, tool=cell.tool, part=cell.part, motion=cell.motion
        )
        return dataclasses.replace(seam, cell=seam_cell, speed=process_speed(cell, k), **poses)

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

    def _plan(self, state: CellValues, stage: StageTimer) -> tuple[Plan, DrakeCell]:
        results = {}
        plan = plan_seam(
            self.inputs(state),
            stage,
            results=results,
            cache=self.cache,
            values=state,
            clearance_profile=False,
        )
        return plan, results["scene"]
