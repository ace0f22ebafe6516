"""The plan folder of a whole job (``seams:``): trajectory.csv with a ``segment``
column, report.json per seam and per link with the job's cycle time split into process
and air time, collisions.json of the whole job, and the joint-trajectory programs with
the segment and process I/O columns.

Written like the one-seam folder (``plan_folder``): staged, swapped in whole, and a
folder holding files we did not write is refused.
"""

from __future__ import annotations

import datetime
import json
from pathlib import Path

import numpy as np

from offline_prog import __version__
from offline_prog.arrays import csv_text
from offline_prog.atomic import staged_folder, write_atomic, write_manifest
from offline_prog.collision.check import write_collisions_json
from offline_prog.config.cell import transform
from offline_prog.export.formats import PROGRAMS_DIR, export, job_formats
from offline_prog.export.job_program import JobProgramData, JobSegment
from offline_prog.export.program import PLAN_FILE, ProgramData
from offline_prog.job.records import JobPlan
from offline_prog.job.seams import job_config, job_seams
from offline_prog.results.plan_folder import (
    InParallel,
    check_out_dir,
    clearance_csv,
    program_data,
    program_names,
    time_law_name,
)
from offline_prog.results.report import collision_summary, payload_summary, report
from offline_prog.results.timing_bound import timing_bound_report
from offline_prog.timing.trajectory import CSV_COLUMNS, tait_bryan_xyz
from offline_prog.viz.job_preview import write_job_preview_html
from offline_prog.viz.job_report_html import write_job_report_html


def flange_table(job: JobPlan) -> np.ndarray:
    """(N, len(CSV_COLUMNS)) the one-seam trajectory.csv columns on every row of the job:
    on the seams the seams' own exact values (σ the arc length); elsewhere the flange
    pose X_IE from forward kinematics and its rates by central differences in t, with
    ``sigma`` the signed path position (NaN on links)."""
    s = job.samples
    X_IE = transform(job.cell.robot.X_IB).GetAsMatrix4() @ job.robot.forward(s.q)
    p, R = X_IE[:, :3, 3], X_IE[:, :3, :3]
    v = np.gradient(p, s.t, axis=0)
    W = np.gradient(R, s.t, axis=0) @ np.swapaxes(R, 1, 2)  # skew(w) = Ṙ Rᵀ
    w = 0.5 * np.stack(
        [W[:, 2, 1] - W[:, 1, 2], W[:, 0, 2] - W[:, 2, 0], W[:, 1, 0] - W[:, 0, 1]], axis=1
    )
    table = np.column_stack(
        [
            s.t,
            s.path_m,
            p,
            tait_bryan_xyz(R),
            v,
            w,
            np.gradient(v, s.t, axis=0),
            job.tcp_speed,
            np.gradient(w, s.t, axis=0),
        ]
    )
    by_seam = {option.name: option.plan.trajectory for option in job.chosen}
    for segment in s.segments:
        if segment.kind == "process":
            rows = slice(segment.start, segment.stop)
            exact = by_seam[segment.seam].table()[: segment.stop - segment.start]
            table[rows, 1:] = exact[:, 1:]  # the job's own clock in column t
    return table


def job_table(job: JobPlan) -> tuple[list[str], list[np.ndarray]]:
    """trajectory.csv's header and columns: the one-seam columns (``CSV_COLUMNS``),
    then ``segment`` (link, approach:<seam>, process:<seam>, retract:<seam>: the
    contract), q1..q6 [rad], qd1..qd6 [rad/s], do<n> (0/1) and ao<n> (the flow
    value) when the tool has process I/O, and the process quality (its model's column,
    e.g. ``bead_area_mm2``, in that unit; empty off the dispensing rows) with a
    process model."""
    s, io_ = job.samples, job.io
    header = [*CSV_COLUMNS, "segment"]
    header += [f"q{i + 1}" for i in range(6)] + [f"qd{i + 1}" for i in range(6)]
    columns = [*flange_table(job).T, s.labels(), *s.q.T, *s.qd.T]
    if io_.digital is not None:
        header.append(f"do{io_.settings.digital_output}")
        columns.append(io_.digital)
    if io_.analog is not None:
        header.append(f"ao{io_.settings.analog_output}")
        columns.append(io_.analog)
    if job.quality is not None:
        header.append(job.quality.model.column)
        columns.append(job.quality.column)
    return header, columns


