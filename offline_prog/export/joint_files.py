"""Joint trajectories as files: CSV with units in the header, and JSON shaped like
ROS 2 ``trajectory_msgs/msg/JointTrajectory``."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.export.header import header_lines
from offline_prog.export.program import ProgramData


def joint_csv_text(data: ProgramData) -> str:
    """``t_s,<joint>_rad,...`` then one row per planned sample (SI units)."""
    buffer = io.StringIO()
    header = ",".join(["t_s", *(f"{name}_rad" for name in data.joint_names)])
    np.savetxt(
        buffer,
        np.column_stack([data.t, data.q]),
        delimiter=",",
        fmt="%.10g",
        header=header,
        comments="",
    )
    return buffer.getvalue()


def ros_json(data: ProgramData) -> dict:
    """A JointTrajectory message as JSON: joint names from the URDF, positions
    [rad], velocities [rad/s], time_from_start {sec, nanosec} (ROS 2 Duration)."""
    points = []
    for t, q, qd in zip(data.t, data.q, data.qd, strict=True):
        sec, nanosec = divmod(int(round(t * 1e9)), 1_000_000_000)
        points.append(
            {
                "positions": [float(v) for v in q],
                "velocities": [float(v) for v in qd],
                "accelerations": [],
                "effort": [],
                "time_from_start": {"sec": sec, "nanosec": nanosec},
            }
        )
    return {
        "header": {"frame_id": "base_link", "stamp": {"sec": 0, "nanosec": 0}},
        "joint_names": list(data.joint_names),
        "points": points,
        "comment": header_lines(data, conventions=["Units: rad, rad/s, s."]),
    }


def write_joint_csv(data: ProgramData, out_dir: Path, name: str = "joint_trajectory") -> Path:
    file = Path(out_dir) / f"{name}.csv"
    write_atomic(file, joint_csv_text(data))
    return file


def write_ros_json(data: ProgramData, out_dir: Path, name: str = "joint_trajectory") -> Path:
    file = Path(out_dir) / f"{name}.json"
    write_atomic(file, json.dumps(ros_json(data), separators=(",", ":")) + "\n")
    return file
