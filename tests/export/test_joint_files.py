"""joint_trajectory.json is written as one %-format over its points (ros_json_text):
the same text, byte for byte, as json.dumps of the whole JointTrajectory message with
its points as dicts (how it was written before), on a demo job and on the values JSON
writes in its own way (NaN, infinities, −0.0, the extremes of a float)."""

import dataclasses
import json

import numpy as np
import pytest

from offline_prog.export.job_program import JobProgramData
from offline_prog.export.joint_files import job_ros_json, ros_json, ros_json_text


def points(data) -> list[dict]:
    """The message's points as dicts, as ROS 2's JointTrajectoryPoint."""
    out = []
    for t, q, qd in zip(data.t, data.q.tolist(), data.qd.tolist(), strict=True):
        sec, nanosec = divmod(int(round(t * 1e9)), 1_000_000_000)
        time_from_start = {"sec": sec, "nanosec": nanosec}
        out.append(
            {
                "positions": q,
                "velocities": qd,
                "accelerations": [],
                "effort": [],
                "time_from_start": time_from_start,
            }
        )
    return out


def dumped(message: dict, data) -> str:
    return json.dumps({**message, "points": points(data)}, separators=(",", ":")) + "\n"


@pytest.fixture(scope="module")
def seal_job(planned_job):
    _, folder = planned_job("seal_job_kr16")
    return JobProgramData.load(folder)


def test_the_job_file_is_json_dumps_of_its_message(seal_job):
    message = job_ros_json(seal_job)
    text = ros_json_text(message, seal_job.job)
    assert text == dumped(message, seal_job.job)
    assert len(json.loads(text)["points"]) == len(seal_job.job.t)


@pytest.mark.parametrize(
    "q",
    [
        np.zeros((0, 6)),
        np.array([[np.nan, -0.0, 5e-324, 1.7976931348623157e308, np.inf, -np.inf]]),
        np.random.default_rng(0).normal(scale=3.0, size=(50, 6)),
    ],
)
def test_any_values_are_written_as_json_dumps_writes_them(seal_job, q):
    seam = seal_job.seams[0]
    data = dataclasses.replace(seam, q=q, qd=-0.5 * q, t=np.arange(len(q)) * 0.123456789123)
    message = ros_json(data)  # once: its header's comment has the time it was written
    assert ros_json_text(message, data) == dumped(message, data)
