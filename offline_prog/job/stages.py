"""The stages of :func:`offline_prog.plan.plan_job` beyond the one-seam pipeline.

``job.home.home_pose`` → ``seam_options`` (each seam planned in each direction it may run,
with its approach and retract) → ``choose_order`` → ``job_pieces`` (links between the
chosen seams, from home and back) → ``job.assemble.lay_out`` → ``check_job``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.collision.check import CollisionResult, check_trajectory
from offline_prog.collision.motion import MotionChecker
from offline_prog.collision.profile import distance_profile
from offline_prog.errors import InputError, PlanFailedError
from offline_prog.forked import forked_map, in_child, quiet
from offline_prog.job.approach import other_branches, plan_ends
from offline_prog.job.assemble import JobSamples, Piece, lay_out
from offline_prog.job.links import LinkMotion, plan_link, timed_polyline
from offline_prog.job.process_io import IoColumns, IoPlacementError, io_columns
from offline_prog.job.records import SeamOption
from offline_prog.job.seams import (
    errors_named_for,
    job_config,
    job_seams,
    seam_inputs,
    seam_key,
)
from offline_prog.job.speed_band import check_speed_bands
from offline_prog.job.untimed import (
    MAX_OTHER_BRANCHES,
    SeamChoices,
    TimedOrder,
    untimed_options,
)
from offline_prog.process.quality import ProcessQuality, process_quality
from offline_prog.process.registry import process_model
from offline_prog.progress import Step
from offline_prog.scene.drake_cell import DrakeCell
from offline_prog.stages import Inputs, attempt_motion

LINK_SEED = 0  # links are seeded with this plus their index: same job, same links
# The directions a seam's ``direction`` runs it in (reversed?), forward first.
DIRECTIONS = {"forward": (False,), "reverse": (True,), "auto": (False, True)}


def seam_options(inputs: Inputs, scene: DrakeCell, plan_seam, progress) -> SeamChoices:
    """Each seam's options in each direction it may run (``direction``), with approach
    and retract, decided before their time law where the path IK and a collision check
    decide them (``job.untimed``), else planned in full. A direction the robot cannot do
    is dropped when the other one works. ``plan_seam(k, reverse, seam_inputs, scene,
    known=...)`` plans seam k in one direction from the stages' results it is given.

    Raises:
        InputError: naming ``seams[k].<key>`` (a process speed outside the process
            model's speed band: ``job.speed_band``).
        PlanFailedError: a seam cannot be done in any direction (its reason, named).
    """
    check_speed_bands(inputs)
    seams = job_seams(inputs.cell)
    items = [(k, reverse) for k, seam in enumerate(seams) for reverse in DIRECTIONS[seam.direction]]

    def one_direction(item: tuple[int, bool]):
        """(seam k's options in one direction, or why it cannot run that way; its fit
        and stage timer)."""
        k, reverse = item
        tell = progress
        if in_child():  # the terminal's progress line is the parent's
            tell = quiet
            plan_seam.silence()
        seam, found, error = seams[k], [], None
        text = f"seam {k + 1}/{len(seams)}: {seam.name} ({'reverse' if reverse else 'forward'})"
        tell(Step(text, stage="seams", done=k, total=len(seams)))
        try:
            with errors_named_for(seam_key(inputs.cell, k)):
                seam_in = seam_inputs(inputs, k, reverse=reverse)
                found = _direction_options(inputs, seam_in, scene, plan_seam, k, reverse, seam)
        except PlanFailedError as failed:
            error = failed
        return found, error, plan_seam.fits.get(item), plan_seam.timers.get(item)

    if plan_seam.parallel:  # on the second core too (seams and directions are independent)
        outcomes = forked_map(one_direction, items, shared=(inputs, scene, plan_seam))
        results = (outcome.result() for outcome in outcomes)  # raised in their order
    else:
        results = (one_direction(item) for item in items)  # the first failure ends it
    options, errors = [[] for _ in seams], [{} for _ in seams]
    for (k, reverse), (found, error, fit, timer) in zip(items, results, strict=True):
        if fit is not None:
            plan_seam.fits[k, reverse] = fit
        if timer is not None:
            timer.progress = plan_seam.progress
            plan_seam.timers[k, reverse] = timer
        options[k] += found
        if error is not None:
            errors[k][reverse] = error
        if reverse == DIRECTIONS[seams[k].direction][-1] and not options[k]:
            failure = errors[k][DIRECTIONS[seams[k].direction][0]].failure
            if inputs.cell.seams:  # name the seam (a path: cell has only the one)
                failure = dataclasses.replace(
                    failure, reason=f"seam {seams[k].name}: {failure.reason}"
                )
            raise PlanFailedError(failure)
    progress(Step(f"{len(seams)} seams planned", stage="seams", done=len(seams), total=len(seams)))
    return SeamChoices(options, errors)


def _direction_options(inputs, seam_in: Inputs, scene: DrakeCell, plan_seam, k, reverse, seam):
    """Seam k's options in one direction (``seam_in``: its inputs): untimed where they can
    be and the order has a choice (``job.untimed``), else planned in full, with up to
    MAX_OTHER_BRANCHES other branches in a ``seams:`` job."""
    known = plan_seam.geometry(k, reverse, seam_in, scene)
    if inputs.cell.seams or seam.direction == "auto":  # the order has a choice
        untimed = untimed_options(
            seam_in,
            scene,
            known["fit"],
            known["frames"],
            seam,
            k=k,
            reverse=reverse,
            branches=bool(inputs.cell.seams),
        )
        if untimed is not None:
            return untimed
    plan = plan_seam(k, reverse, seam_in, scene, known=known)
    # A path: cell's one seam keeps the branch its pipeline chose (the plan as before
    # issue 24, not planned again on other branches).
    others = _other_branches(seam_in, scene, plan) if inputs.cell.seams else []
    found = []
    for variant in [plan, *others]:
        try:
            approach, retract = plan_ends(seam_in, variant, seam)
        except PlanFailedError:
            if variant is plan:
                raise
            continue  # this branch cannot approach or retract
        found.append(SeamOption(k, seam.name, reverse, variant, approach, retract))
    return found


def _other_branches(inputs: Inputs, scene: DrakeCell, plan) -> list:
    """The seam on up to MAX_OTHER_BRANCHES other IK branches that follow the whole path
    within the limits (largest margin first), each collision-free at the clearances, as
    plans beside the chosen one: the seam order may pick them (issue 13: the branch is
    part of the choice). Not for a plan that needed collision avoidance."""
    if plan.avoidance is not None or not plan.feasible:
        return []
    joints = plan.joints
    others = other_branches(joints.branches, joints.branch, MAX_OTHER_BRANCHES)
    variants = []
    for other in others:
        try:
            attempt = attempt_motion(
                inputs, scene, plan.tool_rotation_rad, plan.flange, other.branch
            )
        except PlanFailedError:
            continue
        if attempt.collisions.collision_free:
            variants.append(
                dataclasses.replace(
                    plan,
                    joints=attempt.joints,
                    trajectory=attempt.joints.trajectory,
                    collisions=attempt.collisions,
                    clearance_profile=None,
                )
            )
    return variants


def job_pieces(
    inputs: Inputs, scene: DrakeCell, chosen: list[SeamOption], q_home, progress
) -> tuple[list[Piece], list[LinkMotion]]:
    """home → link → approach → process → retract → link → … → home, as pieces.

    A link not found within its time budget keeps its failure (naming it) and the direct
    move in its place, so that the job's reports show where it collides."""
    motion = inputs.cell.motion
    checker = MotionChecker(scene, clearance=motion.clearance, self_clearance=motion.self_clearance)
    pieces, links, q_now, previous = [], [], q_home, "home"
    for option in [*chosen, None]:
        target = option.q_in if option else q_home
        name = f"{previous} -> {option.name if option else 'home'}"
        text = f"link {len(links) + 1}/{len(chosen) + 1}: {name}"
        progress(Step(text, stage="links", done=len(links), total=len(chosen) + 1))
        link = plan_link(
            scene,
            inputs.robot,
            q_now,
            target,
            clearance=motion.clearance,
            self_clearance=motion.self_clearance,
            seed=LINK_SEED + len(links),
            time_budget_s=job_config(inputs.cell).link_time_s,
            rate_hz=motion.sample_rate_hz,
            name=name,
            checker=checker,
            speed_share=motion.link_speed_percent / 100.0,
        )
        if not link.ok:  # the direct move stands in: the check shows where it collides
            t, q, qd = timed_polyline(
                inputs.robot,
                np.array([q_now, target]),
                motion.sample_rate_hz,
                speed_share=motion.link_speed_percent / 100.0,
            )
            link = dataclasses.replace(link, t=t, q=q, qd=qd, waypoints=np.array([q_now, target]))
        links.append(link)
        nan = np.full(len(link.t), np.nan)
        pieces.append(Piece("link", "", link.t, link.q, link.qd, nan))
        if option is None:
            break
        pieces += _seam_pieces(option)
        q_now, previous = option.q_out, option.name
    return pieces, links


def _seam_pieces(option: SeamOption) -> list[Piece]:
    """approach (its straight move, then a flying seam's lead-in), process, retract (the
    lead-out, then the straight move); path_m: σ on the seam and its leads, −(lead-in +
    δ) and L + lead-out + δ on the straight moves."""
    plan, name = option.plan, option.name
    joints, traj = plan.joints, plan.joints.trajectory
    lead_in, lead_out, length = plan.lead_in, plan.lead_out, plan.path.length
    out = []
    a, r = option.approach, option.retract
    before = lead_in.length_m if lead_in else 0.0
    after = lead_out.length_m if lead_out else 0.0
    moves = []
    if a:
        moves.append((a.t, a.q, np.gradient(a.q, a.t, axis=0), -before - a.delta))
    if lead_in:
        moves.append((lead_in.t, lead_in.q, lead_in.qd, lead_in.s))
    if moves:
        out.append(Piece("approach", name, *_joined(moves)))
    out.append(Piece("process", name, traj.t, joints.q, joints.qd, traj.s))
    moves = []
    if lead_out:
        moves.append((lead_out.t, lead_out.q, lead_out.qd, lead_out.s))
    if r:
        moves.append((r.t, r.q, np.gradient(r.q, r.t, axis=0), length + after + r.delta))
    if moves:
        out.append(Piece("retract", name, *_joined(moves)))
    return out


def _joined(moves: list[tuple]) -> tuple[np.ndarray, ...]:
    """(t, q, qd, path_m) of motions run one after the other, each starting where the
    one before ends (that shared row once, the later motion's)."""
    t, q, qd, path = [], [], [], []
    clock = 0.0
    for k, (t_k, q_k, qd_k, path_k) in enumerate(moves):
        keep = slice(0, None) if k == len(moves) - 1 else slice(0, -1)
        t.append(clock + t_k[keep])
        q.append(q_k[keep])
        qd.append(qd_k[keep])
        path.append(path_k[keep])
        clock += float(t_k[-1])
    return tuple(np.concatenate(x) for x in (t, q, qd, path))


@dataclasses.dataclass
class LinkedJob:
    """Stage ``links``: the options run, in order; the links (home → first, …, last →
    home); the job's samples, the flange E in the robot base B on every row X_BE
    (N, 4, 4) (forward kinematics, once for the job) and the tool's speed along the
    part on every row (N,) [m/s]."""

    chosen: list[SeamOption]
    links: list[LinkMotion]
    samples: JobSamples
    X_BE: np.ndarray
    tcp_speed: np.ndarray


def link_job(
    inputs: Inputs,
    scene: DrakeCell,
    timed: TimedOrder,
    q_home: np.ndarray,
    progress,
) -> LinkedJob:
    """The chosen options linked from home and back (:func:`job_pieces`), laid out as
    one trajectory (``job.assemble.lay_out``)."""
    flat = [option for seam in timed.options for option in seam]
    chosen = [flat[i] for i in timed.order.sequence]
    pieces, links = job_pieces(inputs, scene, chosen, q_home, progress)
    samples = lay_out(pieces)
    X_BE = inputs.robot.forward(samples.q)
    return LinkedJob(
        chosen, links, samples, X_BE, tool_speed(inputs, samples, chosen=chosen, X_BE=X_BE)
    )


def job_io(inputs: Inputs, linked: LinkedJob) -> IoColumns:
    """Stage ``io``: the process I/O on every row (``job.process_io``).

    Raises:
        InputError: a switch that falls outside its seam's moves (the key named).
    """
    lengths = {option.name: option.plan.path.length for option in linked.chosen}
    process_io = inputs.cell.tool.process_io
    try:
        return io_columns(
            linked.samples,
            process_io,
            lengths,
            linked.tcp_speed,
            process_model(inputs.cell.process),
            flying=frozenset(o.name for o in linked.chosen if o.plan.lead_in is not None),
        )
    except IoPlacementError as error:
        raise InputError(inputs.file, error.key, error.reason) from None


def job_quality(inputs: Inputs, linked: LinkedJob, io: IoColumns) -> ProcessQuality | None:
    """Stage ``quality``: the process quality along the job (process.quality) from the
    planned TCP speed and the outputs as the programs set them; None without a model."""
    model = process_model(inputs.cell.process)
    if model is None:
        return None
    samples = linked.samples
    return process_quality(
        model,
        t=samples.t,
        v_tcp=linked.tcp_speed,
        path_m=samples.path_m,
        segments=samples.segments,
        command=io.analog,
        digital=io.digital if io.valve is None else io.valve,
        settings=io.settings,
        events=io.events,
    )


def check_job(inputs: Inputs, scene: DrakeCell, linked: LinkedJob) -> CollisionResult:
    """The whole job's collision check: every sample and between samples, the same
    geometry, clearances and rules as a seam (collision.check)."""
    motion, samples = inputs.cell.motion, linked.samples
    return check_trajectory(
        scene,
        samples.q,
        samples.t,
        np.nan_to_num(samples.path_m),
        clearance=motion.clearance,
        self_clearance=motion.self_clearance,
    )


def job_clearance(scene: DrakeCell, linked: LinkedJob):
    """Stage ``clearance``: the whole job's clearance profile (collision.profile)."""
    return distance_profile(scene, linked.samples.q, linked.samples.t)


def tool_speed(
    inputs: Inputs, samples: JobSamples, *, chosen: list[SeamOption], X_BE: np.ndarray
) -> np.ndarray:
    """(N,) speed of the tool point along the part [m/s] on every row: |d p_PT / dt|
    with X_PT = X_PE · X_EB · X_BI · X_IT (X_BE (N, 4, 4): the flange on every row);
    the seams' own exact TCP speed on their process rows and their leads' rows."""
    X_BT = (inputs.X_IB.inverse() @ inputs.X_IT).GetAsMatrix4()
    X_PE = inputs.X_PE.GetAsMatrix4()
    p_PT = (X_PE @ np.linalg.inv(X_BE) @ X_BT)[:, :3, 3]
    speed = np.linalg.norm(np.gradient(p_PT, samples.t, axis=0), axis=1)
    by_seam = {option.name: option.plan for option in chosen}
    for segment in samples.segments:
        plan = by_seam.get(segment.seam)
        rows = slice(segment.start, segment.stop)
        if segment.kind == "process":
            speed[rows] = plan.trajectory.tcp_speed[: segment.stop - segment.start]
        elif segment.kind == "approach" and plan.lead_in is not None:  # its last rows
            lead = plan.lead_in.tcp_speed[:-1]  # the last: the seam's first row
            speed[segment.stop - len(lead) : segment.stop] = lead
        elif segment.kind == "retract" and plan.lead_out is not None:  # its first rows
            lead = plan.lead_out.tcp_speed[: segment.stop - segment.start]
            speed[segment.start : segment.start + len(lead)] = lead
    return speed
