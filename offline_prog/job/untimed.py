"""Seam options decided before their time law; the law runs for the chosen ones only.

The seam order (``job.order``) reads each option's link ends q_in, q_out and nothing of
its timing, so an option is offered on what decides whether it exists: its path IK on
its branch follows the whole path within the joint limits, its path is collision-free
at the clearances (checked on the IK grid by ``collision.check`` without the pruning
margin: the verdict, not the minima), and its approach and retract exist. The time
law, the joint retiming and the collision check of the timed samples then run only for
the option the order chooses for each seam (:func:`timed_order`). Where a timed check
refuses what the untimed one passed, the plan goes the way it went when every option
was timed: a first option that collides goes through the collision avoidance (its
direction then offers no other branch), a first option that cannot be timed drops its
direction, another branch that fails is dropped; and the order is searched again
without it. One difference is left on purpose: another branch that can be timed is
kept even where its direction's first could not have been (every option timed dropped
the whole direction with its first).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from offline_prog.collision.check import check_trajectory
from offline_prog.errors import PlanFailedError
from offline_prog.forked import forked_map, in_child
from offline_prog.job.approach import other_branches, plan_ends, seam_ends
from offline_prog.job.order import JobOrder, order_job
from offline_prog.job.records import Plan, SeamOption, UntimedSeam
from offline_prog.job.seams import errors_named_for, job_config, job_seams, seam_key
from offline_prog.joints.joint_plan import path_branches
from offline_prog.progress import Step
from offline_prog.scene.drake_cell import DrakeCell
from offline_prog.stages import (
    FittedPath,
    FlangePaths,
    Inputs,
    MotionSetup,
    check_attempt,
    motion_setup,
    plan_motion,
)
from offline_prog.timing.fallback_walk import walk_fallbacks
from offline_prog.timing.lead_length import lead_failure

MAX_OTHER_BRANCHES = 2  # IK branches per seam direction offered to the order besides the best


@dataclasses.dataclass
class SeamChoices:
    """Stage ``seams``: every option of each seam (``options[k]``: the forward ones
    first, each direction's first option first) and why a direction of seam k was
    dropped (``errors[k][reverse]``)."""

    options: list[list[SeamOption]]
    errors: list[dict[bool, PlanFailedError]]


@dataclasses.dataclass
class TimedOrder:
    """Stage ``order``: the seams' options with the chosen ones timed, and the order."""

    options: list[list[SeamOption]]
    order: JobOrder


def untimed_options(
    inputs: Inputs,
    scene: DrakeCell,
    fit: FittedPath,
    frames: FlangePaths,
    seam,
    *,
    k: int,
    reverse: bool,
    branches: bool,
) -> list[SeamOption] | None:
    """Seam k's options in one direction before their time law (``inputs``: the seam's,
    ``seam``: its SeamConfig): the first (the best tool rotation and branch) and, with
    ``branches``, up to MAX_OTHER_BRANCHES other branches (largest joint-limit margin
    first). None where the first option takes more than
    its path IK and a collision check to decide (its IK, path or approach fails): the
    caller plans that direction in full.

    Raises:
        InputError: ``motion.cusp_smoothing_mm`` or the sample count (``motion_setup``).
    """
    if inputs.robot.family == "drake":  # no analytic branches: planned in full
        return None
    rotation, flange = frames.rotations[0]
    run, results, start = _first_run(inputs, flange)
    first, results = _untimed(
        inputs, scene, fit, frames, rotation, flange, run, None, results, start=start
    )
    if first is None:
        return None
    try:
        moves = _ends(inputs, run, first, seam)
    except PlanFailedError:
        return None
    options = [SeamOption(k, seam.name, reverse, None, *moves, untimed=first)]
    if not branches:
        return options
    others = other_branches(results, first.branch, MAX_OTHER_BRANCHES)
    # As the timed plan of another branch gets it: the first option's path as run (the
    # first's verdicts where that is the path they were found on: no cusp smoothing).
    again = motion_setup(inputs, run.flange) if others else None
    known = results if again is not None and again.flange is run.flange else None
    for other in others:  # one path IK on the path as run serves each
        variant, known = _untimed(
            inputs, scene, fit, frames, rotation, run.flange, again, other.branch, known
        )
        if variant is None:
            continue
        try:
            moves = _ends(inputs, run, variant, seam)
        except PlanFailedError:
            continue
        options.append(SeamOption(k, seam.name, reverse, None, *moves, untimed=variant))
    return options


def _first_run(inputs: Inputs, flange) -> tuple[MotionSetup, list, tuple | None]:
    """The path a direction's first option runs on, as ``stages.plan_motion`` runs it
    before its time law: (``motion_setup`` of ``flange``, every IK branch's verdict on
    its grid, None); where no branch follows a flying path, the first of its leads'
    fallbacks (``timing.lead_length.fallbacks``: own lift, then rest) one does, as
    (its setup, its verdicts, (the path as first asked, its verdicts)): the timed plan
    starts there and walks the same fallbacks (a fallback that cannot be timed)."""
    robot, X_IB = inputs.robot, inputs.X_IB

    def followed(run: MotionSetup):
        _, results, chosen, _ = path_branches(robot, X_IB, run.flange, run.parameter)
        return results, "" if chosen.feasible else lead_failure(chosen.reason)

    walk = walk_fallbacks(
        motion_setup(inputs, flange), followed, setup=lambda leads: motion_setup(inputs, leads)
    )
    first = walk.tried[0][:2]
    if len(walk.tried) == 1 or not walk.served:  # as asked, or planned in full (no
        return (*first, None)  # branch follows it at rest either)
    return (*walk.last, first)


def _untimed(
    inputs: Inputs,
    scene: DrakeCell,
    fit: FittedPath,
    frames: FlangePaths,
    rotation: float,
    flange,
    run: MotionSetup,
    branch: int | None,
    results: list | None = None,
    *,
    start: tuple | None = None,
) -> tuple[UntimedSeam | None, list]:
    """(the option on ``branch`` (None: the best), or None if its path IK fails or its
    path collides; every branch's verdict on ``run``'s path, ``results`` if known).
    ``start``: where its timed plan starts (``UntimedSeam.start``)."""
    motion = inputs.cell.motion
    grid, results, chosen, path = path_branches(
        inputs.robot, inputs.X_IB, run.flange, run.parameter, branch, results=results
    )
    if not chosen.feasible:
        return None, results
    verdict = check_trajectory(
        scene,
        chosen.q,
        grid / inputs.speed.v_m_s,  # only labels the verdict's stretches
        grid,
        clearance=motion.clearance,
        self_clearance=motion.self_clearance,
        margin=0.0,
    )
    if not verdict.collision_free:
        return None, results
    q_ends = path.q(grid[[0, -1]], chosen.q[[0, -1]])
    first = branch is None
    option = UntimedSeam(
        inputs, fit, frames, rotation, flange, chosen.branch, q_ends, first, run, results, start
    )
    return option, results


def _ends(inputs: Inputs, run: MotionSetup, untimed: UntimedSeam, seam):
    """Approach and retract of an untimed option, on the direction's first flange path
    as run (the timed plan's ``flange``)."""
    length = untimed.fit.path.length
    return seam_ends(inputs, run.flange, length, untimed.q_ends, untimed.branch, seam)


def choose_order(
    inputs: Inputs, options: list[list[SeamOption]], q_home, progress=lambda message: None
) -> JobOrder:
    """Seam order and direction (``job.order``) for the least estimated air time; the
    search's rounds told to ``progress`` (its budget spent as the bar)."""
    flat = [option for seam in options for option in seam]
    robot = inputs.robot

    def search_round(rounds: int, air_time_s: float, used: int, budget: int) -> None:
        text = f"seam order: round {rounds}, estimated air time {air_time_s:.2f} s"
        progress(Step(text, stage="order", done=used, total=budget))

    return order_job(
        [(o.seam, o.label, o.q_in, o.q_out) for o in flat],
        q_home,
        qd_max=robot.qd_max * inputs.cell.motion.link_speed_percent / 100.0,  # the links'
        qdd_max=robot.qdd_max,
        n_seams=len(options),
        mode=job_config(inputs.cell).order,
        controller_joints=robot.controller_joints,
        progress=search_round,
    )


def timed_order(
    inputs: Inputs,
    scene: DrakeCell,
    choices: SeamChoices,
    q_home: np.ndarray,
    seam_planner,
    progress=lambda message: None,
) -> TimedOrder:
    """Stage ``order``: the seam order (:func:`choose_order`), the chosen options timed,
    and the order searched again while the timed checks drop a chosen option.

    Raises:
        PlanFailedError: a seam none of whose options can be timed (its first reason).
    """
    options = [list(seam) for seam in choices.options]
    errors = [dict(e) for e in choices.errors]
    while True:
        order = choose_order(inputs, options, q_home, progress)
        flat = [(k, j) for k, seam in enumerate(options) for j in range(len(seam))]
        chosen = [flat[i] for i in order.sequence]
        pending = [(k, j) for k, j in chosen if options[k][j].plan is None]

        time_one = functools.partial(
            _time_pending, inputs, scene, seam_planner, options, errors, pending, progress
        )
        items = list(range(len(pending)))
        if seam_planner.parallel:  # the chosen seams are timed on the second core too
            # Longest path first: the two processes end nearer together.
            longest = sorted(items, key=lambda n: -_length(options[pending[n][0]][pending[n][1]]))
            shared = (inputs, scene, seam_planner, options, errors)
            outcomes = dict(zip(longest, forked_map(time_one, longest, shared=shared), strict=True))
            results = (outcomes[n].result() for n in items)  # raised in order
        else:
            results = (time_one(n) for n in items)
        changed = False
        for (k, j), (timed, same, seam_errors, timings) in zip(pending, results, strict=True):
            name = options[k][j].name
            options[k] = timed
            errors[k].clear()
            errors[k].update(seam_errors)
            for key, timings_s in timings.items():  # in place: a plan holds its timer's
                seam_planner.timer(*key).timings_s.update(timings_s)
            changed |= not same
            if not options[k]:
                failure = errors[k][min(errors[k])].failure  # forward's reason first
                if inputs.cell.seams:
                    failure = dataclasses.replace(failure, reason=f"seam {name}: {failure.reason}")
                raise PlanFailedError(failure)
        if not changed:
            return TimedOrder(options, order)


def _length(option: SeamOption) -> float:
    """The option's path length [m]: the size of its time law's work."""
    return option.untimed.fit.path.length if option.untimed else option.plan.path.length


def _time_pending(inputs, scene, seam_planner, options, errors, pending, progress, n: int):
    """(seam k's options with option j timed (:func:`_time`), whether they are the same
    ones, its errors, its timers' timings) for ``pending[n]`` = (k, j): new containers, so
    that what changed travels back from a forked process (``offline_prog.forked``)."""
    k, j = pending[n]
    if in_child():  # the terminal's progress line is the parent's
        seam_planner.silence()
    else:
        text = f"timing seam {options[k][j].label}"
        progress(Step(text, stage="timing", done=n, total=len(pending)))
    seam_errors = dict(errors[k])
    with errors_named_for(seam_key(inputs.cell, k)):
        seam = job_seams(inputs.cell)[k]
        timed, same = _time(options[k], j, scene, seam_planner, seam_errors, seam)
    keys = [key for key in seam_planner.timers if key[0] == k]
    timings = {key: dict(seam_planner.timers[key].timings_s) for key in keys}
    return timed, same, seam_errors, timings


def _time(options: list[SeamOption], j: int, scene, seam_planner, errors, seam):
    """Seam k's ``options`` with option j timed: (the options, whether they are the same
    ones as before). Another branch is timed on its direction's first flange path as
    run, and its plan holds that path and its limits as the first's does; it is dropped
    where it cannot run the leads the first runs (``stages.plan_motion``'s fallbacks)."""
    option = options[j]
    first = next(i for i, o in enumerate(options) if o.reverse == option.reverse)
    if j == first:
        return _time_first(list(options), first, scene, seam_planner, errors, seam)
    u = option.untimed
    timer = seam_planner.timer(option.seam, option.reverse)
    try:
        from_untimed = functools.partial(plan_motion, run=u.run, branches=u.branches)
        attempt = timer(
            "joints", "joint trajectory", from_untimed, u.inputs, u.rotation, u.flange, u.branch
        )
        attempt = timer("check", "collision check", check_attempt, u.inputs, scene, attempt)
    except PlanFailedError:
        attempt = None
    held = options[first].plan or options[first].untimed.run  # the path its plan holds
    if (
        attempt is None
        or not attempt.collisions.collision_free
        or attempt.flange.asked != held.flange.asked  # its leads fell back, the first's not
    ):
        return options[:j] + options[j + 1 :], False
    if options[first].plan is None:
        run = options[first].untimed.run  # the first's flange path, as run
        as_first = dataclasses.replace(attempt, flange=run.flange, limits=run.limits)
        plan = Plan.of_attempt(u.inputs, u.fit, u.frames, as_first, timings_s=timer.timings_s)
    else:
        plan = dataclasses.replace(
            options[first].plan,
            joints=attempt.joints,
            trajectory=attempt.joints.trajectory,
            collisions=attempt.collisions,
            clearance_profile=None,
        )
    options = list(options)
    options[j] = dataclasses.replace(option, plan=plan, untimed=None)
    return options, True


def _time_first(options: list[SeamOption], i: int, scene, seam_planner, errors, seam):
    """``options`` with the direction's first option (at i) timed, if it is not: as
    planned, or its direction planned again in full (the collision avoidance, which
    offers no other branches) or dropped; and whether the options are the same ones."""
    option = options[i]
    if option.plan is not None:
        return options, True
    u, reverse = option.untimed, option.reverse
    timer = seam_planner.timer(option.seam, reverse)  # the stages' names and wall times
    known = {"fit": u.fit, "frames": u.frames}
    run, branches = u.start or (u.run, u.branches)  # a fallback's: from the leads asked
    try:
        from_untimed = functools.partial(plan_motion, run=run, branches=branches)
        unchecked = timer(
            "joints", "joint trajectory", from_untimed, u.inputs, u.rotation, u.flange
        )
        attempt = timer("check", "collision check", check_attempt, u.inputs, scene, unchecked)
        known |= {"joints": unchecked, "check": attempt}
    except PlanFailedError:
        attempt = None  # the full plan below says why, as it did for every option
    if attempt is not None and attempt.collisions.collision_free:
        timer("collision", "collision avoidance: not needed", lambda: None)
        plan = Plan.of_attempt(u.inputs, u.fit, u.frames, attempt, timings_s=timer.timings_s)
        moves = {"approach": option.approach, "retract": option.retract}
        ran = attempt.flange
        if ran is not u.run.flange and ran.asked != u.run.flange.asked:  # other leads ran:
            try:
                moves = dict(zip(moves, plan_ends(u.inputs, plan, seam), strict=True))
            except PlanFailedError:
                moves = None  # planned in full below
        if moves is not None:
            options[i] = dataclasses.replace(option, plan=plan, untimed=None, **moves)
            return options, True
    # The direction planned in full from here: the collision avoidance for timed
    # samples that collide (no other branches offered then), or the failure named.
    block = []
    try:
        plan = seam_planner(option.seam, reverse, u.inputs, scene, known=known)
        moves = plan_ends(u.inputs, plan, seam)
        block = [SeamOption(option.seam, option.name, reverse, plan, *moves)]
    except PlanFailedError as error:
        errors[reverse] = error
    kept = [o for o in options if o.reverse != reverse]
    return sorted(kept + block, key=lambda o: o.reverse), False