def trajectory_csv(job: JobPlan) -> str:
    """CSV text of :func:`job_table` (SI units; sigma empty on links)."""
    header, columns = job_table(job)
    columns = [c if c.dtype == object else c.astype(float) for c in columns]
    return csv_text(header, columns, nan="")


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


def write_job_outputs(job: JobPlan, out_dir: Path) -> tuple[dict[str, Path], dict]:
    """Write the job's plan folder; returns the files by name and the report."""
    out_dir = Path(out_dir)
    check_out_dir(out_dir)
    with staged_folder(out_dir) as folder:
        files = {"preview": folder / "preview.html", "trajectory": folder / "trajectory.csv"}

        def beside() -> None:  # what needs nothing else written here
            write_atomic(files["trajectory"], trajectory_csv(job))
            write_job_preview_html(job, files["preview"])

        # The second core writes trajectory.csv and draws preview.html. An error or
        # Ctrl-C in the block stops it before the staged folder goes.
        with InParallel(beside) as child:
            summary = _write_rest(job, folder, files)
            child.wait()
        # After the programs and trajectory.csv, which it reads; it names the folder
        # the user gets, not the staged one.
        files["report_html"] = write_job_report_html(folder, folder_name=out_dir.name)
        names = sorted({path.relative_to(folder).parts[0] for path in files.values()})
        write_manifest(folder, {"plan": names})
    return {key: out_dir / path.relative_to(folder) for key, path in files.items()}, summary


def _write_rest(job: JobPlan, folder: Path, files: dict[str, Path]) -> dict:
    """Everything but trajectory.csv, preview.html and report.html into the staged
    ``folder``, adding to ``files``; returns the report."""
    summary = job_report(job)
    files |= {"report": folder / "report.json", "collisions": folder / "collisions.json"}
    write_atomic(files["report"], json.dumps(summary, indent=2) + "\n")
    write_collisions_json(job.collisions, files["collisions"])
    if job.clearance_profile is not None:
        files["clearance"] = folder / "clearance.csv"
        write_atomic(files["clearance"], clearance_csv(*job.clearance_profile))
    data = job_program_data(job, summary)
    files["job"] = data.save(folder)
    files["plan"] = folder / PLAN_FILE
    if data.feasible:  # no program from a failed plan (offline-prog export --force can)
        for fmt in job_formats(data.language):
            for file in export(data, fmt, folder / PROGRAMS_DIR):
                files[f"{fmt}:{file.name}"] = file
    return summary


def job_program_data(job: JobPlan, summary: dict) -> JobProgramData:
    """The job as the program writers need it (poses in the robot base B)."""
    cell, robot, s = job.cell, job.robot, job.samples
    X_BI = transform(cell.robot.X_IB).inverse().GetAsMatrix4()
    X_BT = X_BI @ transform(cell.tool.X_IT).GetAsMatrix4()
    X_EP = transform(cell.part.X_PE).inverse().GetAsMatrix4()
    X_BE = robot.forward(s.q)
    X_PT = np.linalg.inv(np.linalg.inv(X_BT) @ X_BE @ X_EP)  # the tool T in P, every row
    rows = ProgramData(
        **program_names(cell, job.cell_file, robot, summary),
        speed_reference=cell.motion.speed_reference,
        cycle_time_s=float(s.t[-1]),
        time_law=time_law_name(cell.motion),
        feasible=job.feasible,
        failure=job.failure,
        t=s.t,
        sigma=s.path_m,
        q=s.q,
        qd=s.qd,
        X_BE=X_BE,
        X_PF=X_PT,
        X_BT=X_BT,
        X_EP=X_EP,
        tcp_speed=job.tcp_speed,
        whole_job=True,
    )
    return JobProgramData(
        job=rows,
        segments=tuple(JobSegment(g.kind, g.seam, g.start, g.stop) for g in s.segments),
        seams=tuple(program_data(o.plan, summary) for o in job.chosen),
        seam_names=tuple(o.name for o in job.chosen),
        seam_lengths_m=tuple(o.plan.path.length for o in job.chosen),
        link_waypoints=tuple(np.asarray(link.waypoints, dtype=float) for link in job.links),
        process_io=job.io.settings,
        digital=job.io.digital,
        analog=job.io.analog,
        events=tuple(job.io.events),
    )
