"""A job's joint trajectory as files for every robot: CSV with units in the header
(``--format csv``), and JSON shaped like ROS 2 ``trajectory_msgs/msg/JointTrajectory``
(``--format ros-json``), each with the segment and process I/O of every row."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np

from offline_prog.arrays import csv_text
from offline_prog.atomic import write_atomic
from offline_prog.export.header import header_lines
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.program import ProgramData

FILE_STEM = "joint_trajectory"


_POINTS = "@points@"  # where ros_json_text puts the points into the message's text
_POINT = (
    '{"positions":[%s],"velocities":[%s],"accelerations":[],"effort":[],'
    '"time_from_start":{"sec":%d,"nanosec":%d}}'
)


def ros_json(data: ProgramData) -> dict:
    """A JointTrajectory message as JSON, but for its points (see
    :func:`ros_json_text`, which fills them in): the joint names from the URDF."""
    return {
        "header": {"frame_id": "base_link", "stamp": {"sec": 0, "nanosec": 0}},
        "joint_names": list(data.joint_names),
        "points": _POINTS,
        "comment": header_lines(data, conventions=["Units: rad, rad/s, s."]),
    }


def ros_json_text(message: dict, data: ProgramData) -> str:
    """The file's text: ``message`` (:func:`ros_json`, maybe with more keys) as compact
    JSON, with one point per planned sample: positions [rad], velocities [rad/s],
    time_from_start {sec, nanosec} (ROS 2 Duration). The same text as json.dumps of the
    whole message with its points as dicts (separators "," and ":"), in 60 % of the
    time: each row's numbers come from one json.dumps of the table, and the points from
    one %-format."""
    ns = np.rint(np.asarray(data.t, dtype=float) * 1e9).astype(np.int64)  # = round(t · 1e9)
    sec, nanosec = np.divmod(ns, 1_000_000_000)
    rows = [_rows(data.q), _rows(data.qd), sec.tolist(), nanosec.tolist()]
    points = ",".join([_POINT] * len(ns)) % tuple(
        itertools.chain.from_iterable(zip(*rows, strict=True))
    )
    text = json.dumps(message, separators=(",", ":"))
    return text.replace(f'"points":"{_POINTS}"', f'"points":[{points}]', 1) + "\n"


def _rows(values: np.ndarray) -> list[str]:
    """Each row of (N, n) as json.dumps writes its numbers, comma-separated."""
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return [""] * len(values)
    return json.dumps(values.tolist(), separators=(",", ":"))[2:-2].split("],[")


def joint_csv_text(data: JobProgramData) -> str:
    """``t_s,segment,<joint>_rad,...[,do<n>][,ao<n>]``: one row per planned sample of a
    job, the segment label (link, approach:<seam>, process:<seam>, retract:<seam>) and
    the process outputs (0/1 and the flow value) on each row."""
    job, io = data.job, data.process_io
    labels = np.empty(len(job.t), dtype=object)
    for segment in data.segments:
        labels[segment.start : segment.stop] = segment.label
    header = ["t_s", "segment", *(f"{name}_rad" for name in job.joint_names)]
    columns, formats = [job.t, labels.astype(str), *job.q.T], ["%.10g"] * (2 + job.q.shape[1])
    if data.digital is not None:
        header.append(f"do{io.digital_output}")
        columns.append(data.digital)
        formats.append("%d")
    if data.analog is not None:
        header.append(f"ao{io.analog_output}")
        columns.append(data.analog)
        formats.append("%.6g")
    return csv_text(header, columns, formats)


def job_ros_json(data: JobProgramData) -> dict:
    """The job's JointTrajectory (as :func:`ros_json`) plus ``segments`` (label and the
    index range [start, stop) of its points) and, with process I/O, ``process_io`` (the
    output numbers and each point's values)."""
    message = ros_json(data.job)
    message["segments"] = [
        {"segment": s.label, "start": s.start, "stop": s.stop} for s in data.segments
    ]
    io = data.process_io
    if io is not None:
        message["process_io"] = {
            "digital_output": io.digital_output,
            "digital": None if data.digital is None else data.digital.astype(int).tolist(),
            "analog_output": io.analog_output,
            "analog": None if data.analog is None else [float(v) for v in data.analog],
        }
    return message


def write_joint_csv(data: JobProgramData, out_dir: Path) -> list[Path]:
    """``joint_trajectory.csv`` (:func:`joint_csv_text`) in out_dir."""
    file = Path(out_dir) / f"{FILE_STEM}.csv"
    write_atomic(file, joint_csv_text(data))
    return [file]


def write_ros_json(data: JobProgramData, out_dir: Path) -> list[Path]:
    """``joint_trajectory.json`` (:func:`job_ros_json`) in out_dir."""
    file = Path(out_dir) / f"{FILE_STEM}.json"
    write_atomic(file, ros_json_text(job_ros_json(data), data.job))
    return [file]
