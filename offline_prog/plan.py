"""The planning pipeline: cell file → processing path → flange path → joints → checks,
and the whole job around the seams.

Every cell is planned by :func:`plan_job` (a ``path:`` cell is a one-seam job), whose
stages read as the method, one named stage per line (Drake's ``hardware_sim.run`` is
the model), and whose stage timings in report.json fall out of that list:

1. ``load``: the cell file, its semantic checks, the path points, the robot (§2).
2. ``scene``: robot, part, tool and obstacles as a Drake MultibodyPlant.
3. ``home``: the home pose, inside the limits and collision-free.
4. ``seams``: each seam in each direction by :func:`plan_seam`, i.e. the stages of
   :data:`~offline_prog.pipeline.SEAM_STAGES` (fit §2, §4; frames and flange path
   X_IE = X_IT · X_PF⁻¹ · X_PE §3; joints: time law, path IK, retiming §4; the
   collision check; collision avoidance), with approach and retract.
5. ``order``, ``links``: the seam order; collision-free links from home and back.
6. ``check``: the whole job's collision check; ``clearance``: its clearance profile.

:func:`plan_cell` runs one seam alone (no home, approach or links): the session's
preview and the tests of the seam's method.

Bad input is an :class:`~offline_prog.errors.InputError` naming the file and key; a
valid cell the robot cannot do is a :class:`~offline_prog.errors.PlanFailedError`
(joints) or a plan whose ``failure`` says why (a collision: the reports are still
written).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from offline_prog.collision.profile import distance_profile
from offline_prog.config.cell import Cell
from offline_prog.config.edits import CellValues
from offline_prog.errors import PlanFailedError
from offline_prog.forked import quiet
from offline_prog.job.records import JobPlan, Plan
from offline_prog.pipeline import (
    JOB_CHECK,
    JOB_CLEARANCE,
    JOB_STAGES,
    SEAM_STAGES,
    StageCache,
    run_side_by_side,
    run_stages,
    with_normal_hint,
)
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.scene.drake_cell import DrakeCell
from offline_prog.stages import FittedPath, Inputs, load_inputs


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
    stage = StageTimer(progress)
    inputs = stage("load", "reading the cell", load_inputs, Path(cell_file), robots_dir)
    return plan_seam(inputs, stage)


class StageTimer:
    """Runs named stages, tells ``progress`` and keeps each stage's wall time [s]."""

    def __init__(self, progress: Callable[[str], None], prefix: str = ""):
        self.progress, self.prefix, self.timings_s = progress, prefix, {}

    def __call__(self, name: str, description: str, function, *args):
        self.progress(description)
        start = time.perf_counter()
        result = function(*args)
        self.add(name, time.perf_counter() - start)
        return result

    def add(self, name: str, seconds: float) -> None:
        """Count ``seconds`` [s] of wall time to stage ``name`` (one run elsewhere)."""
        key = self.prefix + name
        self.timings_s[key] = self.timings_s.get(key, 0.0) + seconds


def plan_seam(
    inputs: Inputs,
    stage: StageTimer,
    *,
    results: dict[str, object] | None = None,
    cache: StageCache | None = None,
    values: CellValues | None = None,
    clearance_profile: bool = True,
) -> Plan:
    """The single-seam pipeline (paper §§2–4): :data:`~offline_prog.pipeline.SEAM_STAGES`
    (fit, frames, scene, joints, check, collision avoidance), then the clearance profile
    unless told not to.

    Args:
        results: results the caller holds (a built ``scene``, a kept ``fit``); every
            stage's result is added to it.
        cache, values: the session's: reuse each stage while the values it depends on
            are unchanged (:func:`~offline_prog.pipeline.run_stages`).

    Raises:
        PlanFailedError: the robot cannot follow the path (σ, t and why; with a hint
            when the path's normals reversed would work).
    """
    results = {} if results is None else results
    results.update(inputs=inputs, progress=stage.progress)
    try:
        run_stages(SEAM_STAGES, results, stage, cache=cache, values=values)
    except PlanFailedError as error:
        if "joints" in results or "scene" not in results:
            raise
        raise with_normal_hint(error, inputs, results["fit"], results["scene"]) from None
    fit, flanges, scene = results["fit"], results["frames"], results["scene"]
    chosen, avoidance = results["collision"]
    profile = None
    if clearance_profile:
        profile = stage(
            "clearance",
            "clearance profile",
            distance_profile,
            scene,
            chosen.joints.q,
            chosen.joints.trajectory.t,
        )
    return Plan.of_attempt(
        inputs,
        fit,
        flanges,
        chosen,
        timings_s=stage.timings_s,
        avoidance=avoidance,
        clearance_profile=profile,
    )


