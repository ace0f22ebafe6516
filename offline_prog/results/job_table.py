"""trajectory.csv of a job: the one-seam columns on every row, the segment, the joints,
the process outputs and the process quality.
"""

from __future__ import annotations

import numpy as np

from offline_prog.arrays import csv_text
from offline_prog.config.cell import transform
from offline_prog.job.records import JobPlan
from offline_prog.timing.trajectory import CSV_COLUMNS, tait_bryan_xyz


def flange_table(job: JobPlan) -> np.ndarray:
    """(N, len(CSV_COLUMNS)) the one-seam trajectory.csv columns on every row of the job:
    on the seams the seams' own exact values (σ the arc length); elsewhere the flange
    pose X_IE the plan computed (``JobPlan.X_BE``) and its rates by central differences
    in t, with ``sigma`` the signed path position (NaN on links)."""
    s = job.samples
    X_IE = transform(job.cell.robot.X_IB).GetAsMatrix4() @ job.X_BE
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
