"""The screen: a candidate judged without a plan, cheaply (~30 ms a seam) and soundly.

``screen``: the stands (``placement.stand``: a length outside its limit rules the
candidate out), then for every seam the joint paths of every tool turn and branch the
planner may take (``placement.variants``). A seam that no variant reaches rules the
candidate out ("reach"); one that no reaching variant keeps inside the joint limits,
too ("joint_limit"): no plan could follow it. Otherwise the candidate gets the lower
bound of its cycle time and the steady-speed estimate (``placement.bound``); it is
feasible for the screen when the planner's first variant is (continuous along the
path as the planner tests it).

``rank`` (the candidates the screen ranks best): the cheaper law
(``placement.cheap_law``) on the planner's variant instead of the steady estimate, and
the coarse collision look (``placement.collision_look``), whose fixed layout in
contact rules the candidate out ("collision").
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from offline_prog.job.approach import lead_covers_m
from offline_prog.job.seams import job_config, job_seams
from offline_prog.joints.path_ik import singularity_distances
from offline_prog.placement.bound import SeamTimes, end_moves_s, job_times, seam_times
from offline_prog.placement.cheap_law import law_seam_s
from offline_prog.placement.collision_look import collision_look, look_rows
from offline_prog.placement.context import Context, placed_inputs, placed_stands, rigid
from offline_prog.placement.objective import (
    CANNOT_FOLLOW,
    FEASIBLE,
    STAND,
    Evaluation,
)
from offline_prog.placement.space import Candidate
from offline_prog.placement.variants import SeamVariants, seam_variants
from offline_prog.stages import build_scene


def home_c(ctx: Context) -> np.ndarray:
    """(6,) the job's home in the controller's axes [rad] (``job.home`` or the
    robot's; ``job.home.home_pose`` checks it when a candidate is planned)."""
    robot, home = ctx.inputs.robot, job_config(ctx.inputs.cell).home
    if home is not None:
        return np.deg2rad(np.asarray(home.joints_deg, dtype=float))
    return np.asarray(robot.home_c, dtype=float)


def _violation(v: SeamVariants) -> float:
    """How far the seam's closest variant is from feasible: the share of its rows out
    of reach plus the mean distance beyond reach [m], or its joint-limit excess / π, or
    0.5 for a flip."""
    unreachable = 1.0 - v.reach_share + v.reach_excess.mean(axis=1)[:, None]  # (A, 8)
    beyond = np.where(v.reach, np.maximum(0.0, -v.margin) / math.pi, 0.0)
    flipped = np.where(v.usable & v.flips, 0.5, 0.0)
    return float(np.min(unreachable + beyond + flipped))


def _seam_verdict(v: SeamVariants) -> tuple[str, str]:
    """(screened out by: "reach" | "joint_limit" | "", the reason) of one seam."""
    if not v.reach.any():
        return "reach", "out of reach"
    if not v.usable.any():
        return "joint_limit", "joint limit on every tool turn and branch"
    if v.planner_choice() is None:
        return "", "singularity (the configuration flips) on every tool turn and branch"
    return "", ""


def _variants(ctx: Context, candidate: Candidate) -> list[tuple[SeamVariants, SeamTimes]]:
    X_IT, X_PE = rigid(candidate.X_IT), rigid(candidate.X_PE)
    found = []
    for view, seam in zip(ctx.seams, job_seams(ctx.inputs.cell), strict=True):
        v = seam_variants(view, seam, X_IT, X_PE)
        found.append((v, seam_times(v, view.inputs, seam)))
    return found


def screen(ctx: Context, candidate: Candidate) -> Evaluation:
    """The candidate screened (see the module)."""
    return _judged(ctx, candidate, time.perf_counter())[0]


def _judged(ctx: Context, candidate: Candidate, start: float):
    """(the screen's Evaluation, each seam's (variants, times) or [] for a stand)."""
    stands = [s for s in placed_stands(ctx, candidate) if s.reason]
    if stands:
        excess = sum(max(s.length_m - ctx.stand_max_m, -s.length_m, 0.0) for s in stands)
        judged = Evaluation(
            candidate,
            "screen",
            STAND,
            excess,
            stands[0].reason,
            "stand",
            screened_out="stand",
            bound_s=math.inf,
            seconds=time.perf_counter() - start,
        )
        return judged, []
    seams = _variants(ctx, candidate)
    verdicts = [_seam_verdict(v) for v, _ in seams]
    bound, estimate = job_times([t for _, t in seams], home_c(ctx), ctx.inputs.robot)
    out = next((by for by, _ in verdicts if by), "")
    reason = next((why for _, why in verdicts if why), "")
    if reason:
        kinds = {"reach": "out_of_reach", "joint_limit": "joint_limit"}
        judged = Evaluation(
            candidate,
            "screen",
            CANNOT_FOLLOW,
            sum(_violation(v) for v, _ in seams),
            reason,
            kinds.get(out, "singularity"),
            screened_out=out,
            bound_s=math.inf if out else bound,
            seconds=time.perf_counter() - start,
        )
        return judged, seams
    margins, singular = [], []
    for v, t in seams:
        margins.append(v.margin[t.choice])
        singular.append(_singularity_deg(ctx, v, t))
    judged = Evaluation(
        candidate,
        "screen",
        FEASIBLE,
        0.0,
        "",
        cycle_time_s=estimate,
        joint_limit_margin_deg=float(np.rad2deg(min(margins))),
        singularity_margin_deg=min(singular),
        tool_rotation_deg=float(np.rad2deg(seams[0][0].angles[seams[0][1].choice[0]])),
        bound_s=bound,
        seconds=time.perf_counter() - start,
    )
    return judged, seams


def _singularity_deg(ctx: Context, v: SeamVariants, t: SeamTimes) -> float:
    """The smallest wrist or elbow angle from singular on the planner's variant [deg]."""
    robot = ctx.inputs.robot
    q = v.q[t.choice][1:-1]
    X_BE = robot.forward(q)
    d = singularity_distances(robot, q, X_BE)
    return float(np.rad2deg(np.arcsin(min(1.0, d["wrist"].min(), d["elbow"].min()))))


def rank(ctx: Context, candidate: Candidate) -> Evaluation:
    """The screen with the cheaper law's estimate and the coarse collision look."""
    start = time.perf_counter()
    screened, seams = _judged(ctx, candidate, start)
    if not screened.feasible:
        return dataclasses.replace(screened, stage="rank")
    X_IT, X_PE = rigid(candidate.X_IT), rigid(candidate.X_PE)
    times = []
    for view, seam, (v, t) in zip(ctx.seams, job_seams(ctx.inputs.cell), seams, strict=True):
        law, flange = law_seam_s(view, v, X_IT, X_PE)  # a flying seam's leads included
        covered = (0.0, 0.0) if flange is None else lead_covers_m(flange, seam)
        moves = end_moves_s(seam, view.inputs, covered=covered)
        times.append(dataclasses.replace(t, estimate_s=law + moves))
    _, estimate = job_times(times, home_c(ctx), ctx.inputs.robot)
    inputs = placed_inputs(ctx, candidate)
    motion = inputs.cell.motion
    rows = np.concatenate([look_rows(v.q[t.choice]) for v, t in seams])
    look = collision_look(
        build_scene(inputs), rows, clearance=motion.clearance, self_clearance=motion.self_clearance
    )
    ranked = dataclasses.replace(
        screened,
        stage="rank",
        cycle_time_s=estimate,
        collides=look.first_collides,
        seconds=time.perf_counter() - start,
    )
    if not look.layout:
        return ranked
    return dataclasses.replace(
        ranked,
        tier=CANNOT_FOLLOW,
        violation=1.0,
        reason=f"the layout collides: {look.layout}",
        failure="collision",
        screened_out="collision",
        bound_s=math.inf,
        cycle_time_s=math.nan,
    )