def plan_job(
    cell_file: str | Path,
    *,
    robots_dir: Path = ROBOTS_DIR,
    progress: Callable[[str], None] = lambda stage: None,
    cell: Cell | None = None,
) -> JobPlan:
    """A whole job (issue 13): every seam by the one-seam pipeline, approach and
    retract, seam order, collision-free links from home and back, process I/O, and the
    collision check of the whole job.

    Args:
        cell: the file's cell, already read (the API's edited cell); ``cell_file``
            still resolves its relative paths and names it.

    Raises:
        InputError: bad input (one line; exit 2).
        PlanFailedError: a seam the robot cannot do, or a link not found (exit 1).
    """
    stage = StageTimer(progress)
    inputs = stage("load", "reading the cell", load_inputs, Path(cell_file), robots_dir, cell)
    return plan_loaded_job(inputs, stage, parallel=True)


def plan_loaded_job(
    inputs: Inputs,
    stage: StageTimer,
    *,
    clearance_profile: bool = True,
    fits: dict[tuple[int, bool], FittedPath] | None = None,
    parallel: bool = False,
) -> JobPlan:
    """:func:`plan_job` on loaded inputs (a placement candidate's cell, in memory).

    Args:
        clearance_profile: compute the whole job's clearance profile (clearance.csv).
        fits: (seam index, reversed) ↦ the seam's fitted path, kept by the caller: a
            fit found here is used, one computed here is added (a path on the part does
            not change with the placement).
        parallel: plan the seams on a forked second process too (``forked``; not for
            placement, whose workers already take every core).
    """
    fits = {} if fits is None else fits
    planner = SeamPlanner(stage.progress, fits, parallel=parallel)
    results = {"inputs": inputs, "progress": stage.progress, "seam_planner": planner}
    if clearance_profile and parallel:  # the check and the profile: one on each core
        run_stages(JOB_STAGES[: JOB_STAGES.index(JOB_CHECK)], results, stage)
        run_side_by_side((JOB_CHECK, JOB_CLEARANCE), results, stage)
    else:
        run_stages(JOB_STAGES + ((JOB_CLEARANCE,) if clearance_profile else ()), results, stage)
    linked, timed = results["links"], results["order"]
    return JobPlan(
        inputs.file,
        inputs.cell,
        inputs.robot,
        results["home"],
        timed.options,
        linked.chosen,
        timed.order,
        linked.links,
        linked.samples,
        linked.X_BE,
        linked.tcp_speed,
        results["io"],
        results["check"],
        stage.timings_s,
        results.get("clearance"),
        results["quality"],
    )


class SeamPlanner:
    """One seam in one direction for the job's stages, by the one-seam pipeline: its
    fit and frames alone (:meth:`geometry`), or its whole plan (called), each seam
    direction's stage timings in one StageTimer. Keeps each fit in ``fits``
    ((seam index, reversed) ↦ FittedPath); with ``parallel`` the job's seams are planned
    on two processes (``job.stages.seam_options``)."""

    def __init__(self, progress: Callable[[str], None], fits: dict, *, parallel: bool = False):
        self.progress, self.fits, self.parallel = progress, fits, parallel
        self.timers: dict[tuple[int, bool], StageTimer] = {}

    def geometry(self, k: int, reverse: bool, inputs: Inputs, scene: DrakeCell) -> dict:
        """{fit, frames} of seam k in one direction (SEAM_STAGES' fit, frames)."""
        results = {"scene": scene, "inputs": inputs, "progress": self.progress}
        if (k, reverse) in self.fits:
            results["fit"] = self.fits[k, reverse]
        run_stages(SEAM_STAGES[:2], results, self.timer(k, reverse))
        self.fits[k, reverse] = results["fit"]
        return {name: results[name] for name in ("fit", "frames")}

    def silence(self) -> None:
        """Tell no more progress (a forked process's: the terminal's line is the
        parent's)."""
        self.progress = quiet
        for timer in self.timers.values():
            timer.progress = quiet

    def timer(self, k: int, reverse: bool) -> StageTimer:
        """The StageTimer of seam k in one direction (its plan's ``timings_s``)."""
        return self.timers.setdefault((k, reverse), StageTimer(self.progress))

    def __call__(
        self, k: int, reverse: bool, inputs: Inputs, scene: DrakeCell, *, known: dict
    ) -> Plan:
        """Seam k's plan in one direction, from the stages' results ``known``."""
        results = {"scene": scene, **known}
        return plan_seam(inputs, self.timer(k, reverse), results=results, clearance_profile=False)
