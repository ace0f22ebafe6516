"""The screen: a candidate judged by the analytic path IK alone (~10 ms a seam).

For each seam, the flange path X_IE = X_IT · X_PF⁻¹ · X_PE at SCREEN_SAMPLES σ (tool
rotation 0), all eight branches at once (``joints.path_ik``); the branch closest to
feasible speaks for the seam. A feasible seam gets a cycle-time estimate at steady
speed (:func:`speed_limited_time`); a job's seams add up.
"""

from __future__ import annotations

import math
import time

import numpy as np

from offline_prog.joints.path_ik import (
    base_poses,
    branch_results,
    reach_excess,
    singularity_distances,
)
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.path.process_frames import NormalTangentError
from offline_prog.placement.context import Context, SeamView, rigid
from offline_prog.placement.objective import CANNOT_FOLLOW, FEASIBLE, REFUSED, Evaluation
from offline_prog.placement.space import Candidate


def _screen_seam(seam: SeamView, candidate: Candidate) -> Evaluation:
    inputs, fit, s = seam.inputs, seam.fit, seam.screen_s
    robot = inputs.robot
    try:
        flange = FlangePath(
            fit.path, fit.normal, X_IT=rigid(candidate.X_IT), X_PE=rigid(candidate.X_PE)
        )
        f = flange(s)
    except NormalTangentError as error:
        return Evaluation(candidate, "screen", REFUSED, 1.0, str(error), "refused")
    X_BE = base_poses(inputs.X_IB, f.p_IE, f.R_IE)
    results = branch_results(robot, X_BE)
    reach = ~np.isnan(robot.inverse(X_BE)).any(axis=-1)  # (N, 8)
    excess = float(reach_excess(robot, X_BE).mean())  # [m]

    def violation(r) -> float:
        if r.feasible:
            return 0.0
        unreachable = 1.0 - reach[:, r.branch].mean() + excess
        flipped = (1.0 - r.sample / len(s)) if r.reason.startswith("singularity") else 0.0
        beyond = max(0.0, -r.margin_rad) if math.isfinite(r.margin_rad) else math.pi
        return float(unreachable + flipped + beyond / math.pi)

    best = min(results, key=lambda r: (violation(r), -r.margin_rad))
    if not best.feasible:
        kind = best.kind.value
        return Evaluation(candidate, "screen", CANNOT_FOLLOW, violation(best), best.reason, kind)
    d = singularity_distances(robot, best.q, X_BE)
    singular = float(np.rad2deg(np.arcsin(min(1.0, d["wrist"].min(), d["elbow"].min()))))
    return Evaluation(
        candidate,
        "screen",
        FEASIBLE,
        0.0,
        "",
        cycle_time_s=speed_limited_time(seam, best.q),
        joint_limit_margin_deg=float(np.rad2deg(best.margin_rad)),
        singularity_margin_deg=singular,
    )


def screen(ctx: Context, candidate: Candidate) -> Evaluation:
    """Every seam screened; the candidate's tier is its worst seam's, violations and
    cycle-time estimates add up, margins are the smallest."""
    start = time.perf_counter()
    seams = [_screen_seam(seam, candidate) for seam in ctx.seams]
    worst = max(seams, key=lambda e: (e.tier, e.violation))
    return Evaluation(
        candidate,
        "screen",
        worst.tier,
        float(sum(e.violation for e in seams)),
        worst.reason,
        worst.failure,
        cycle_time_s=float(sum(e.cycle_time_s for e in seams)),
        joint_limit_margin_deg=min(e.joint_limit_margin_deg for e in seams),
        singularity_margin_deg=min(e.singularity_margin_deg for e in seams),
        seconds=time.perf_counter() - start,
    )


def speed_limited_time(seam: SeamView, q: np.ndarray) -> float:
    """The screen's cycle-time estimate of a seam [s]: ∫ dσ / v(σ) with v the process
    speed, lowered where a joint would pass its speed or acceleration limit at steady
    speed, v ≤ q̇max_j / |q′_j(σ)| and v ≤ √(q̈max_j / |q″_j(σ)|) (q′, q″ by differences
    of the (N, 6) joint path q [rad] on the screen's σ grid). The time law's ramps are
    left out: it ranks candidates, ``evaluate`` times them."""
    s, robot = seam.screen_s, seam.inputs.robot
    ds = np.diff(s)
    d1 = np.diff(q, axis=0) / ds[:, None]  # q′ [rad/m] between samples, (N−1, 6)
    d2 = np.zeros_like(d1)
    d2[1:] = np.diff(d1, axis=0) / ((ds[1:] + ds[:-1]) / 2)[:, None]  # q″ [rad/m²]
    with np.errstate(divide="ignore"):
        by_speed = np.min(robot.qd_max / np.abs(d1), axis=1)
        by_acceleration = np.min(np.sqrt(robot.qdd_max / np.abs(d2)), axis=1)
    v = np.minimum(seam.inputs.speed.v_m_s, np.minimum(by_speed, by_acceleration))
    return float(np.sum(ds / v))
