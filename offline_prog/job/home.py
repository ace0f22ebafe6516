"""The job's home: where the robot starts and ends, ``job.home`` or the robot's own
(``home_deg`` in its robot.yaml), checked inside the joint limits and collision-free."""

from __future__ import annotations

import numpy as np

from offline_prog.collision.check import check_trajectory
from offline_prog.errors import InputError
from offline_prog.job.seams import job_config
from offline_prog.scene.drake_cell import DrakeCell
from offline_prog.stages import Inputs


def home_pose(inputs: Inputs, scene: DrakeCell) -> np.ndarray:
    """(6,) the job's home in URDF joints [rad]: ``job.home`` or the robot's own,
    inside the joint limits and collision-free at the cell's clearances.

    Raises:
        InputError: naming ``job.home.joints_deg``.
    """
    robot, home = inputs.robot, job_config(inputs.cell).home
    key = "job.home.joints_deg"
    if home is None:
        if robot.home_c is None:
            raise InputError(
                inputs.file, "job.home", f"robot {robot.name} has no home_deg: give one"
            )
        q_c = np.asarray(robot.home_c)
    else:
        q_c = np.deg2rad(home.joints_deg)
        outside = (q_c < robot.q_lower - 1e-12) | (q_c > robot.q_upper + 1e-12)
        if outside.any():
            j = int(np.argmax(outside))
            raise InputError(
                inputs.file,
                key,
                f"axis {j + 1} = {home.joints_deg[j]:g}° is outside its limits "
                f"[{np.rad2deg(robot.q_lower[j]):g}, {np.rad2deg(robot.q_upper[j]):g}]°",
            )
    q = robot.urdf_joints(q_c)
    motion = inputs.cell.motion
    check = check_trajectory(
        scene,
        q[None, :],
        np.zeros(1),
        np.zeros(1),
        clearance=motion.clearance,
        self_clearance=motion.self_clearance,
    )
    if not check.collision_free:
        where = "job.home" if home is None else key
        hint = "; give job.home.joints_deg" if home is None else ""
        raise InputError(inputs.file, where, f"the home pose collides: {check.message}{hint}")
    return q
