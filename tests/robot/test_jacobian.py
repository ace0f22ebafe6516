"""The flange Jacobian from the URDF chain: FK agrees with the analytic kinematics,
J and its rate agree with finite differences, and the exact joint-path rates q′, q″
agree with central differences of the exact path IK."""

import numpy as np
import pytest

from offline_prog.config.cell import transform
from offline_prog.joints.joint_plan import BranchPath
from offline_prog.robot.jacobian import (
    jacobian,
    jacobian_rate_times,
    joint_frames,
    urdf_chain,
)
from offline_prog.robot.model import list_robots, load_robot
from offline_prog.timing.trajectory import TimeLawParameter

STEP = 1e-6


@pytest.mark.parametrize("name", list_robots())
def test_chain_forward_kinematics_is_the_analytic_one(name, rng):
    robot = load_robot(name)
    q = rng.uniform(robot.q_lower, robot.q_upper, (1000, 6))
    _, _, X_BE = joint_frames(urdf_chain(robot.urdf_path, robot.joint_names), q)
    assert np.abs(X_BE - robot.forward(q)).max() < 1e-12


@pytest.mark.parametrize("name", list_robots())
def test_jacobian_and_its_rate_match_finite_differences(name, rng):
    robot = load_robot(name)
    chain = urdf_chain(robot.urdf_path, robot.joint_names)
    q = rng.uniform(robot.q_lower, robot.q_upper, (200, 6))
    dq = rng.normal(size=(200, 6))
    z, p, X = joint_frames(chain, q)
    plus, minus = joint_frames(chain, q + STEP * dq), joint_frames(chain, q - STEP * dq)
    v = (plus[2][:, :3, 3] - minus[2][:, :3, 3]) / (2 * STEP)
    W = (plus[2][:, :3, :3] - minus[2][:, :3, :3]) / (2 * STEP) @ X[:, :3, :3].transpose(0, 2, 1)
    w = np.stack([W[:, 2, 1], W[:, 0, 2], W[:, 1, 0]], axis=1)
    J = jacobian(z, p, X[:, :3, 3])
    assert np.abs(np.einsum("nij,nj->ni", J, dq) - np.hstack([w, v])).max() < 1e-7
    J_rate = jacobian(*plus[:2], plus[2][:, :3, 3]) - jacobian(*minus[:2], minus[2][:, :3, 3])
    expected = np.einsum("nij,nj->ni", J_rate / (2 * STEP), dq)
    assert np.abs(jacobian_rate_times(z, p, X[:, :3, 3], dq) - expected).max() < 1e-6


def test_exact_joint_rates_match_differences_of_the_path_ik(planned_folder):
    plan, _ = planned_folder("seal_plate_kr16")
    parameter = TimeLawParameter(plan.flange, plan.cell.motion.speed_reference)
    path = BranchPath(
        plan.robot, transform(plan.cell.robot.X_IB), plan.flange, parameter, plan.joints.branch
    )
    sigma = np.linspace(0.01, parameter.length - 0.01, 400)
    q_near = np.column_stack(
        [np.interp(sigma, plan.trajectory.law_position, plan.joints.q[:, k]) for k in range(6)]
    )
    rates = path.rates(sigma, q_near)
    h = 3e-5
    q_minus, q_plus = path.q(sigma - h, rates.q), path.q(sigma + h, rates.q)
    dq = (q_plus - q_minus) / (2 * h)
    ddq = (q_plus - 2 * rates.q + q_minus) / h**2
    scale = np.abs(rates.dq).max()
    assert np.abs(rates.dq - dq).max() < 1e-4 * scale  # O(h²) of the differences
    assert np.abs(rates.ddq - ddq).max() < 1e-3 * np.abs(rates.ddq).max()
