"""A candidate judged by ``plan``'s own pipeline (minus the exports and the clearance
plot): process frames, the Drake cell, path IK and timing, collision check and
avoidance; for a job, ``plan_job``'s: every seam, the seam order, the links from home
and back and the whole job's collision check. The terms are those of
:mod:`~offline_prog.placement.objective`.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from offline_prog.errors import Failure, InputError, PlanFailedError
from offline_prog.job.records import JobPlan, Plan
from offline_prog.placement.context import Context, placed_inputs, placed_stands
from offline_prog.placement.objective import (
    CANNOT_FOLLOW,
    COLLIDES,
    FEASIBLE,
    REFUSED,
    Evaluation,
)
from offline_prog.placement.screen import screen
from offline_prog.placement.space import Candidate
from offline_prog.plan import StageTimer, plan_loaded_job

MIN_VIOLATION = 1e-9  # [m]: a collision is never as good as none


def plan_candidate(ctx: Context, candidate: Candidate) -> JobPlan:
    """The candidate's job plan (a ``path:`` cell is a one-seam job), without the
    clearance plot.

    Raises:
        PlanFailedError: the robot cannot follow a path (or no link is found);
        InputError: geometry the method refuses.
    """
    quiet = StageTimer(lambda stage: None)
    inputs = placed_inputs(ctx, candidate)
    return plan_loaded_job(inputs, quiet, clearance_profile=False, fits=ctx.fits)


def _seam_terms(plans: list[Plan]) -> dict:
    """The objective terms a job's seams (or the one seam) give."""
    joints = [p.joints for p in plans]
    singular = [
        j.singularities[k]["distance"]
        for j in joints
        for k in ("wrist", "elbow")
        if k in j.singularities
    ]
    length = sum(p.path.length for p in plans)
    slowed = [sum(b - a for a, b, _ in j.retiming.reductions) for j in joints]
    worst = int(np.argmax(slowed))
    return {
        "joint_limit_margin_deg": float(np.rad2deg(min(np.min(j.margin_rad) for j in joints))),
        "singularity_margin_deg": float(min(singular)) if singular else 90.0,
        "tool_rotation_deg": float(np.rad2deg(plans[0].tool_rotation_rad)),
        "process_bound_s": float(sum(p.nominal_duration_s for p in plans)),
        "slowed_share": float(min(1.0, sum(slowed) / length)),
        "limiting_axis": int(joints[worst].retiming.worst[0]) + 1 if slowed[worst] > 0 else 0,
    }


def evaluate(ctx: Context, candidate: Candidate) -> Evaluation:
    """The candidate through :func:`plan_candidate`, judged (a stand that cannot stand
    there makes it infeasible before any plan: ``placement.stand``)."""
    start = time.perf_counter()
    if any(stand.reason for stand in placed_stands(ctx, candidate)):
        return dataclasses.replace(screen(ctx, candidate), stage="plan")
    try:
        plan = plan_candidate(ctx, candidate)
    except PlanFailedError as error:
        # How far along the one seam it failed (0 for a job of several, or off the seam).
        length = ctx.seams[0].fit.path.length
        done = error.failure.sigma_m / length if len(ctx.seams) == 1 else 0.0
        screened = screen(ctx, candidate)
        return Evaluation(
            candidate,
            "plan",
            CANNOT_FOLLOW,
            screened.violation + 1.0 - done,
            str(error.failure),
            error.failure.kind.value,
            seconds=time.perf_counter() - start,
        )
    except InputError as error:
        return Evaluation(
            candidate,
            "plan",
            REFUSED,
            1.0,
            error.reason,
            "refused",
            seconds=time.perf_counter() - start,
        )
    seams, t = plan.seams, plan.samples.t
    duration = float(t[-1] - t[0])
    air = duration - sum(float(p.trajectory.duration) for p in seams)
    collisions = plan.collisions
    tier, violation = FEASIBLE, 0.0
    if not plan.feasible:  # the clearance missed, or the deepest pair's depth (a fixed pair
        # may be the only one: min_distance_m covers the moving pairs)
        depth = max((pair.depth_m for pair in collisions.pairs), default=0.0)
        missed = collisions.clearance_m - collisions.min_distance_m
        tier, violation = COLLIDES, max(missed, depth, MIN_VIOLATION)
    distance = collisions.min_distance_m
    quality = plan.quality
    share = None if quality is None else quality.job.share_within_band
    return Evaluation(
        candidate,
        "plan",
        tier,
        violation,
        "" if plan.feasible else plan.failure,
        "" if plan.feasible else Failure.COLLISION.value,
        cycle_time_s=duration,
        air_time_s=max(0.0, air),
        clearance_mm=float(distance * 1e3) if math.isfinite(distance) else math.nan,
        quality_share=math.nan if quality is None else float(share or 0.0),
        seconds=time.perf_counter() - start,
        **_seam_terms(seams),
    )
