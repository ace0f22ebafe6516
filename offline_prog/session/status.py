"""The status line of a session's plan: feasible or why not, and its key figures.

One line for the panel, and the same figures as numbers (``details``) for tests and
tools: feasible, the failure (σ, t, why), cycle time, minimum clearance and its pair,
the smallest joint-limit margin, the samples per state, what was re-planned and how
long it took.
"""

from __future__ import annotations

import numpy as np

from offline_prog.session.sample_states import counts, sample_states


def plan_status(result, seam: str = "") -> dict:
    """{"kind", "line", "details"} of a SessionPlan (of ``seam`` of a job, if named).

    kind: "feasible", "collision" (a plan that fails its collision check), "failed"
    (no joint plan: out of reach, a limit, a singularity) or "error" (the cell as set
    cannot be planned: bad geometry).
    """
    timing = f"planned in {result.seconds:.2f} s (ran: {', '.join(result.ran) or 'nothing'})"
    details = {"seconds": result.seconds, "ran": result.ran, "feasible": False}
    status = _status(result, timing, details)
    if seam:
        status["line"] = f"seam {seam}: {status['line']}"
    return status


def _status(result, timing: str, details: dict) -> dict:
    plan = result.plan
    if plan is None:
        failure = result.failure
        if failure is not None:
            details.update(sigma_m=failure.sigma_m, t_s=failure.t_s, reason=failure.reason)
            line = (
                f"FAILED at σ = {failure.sigma_m * 1e3:.1f} mm, t = {failure.t_s:.3f} s: "
                f"{failure.reason} · {timing}"
            )
            return {"kind": "failed", "line": line, "details": details}
        details["reason"] = result.error
        return {
            "kind": "error",
            "line": f"cannot plan: {result.error} · {timing}",
            "details": details,
        }
    collisions, joints = plan.collisions, plan.joints
    margin_deg = float(np.rad2deg(np.min(joints.margin_rad)))
    closest = collisions.closest
    details.update(
        feasible=plan.feasible,
        cycle_time_s=float(plan.trajectory.duration),
        min_distance_m=None if closest is None else float(collisions.min_distance_m),
        closest_pair=None if closest is None else [closest.a, closest.b],
        closest_sigma_m=None if closest is None else closest.sigma_m,
        joint_limit_margin_deg=margin_deg,
        samples=counts(sample_states(plan)),
        failure=plan.failure,
    )
    clearance = (
        "no checked pairs"
        if closest is None
        else f"min clearance {collisions.min_distance_m * 1e3:.1f} mm "
        f"({closest.a} vs {closest.b} at σ = {closest.sigma_m * 1e3:.1f} mm)"
    )
    figures = (
        f"cycle {plan.trajectory.duration:.2f} s · {clearance} · joint-limit margin "
        f"{margin_deg:.1f}° · {timing}"
    )
    if plan.feasible:
        return {"kind": "feasible", "line": f"feasible · {figures}", "details": details}
    return {"kind": "collision", "line": f"FAILS: {plan.failure} · {figures}", "details": details}
