"""report.json's ``quality.timing_bound``: what the process model asked of the time law
and what it cost (issue 28's feedback into timing).

The cycle time with and without the bound is computed by timing both laws: each
seam's process stretch is timed on the same path and joint rates under the process
model's caps (the plan) and under ``motion.max_acceleration`` / ``max_jerk`` alone
(``JointTrajectory.unbounded_s``). The bound changes nothing else of the job (the
approach, retract, links and the seam order depend on the seams' ends, not on their
timing), so the cycle time without it is the planned one less the sum of the process
stretches' differences. Where the speed falls below the speed band's low end (the
speed at which the output at its minimum, or the arc's fixed heat, still holds the
target), the time law cannot hold a minimum speed against a joint limit or a ramp from
rest: those stretches are named with their cause.
"""

from __future__ import annotations

import numpy as np

from offline_prog.arrays import true_runs
from offline_prog.job.records import JobPlan
from offline_prog.process.registry import process_model


def timing_bound_report(job: JobPlan) -> dict | None:
    """``quality.timing_bound`` of a job with a process model (None without one).

    Returns:
        applied: whether a cap was lowered on any seam; bound: which ("path jerk"),
        seams: per seam run, the caps [m/s², m/s³] (the user's and the process's), why,
        and its process time with and without the bound [s]; cycle_time_s,
        cycle_time_without_bound_s, difference_s [s]; method: how they were computed;
        speed_band_m_s: [low, high] TCP speeds at which the output can hold the
        target; below_speed_band: the process stretches below its low end (seam,
        σ and t ranges [m, s], the lowest speed [m/s], cause).
    """
    model = process_model(job.cell.process)
    if model is None:
        return None
    seams, saved = [], 0.0
    for option in job.chosen:
        joints = option.plan.joints
        caps, with_s = joints.process_caps, float(joints.retiming.law.duration)
        without_s = joints.unbounded_s if caps is not None and caps.bounded else with_s
        saved += with_s - without_s
        seams.append(
            {
                "seam": option.name,
                "applied": bool(caps is not None and caps.bounded),
                "path_jerk_cap_m_s3": None if caps is None else caps.j_max,
                "user_max_jerk_m_s3": None if caps is None else caps.user_j_max,
                "path_acceleration_cap_m_s2": None if caps is None else caps.a_max,
                "user_max_acceleration_m_s2": None if caps is None else caps.user_a_max,
                "reason": None if caps is None else caps.reason,
                "process_time_s": with_s,
                "process_time_without_bound_s": without_s,
            }
        )
    cycle = float(job.samples.t[-1])
    settings = job.io.settings
    low, high = model.speed_band(
        *((0.0, 0.0) if settings is None else (settings.min, settings.max))
    )
    applied = any(seam["applied"] for seam in seams)
    return {
        "applied": applied,
        "bound": "path jerk on the process stretch" if applied else None,
        "seams": seams,
        "cycle_time_s": cycle,
        "cycle_time_without_bound_s": cycle - saved,
        "difference_s": saved,
        "method": (
            "each seam's process stretch timed under both laws on the same path and joint "
            "rates; the rest of the job is the same in both"
        ),
        "speed_band_m_s": [low, high],
        "below_speed_band": _below_band(job, low),
    }


def _below_band(job: JobPlan, low: float) -> list[dict]:
    """The process stretches slower than ``low`` [m/s], each with its cause: the start
    or stop ramp (from or to rest, a seam at rest: a flying seam's are on its leads),
    else a slowdown the joints force, with the joint and limit where the time law names
    them (a minimum speed cannot beat a joint limit)."""
    if low <= 0.0:
        return []
    out = []
    samples, speed = job.samples, job.tcp_speed
    by_seam = {option.name: option.plan for option in job.chosen}
    for segment in samples.segments:
        if segment.kind != "process":
            continue
        rows = np.arange(segment.start, segment.stop)
        for a, b in true_runs(speed[rows] < low):
            stretch = rows[a:b]
            sigma = (float(samples.path_m[stretch[0]]), float(samples.path_m[stretch[-1]]))
            plan = by_seam[segment.seam]  # a flying seam's ramps are on its leads
            if a == 0 and plan.lead_in is None:
                cause = "start ramp"
            elif b == len(rows) and plan.lead_out is None:
                cause = "stop ramp"
            else:
                cause = _slowdown_cause(plan, sigma)
            out.append(
                {
                    "seam": segment.seam,
                    "sigma_start_m": sigma[0],
                    "sigma_end_m": sigma[1],
                    "t_start_s": float(samples.t[stretch[0]]),
                    "t_end_s": float(samples.t[stretch[-1]]),
                    "speed_min_m_s": float(speed[stretch].min()),
                    "cause": cause,
                }
            )
    return out


def _slowdown_cause(plan, sigma: tuple[float, float]) -> str:
    """The joint limit behind a slowdown over the seam's ``sigma`` [m] (its time law's
    ``slowdowns``, time_optimal, on the law's scale: ``Plan.law_origin``), or a plain
    "slowdown" (sin2 does not say)."""
    origin = plan.law_origin[0]
    for slow in plan.joints.retiming.slowdowns:
        a, b = slow.sigma_m[0] + origin, slow.sigma_m[1] + origin
        if slow.joint is not None and a <= sigma[1] and sigma[0] <= b:
            return (
                f"slowdown: joint {slow.joint} {slow.constraint} limit (a minimum speed "
                "cannot beat it)"
            )
    return "slowdown: a joint limit (a minimum speed cannot beat it)"
