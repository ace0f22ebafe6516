"""The plan folder of a whole job (``seams:``): trajectory.csv with a ``segment``
column, report.json per seam and per link with the job's cycle time split into process
and air time, collisions.json of the whole job, and the joint-trajectory programs with
the segment and process I/O columns.

Written like the one-seam folder (``plan_folder``): staged, swapped in whole, and a
folder holding files we did not write is refused.
"""

from __future__ import annotations

import datetime
import io
import json
from pathlib import Path

import numpy as np

from offline_prog import __version__
from offline_prog.atomic import staged_folder, write_atomic, write_manifest
from offline_prog.collision.check import write_collisions_json
from offline_prog.export.formats import PROGRAMS_DIR
from offline_prog.plan import JobPlan
from offline_prog.results.plan_folder import check_out_dir
from offline_prog.results.report import collision_summary, report


def job_table(job: JobPlan) -> tuple[list[str], list[list[str]]]:
    """trajectory.csv's header and rows: t_s, segment, path_m, tcp_speed_m_s, q1..q6
    [rad], qd1..qd6 [rad/s], then do<n> (0/1) and ao<n> when the tool has process I/O."""
    s, io_ = job.samples, job.io
    header = ["t_s", "segment", "path_m", "tcp_speed_m_s"]
    header += [f"q{i + 1}" for i in range(6)] + [f"qd{i + 1}" for i in range(6)]
    columns = [s.t, s.labels(), s.path_m, job.tcp_speed, *s.q.T, *s.qd.T]
    process_io = job.cell.tool.process_io
    if io_.digital is not None:
        header.append(f"do{process_io.on.digital_output}")
        columns.append(io_.digital)
    if io_.analog is not None:
        header.append(f"ao{process_io.flow.analog_output}")
        columns.append(io_.analog)
    return header, columns


def trajectory_csv(job: JobPlan) -> str:
    """CSV text of :func:`job_table` (SI units; path_m empty on links)."""
    header, columns = job_table(job)
    out = io.StringIO()
    out.write(",".join(header) + "\n")
    text = [
        c if c.dtype == object else np.char.mod("%.10g", c.astype(float)) for c in columns
    ]
    table = np.column_stack(text)
    table[table == "nan"] = ""
    out.writelines(",".join(row) + "\n" for row in table)
    return out.getvalue()


def _segment_times(job: JobPlan) -> dict[str, float]:
    total = {"process": 0.0, "approach": 0.0, "retract": 0.0, "link": 0.0}
    for segment in job.samples.segments:
        total[segment.kind] += segment.t_stop - segment.t_start
    return total


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
                "min_clearance_m": getattr(link, "min_clearance_m", None),
                "planning_time_s": getattr(link, "planning_time_s", None),
                "t_start_s": segment.t_start,
            }
        )
    io_ = job.io
    return {
        "generator": f"offline_prog {__version__}",
        "generated": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "cell": str(job.cell_file),
        "name": job.cell.name,
        "robot": job.cell.robot.model,
        "tool": job.cell.tool.name,
        "part": job.cell.part.name,
        "job": {
            "home_deg": np.rad2deg(job.robot.controller_joints(job.q_home)).tolist(),
            "order_mode": job.cell.job.order,
            "order": [
                {"seam": o.name, "direction": "reverse" if o.reverse else "forward"}
                for o in job.chosen
            ],
            "order_method": order.method,
            "estimated_air_time_s": order.air_time_s,
            "estimated_air_time_given_order_s": order.given_air_time_s,
            "estimated_saving_s": order.saved_s,
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
            for e in io_.events
        ],
        "seams": [{"seam": o.name, **report(o.plan)} for o in job.chosen],
        **collision_summary(job),
        "timings_s": job.timings_s,
    }


def write_job_outputs(job: JobPlan, out_dir: Path) -> tuple[dict[str, Path], dict]:
    """Write the job's plan folder; returns the files by name and the report."""
    out_dir = Path(out_dir)
    check_out_dir(out_dir)
    with staged_folder(out_dir) as folder:
        summary = job_report(job)
        files = {
            "trajectory": folder / "trajectory.csv",
            "report": folder / "report.json",
            "collisions": folder / "collisions.json",
        }
        write_atomic(files["trajectory"], trajectory_csv(job))
        write_atomic(files["report"], json.dumps(summary, indent=2) + "\n")
        write_collisions_json(job.collisions, files["collisions"])
        if job.feasible:
            programs = folder / PROGRAMS_DIR
            programs.mkdir()
            files["csv:joint_trajectory.csv"] = programs / "joint_trajectory.csv"
            write_atomic(files["csv:joint_trajectory.csv"], trajectory_csv(job))
        names = sorted({path.relative_to(folder).parts[0] for path in files.values()})
        write_manifest(folder, {"plan": names})
    return {key: out_dir / path.relative_to(folder) for key, path in files.items()}, summary
