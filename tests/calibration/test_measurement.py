"""The measurement model: its analytic Jacobian equals central differences of its
residuals (all unknowns, away from the start), the flange poses are the plan's FK (the
URDF chain for a robot without a closed form gives the same), and a parameter vector
round-trips through the frames it means."""

import dataclasses

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from offline_prog.calibration.measurement import (
    Nominal,
    Problem,
    axis_rotation,
    flange_poses,
    right_jacobian,
    rotation,
)
from offline_prog.calibration.touches import Touches
from offline_prog.config.calibration_keys import CalibrationConfig
from offline_prog.robot.model import load_robot

TARGETS = ("tool_tip",) * 4 + ("tool_axis",) * 2 + ("a", "b", "c", "a")


def problem(rng) -> Problem:
    robot = load_robot("kuka_kr16_2")
    q = rng.uniform(robot.q_lower, robot.q_upper, size=(len(TARGETS), 6)) * 0.5
    touches = Touches("t.csv", TARGETS, tuple(range(2, 2 + len(TARGETS))), q)
    calibration = CalibrationConfig(
        pointer_mm=[0, 0, 250],
        tool_axis_point_mm=50.0,
        part_points={"a": [-200, -150, 0], "b": [200, -150, 0], "c": [0, 100, 5]},
    )
    nominal = Nominal(
        p_IT=np.array([1000.0, 0.0, 500.0]),
        R_IT=Rotation.random(random_state=1).as_matrix(),
        pointer=np.array([0.0, 0.0, 250.0]),
        axis_mm=50.0,
        p_PE=np.array([0.0, 0.0, 100.0]),
        R_PE=Rotation.random(random_state=2).as_matrix(),
    )
    return Problem.of(touches, flange_poses(robot, np.eye(4), q), calibration, nominal)


def test_the_jacobian_is_the_residuals_derivative(rng):
    p = problem(rng)
    assert p.blocks == ("p_IT", "pointer", "axis", "grasp_translation", "grasp_rotation")
    for _ in range(5):
        x = rng.normal(size=p.size()) * np.r_[[50.0] * 6, [0.3] * 2, [20.0] * 3, [0.5] * 3]
        step = 1e-6
        numeric = np.stack(
            [
                (p.residuals(x + step * e) - p.residuals(x - step * e)).ravel() / (2 * step)
                for e in np.eye(p.size())
            ],
            axis=1,
        )
        assert np.allclose(p.jacobian(x), numeric, atol=1e-5 * np.abs(numeric).max())


def test_a_parameter_vector_round_trips_through_its_frames(rng):
    p = problem(rng)
    x = rng.normal(size=p.size()) * 0.1
    assert np.allclose(p.start(p.values(x)), x, atol=1e-12)
    assert np.allclose(p.values(np.zeros(p.size()) + p.start(p.values(x))).R_PE, p.values(x).R_PE)


def test_the_tilt_keeps_the_turn_about_the_axis(rng):
    """The tilt is the smallest rotation from the cell's z axis of T to the touched one:
    its rotation axis is perpendicular to z, so nothing turns about the tool's axis."""
    R = Rotation.random(random_state=3).as_matrix()
    a = np.array([0.02, -0.05])
    tilted = axis_rotation(R, a)
    turn = Rotation.from_matrix(tilted @ R.T).as_rotvec()
    assert abs(turn @ R[:, 2]) < 1e-12  # no turn about the cell's axis
    z = R[:, 2] + R[:, :2] @ a
    assert np.allclose(tilted[:, 2], z / np.linalg.norm(z))


def test_rotations_equal_scipys(rng):
    for _ in range(20):
        w = rng.normal(size=3)
        assert np.allclose(rotation(w), Rotation.from_rotvec(w).as_matrix(), atol=1e-12)
        dw = rng.normal(size=3) * 1e-7
        # exp(w + dw) = exp(w) exp(J_r(w) dw)
        left = rotation(w + dw)
        right = rotation(w) @ rotation(right_jacobian(w) @ dw)
        assert np.allclose(left, right, atol=1e-13)


@pytest.mark.parametrize("name", ["kuka_kr16_2", "abb_irb2400", "ur10e"])
def test_the_urdf_chain_gives_the_same_flange_poses(rng, name):
    """A robot without a closed form (family drake) is measured through its URDF chain:
    for the bundled robots it equals the analytic FK the plan uses."""
    robot = load_robot(name)
    q = rng.uniform(robot.q_lower, robot.q_upper, size=(50, 6))
    X_IB = np.eye(4)
    X_IB[:3, 3] = [0.1, -0.2, 0.3]
    chain = dataclasses.replace(robot, params=None, family="drake")
    assert np.allclose(flange_poses(robot, X_IB, q), flange_poses(chain, X_IB, q), atol=1e-9)
