"""report.json of a job: the job's order, times and segments, each link, the process
I/O switches, each seam's report (``results.report``), the process quality and the
collision check of the whole job (SI units unless the key says otherwise).
"""

from __future__ import annotations

import datetime

import numpy as np

from offline_prog import __version__
from offline_prog.job.records import JobPlan
from offline_prog.job.seams import job_config, job_seams
from offline_prog.results.report import collision_summary, payload_summary, report
from offline_prog.results.timing_bound import timing_bound_report
from offline_prog.robot.record import robot_source


def _segment_times(job: JobPlan) -> dict[str, float]:
    total = {"process": 0.0, "approach": 0.0, "retract": 0.0, "link": 0.0}
    for segment in job.samples.segments:
        total[segment.kind] += segment.t_stop - segment.t_start
    return total


def order_search_report(order) -> dict:
    """report.json ``job.order_search``: how the order (job.order.JobOrder) was found:
    method, budget and what was used of it, rounds, why it stopped, its time, and the
    estimated air time it reached against where it started and the lower bound [s]."""
    search = order.search
    return {
        "method": search.method,
        "budget_link_estimates": search.budget,
        "used_link_estimates": search.used,
        "orders_evaluated": search.orders_evaluated,
        "rounds": search.rounds,
        "descents": search.descents,
        "stopped": search.stopped,
        "min_improvement_s": search.min_improvement_s,
        "time_s": search.time_s,
        "air_time_s": order.air_time_s,
        "start_air_time_s": search.start_air_time_s,
        "lower_bound_s": search.lower_bound_s,
    }


def job_report(job: JobPlan) -> dict:
    """report.json of a job (SI units unless the key says otherwise)."""
    times, order = _segment_times(job), job.order
    cycle = float(job.samples.t[-1])
    links = []
    for link, segment in zip(
        job.links, [g for g in job.samples.segments if g.kind == "link"], strict=True
    ):
        links.append(
            {
                "name": link.name,
                "method": link.method,
                "duration_s": float(link.t[-1]),
                "length_rad": float(np.linalg.norm(np.diff(link.q, axis=0), axis=1).sum()),
                "waypoints": int(len(link.waypoints)),
                "min_clearance_m": link.min_clearance_m,
                "planning_time_s": link.planning_time_s,
                "failure": None if link.ok else link.failure.reason,
                "t_start_s": segment.t_start,
            }
        )
    io_ = job.io
    summary = {
        "generator": f"offline_prog {__version__}",
        "generated": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "cell": str(job.cell_file),
        "name": job.cell.name,
        "robot": job.cell.robot.model,
        **robot_source(job.robot),
        "tool": job.cell.tool.name,
        "part": job.cell.part.name,
        "payload": payload_summary(job.cell, job.cell_file),
        "job": {
            "home_deg": np.rad2deg(job.robot.controller_joints(job.q_home)).tolist(),
            "home_from": "job.home" if job_config(job.cell).home else "robot.yaml home_deg",
            "order_mode": job_config(job.cell).order,
            "order": [
                {
                    "seam": o.name,
                    "direction": "reverse" if o.reverse else "forward",
                    "branch": int(o.plan.joints.branch),
                    "tool_rotation_deg": float(np.rad2deg(o.plan.tool_rotation_rad)),
                    **_moves(job, o.seam),
                }
                for o in job.chosen
            ],
            "order_method": order.method,
            "options_per_seam": [len(seam) for seam in job.options],
            "estimated_air_time_s": order.air_time_s,
            "estimated_air_time_given_order_s": order.given_air_time_s,
            "estimated_saving_s": order.saved_s,
            "order_search": order_search_report(order),
            "cycle_time_s": cycle,
            "process_time_s": times["process"],
            "air_time_s": cycle - times["process"],
            "approach_retract_time_s": times["approach"] + times["retract"],
            "link_time_s": times["link"],
            "n_samples": int(len(job.samples.t)),
            "segments": [
                {"segment": g.label, "t_start_s": g.t_start, "t_end_s": g.t_stop}
                for g in job.samples.segments
            ],
        },
        "links": links,
        "process_io": [
            {
                "seam": e.seam,
                "digital_output": e.output,
                "state": "on" if e.state else "off",
                "path_m": e.path_m,
                "t_s": e.t_s,
            }
            for e in io_.switches
        ],
        "seams": [{"seam": o.name, **report(o.plan)} for o in job.chosen],
        **({} if job.quality is None else {"quality": job.quality.as_dict()}),
        **collision_summary(job),
        "timings_s": job.timings_s,
    }
    bound = timing_bound_report(job)
    if bound is not None:  # beside the predicted quality (issue 28)
        summary.setdefault("quality", {})["timing_bound"] = bound
    if not job.cell.seams:  # path: (one seam): its one-seam keys stay where they were
        for key, value in summary["seams"][0].items():
            if key != "seam":
                summary.setdefault(key, value)
    return summary


def _moves(job: JobPlan, k: int) -> dict:
    """The approach and retract of seam k as planned: kind and distance [mm] ("none",
    0 when there is none), as given in the cell or by default (normal, 50 mm)."""
    seam = job_seams(job.cell)[k]
    return {
        kind: {"kind": spec.kind, "distance_mm": 0.0 if spec.kind == "none" else spec.distance_mm}
        for kind, spec in (("approach", seam.approach), ("retract", seam.retract))
    }
