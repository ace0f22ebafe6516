"""The stages as data, declared once: ``plan``, the session and placement run them.

:data:`JOB_STAGES` plan a whole job (scene, home, seams, order, links, I/O, process
quality, the whole job's check; every cell is a job), :data:`SEAM_STAGES` each of its
seams.

Each :class:`Stage` names its function, the results it reads (by stage name, or
``inputs``: the seam's :class:`~offline_prog.stages.Inputs`) and the editable cell
values it depends on (fields of :class:`~offline_prog.config.edits.CellValues`).
:func:`run_stages` calls them in order; a result the caller already holds (a seam's
fit kept across placement candidates) is not computed again, and with a
:class:`StageCache` a stage runs only when a value it depends on, directly or through
the results it reads, changed (the session):

=========  ==============================  ========================================
stage      reads                           depends on (CellValues)
=========  ==============================  ========================================
fit        inputs                          seam
frames     inputs, fit                     + tool and grasp poses, tool rotation,
                                           tool turn smoothing
scene      inputs                          tool and grasp poses
joints     inputs, frames                  (frames') + speed
check      inputs, scene, joints           (scene's, joints') + clearance
collision  inputs, fit, frames, scene,     (all of those)
           check
=========  ==============================  ========================================
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable

from offline_prog.config.edits import CellValues
from offline_prog.errors import InputError, PlanFailedError
from offline_prog.forked import forked_map
from offline_prog.job.home import home_pose
from offline_prog.job.stages import (
    check_job,
    job_clearance,
    job_io,
    job_quality,
    link_job,
    seam_options,
)
from offline_prog.job.untimed import timed_order
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.path.process_frames import NormalTangentError
from offline_prog.stages import (
    FittedPath,
    Inputs,
    attempt_motion,
    avoid,
    build_scene,
    check_attempt,
    first_joints,
    fit_path,
    flange_paths,
)

POSES = ("p_IT", "rpy_IT_deg", "p_PE", "rpy_PE_deg")


@dataclasses.dataclass(frozen=True)
class Stage:
    """One stage: ``name`` (its result's name and its key in the stage timings), what
    the progress line says, the function, the results it reads (its arguments, in
    order) and the cell values it depends on besides them."""

    name: str
    description: str
    function: Callable
    reads: tuple[str, ...]
    depends_on: tuple[str, ...] = ()


SEAM_STAGES = (
    Stage("fit", "fitting the B-spline", fit_path, ("inputs",), ("seam",)),
    Stage(
        "frames",
        "process frames and flange path",
        flange_paths,
        ("inputs", "fit"),
        (*POSES, "free_rotation_deg", "turn_smoothing_mm"),
    ),
    Stage("scene", "building the Drake cell", build_scene, ("inputs",), POSES),
    Stage("joints", "joint trajectory", first_joints, ("inputs", "frames"), ("speed",)),
    Stage("check", "collision check", check_attempt, ("inputs", "scene", "joints"), ("clearance",)),
    Stage(
        "collision",
        "collision avoidance",
        avoid,
        ("inputs", "fit", "frames", "scene", "check", "progress"),
    ),
)


# The job around its seams (``plan.plan_loaded_job``): ``seam_planner`` is the caller's
# plan of one seam in one direction (``plan.plan_seam`` on SEAM_STAGES).
JOB_STAGES = (
    Stage("scene", "building the Drake cell", build_scene, ("inputs",)),
    Stage("home", "checking the home pose", home_pose, ("inputs", "scene")),
    Stage(
        "seams",
        "planning the seams",
        seam_options,
        ("inputs", "scene", "seam_planner", "progress"),
    ),
    Stage(
        "order",
        "ordering the seams and timing the chosen ones",
        timed_order,
        ("inputs", "scene", "seams", "home", "seam_planner", "progress"),
    ),
    Stage("links", "linking moves", link_job, ("inputs", "scene", "order", "home", "progress")),
    Stage("io", "process I/O", job_io, ("inputs", "links")),
    Stage("quality", "process quality", job_quality, ("inputs", "links", "io")),
    Stage("check", "collision check of the whole job", check_job, ("inputs", "scene", "links")),
)
# The check (last) and the clearance profile read the linked job, not each other.
JOB_CHECK = JOB_STAGES[-1]
JOB_CLEARANCE = Stage("clearance", "clearance profile", job_clearance, ("scene", "links"))


class StageCache:
    """Each stage's last key and result: a stage whose key did not change is reused."""

    def __init__(self):
        self.kept: dict[str, tuple[tuple, object]] = {}


def run_stages(
    stages: tuple[Stage, ...],
    results: dict[str, object],
    timer,
    *,
    cache: StageCache | None = None,
    values: CellValues | None = None,
) -> dict[str, object]:
    """Run ``stages`` in order on ``results`` (updated in place and returned).

    Args:
        results: what the stages read: ``inputs``, ``progress`` and any result the
            caller already holds (that stage is then skipped).
        timer: a :class:`~offline_prog.plan.StageTimer`: progress and wall times.
        cache, values: reuse a stage's kept result while the values it depends on
            (directly or through what it reads) equal these.
    """
    keys: dict[str, tuple] = {}
    for stage in stages:
        key = tuple(getattr(values, v) for v in stage.depends_on) if values else ()
        key += tuple(keys.get(r, ()) for r in stage.reads)
        keys[stage.name] = key
        if stage.name in results:
            continue
        kept = cache.kept.get(stage.name) if cache is not None else None
        if kept is None or kept[0] != key:
            arguments = [results[r] for r in stage.reads]
            try:
                kept = (key, timer(stage.name, stage.description, stage.function, *arguments))
            except PlanFailedError as error:  # kept too: the same values fail the same way
                kept = (key, error)
            if cache is not None:
                cache.kept[stage.name] = kept
        if isinstance(kept[1], PlanFailedError):
            raise kept[1]
        results[stage.name] = kept[1]
    return results


def run_side_by_side(stages: tuple[Stage, ...], results: dict[str, object], timer) -> None:
    """Run ``stages``, none of which reads another's result, on this process and a
    forked child (``forked.forked_map``); ``results`` gets each one's result and
    ``timer`` each one's own wall time, as :func:`run_stages` would give them.

    Raises:
        The first stage's error, in ``stages``' order, as a serial run would.
    """

    def timed(stage: Stage) -> tuple[object, float]:
        start = time.perf_counter()
        value = stage.function(*(results[r] for r in stage.reads))
        return value, time.perf_counter() - start

    timer.progress(" and ".join(stage.description for stage in stages))
    outcomes = forked_map(timed, list(stages), shared=[results])
    for stage, outcome in zip(stages, outcomes, strict=True):
        results[stage.name], seconds = outcome.result()
        timer.add(stage.name, seconds)


def with_normal_hint(error: PlanFailedError, inputs: Inputs, fit: FittedPath, scene):
    """``error``, with a hint when the same path is feasible with the surface normal
    reversed: a normal pointing out of the surface (not into it) turns the tool frame
    over and reads as out of reach or a singularity. Costs one more joint plan, and
    only on failure."""

    def flipped(s):
        return [-v for v in fit.normal(s)]

    try:
        flange = FlangePath(fit.path, flipped, X_IT=inputs.X_IT, X_PE=inputs.X_PE)
        attempt_motion(inputs, scene, 0.0, flange)
    except (PlanFailedError, NormalTangentError, InputError):
        return error
    failure = error.failure
    hint = (
        "; with the path's normals reversed the robot can follow it: check that they "
        "point into the surface (path.normal, the CSV's nx,ny,nz or the mesh)"
    )
    return PlanFailedError(dataclasses.replace(failure, reason=failure.reason + hint))
