"""ABB conventions (export.abb.abb): the controller's axis values of URDF joints."""

import dataclasses

import numpy as np
import pytest

from offline_prog.export.abb.abb import abb_axes_deg
from offline_prog.robot.model import load_robot


@pytest.mark.parametrize("factor", [1.0, -1.0, 0.5])
def test_axis_3_follows_the_robots_j23_factor(factor):
    """Axis 3 = q3 + j23_factor · q2 [deg]; the other axes are the URDF joints."""
    robot = dataclasses.replace(load_robot("abb_irb2400"), j23_factor=factor)
    q = np.random.default_rng(0).uniform(-2.0, 2.0, (200, 6))
    axes = abb_axes_deg(robot, q)
    expected = np.rad2deg(q)
    expected[:, 2] = np.rad2deg(q[:, 2] + factor * q[:, 1])
    np.testing.assert_allclose(axes, expected, atol=1e-12)


def test_an_uncoupled_robot_gives_its_urdf_joints():
    robot = dataclasses.replace(load_robot("abb_irb2400"), j23_coupled=False, j23_factor=-1.0)
    q = np.random.default_rng(1).uniform(-2.0, 2.0, (50, 6))
    np.testing.assert_allclose(abb_axes_deg(robot, q), np.rad2deg(q), atol=1e-12)
