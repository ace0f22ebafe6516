"""A robot without a closed form (family drake, e.g. an imported one whose wrist is not
spherical) may still use a symmetric tool's free rotation: the turns are tried smallest
first instead of being screened with analytic IK it does not have."""

import dataclasses

import numpy as np

from offline_prog.joints.joint_plan import tool_rotations
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import fit_path, load_inputs

from conftest import CELLS


def test_free_rotation_of_a_drake_family_robot_is_tried_smallest_first():
    inputs = load_inputs(CELLS / "seal_plate_kr16.yaml", ROBOTS_DIR)
    robot = dataclasses.replace(inputs.robot, family="drake", params=None)
    fit = fit_path(inputs)
    rotations = tool_rotations(
        robot,
        inputs.X_IB,
        fit.path,
        fit.normal,
        X_IT=inputs.X_IT,
        X_PE=inputs.X_PE,
        bound_rad=np.deg2rad(20.0),
    )
    phis = [phi for phi, _ in rotations]
    assert phis[0] == 0.0 and np.all(np.diff(np.abs(phis)) >= 0) and len(phis) == 9
