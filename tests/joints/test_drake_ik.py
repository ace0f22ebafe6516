"""Drake IK (drake_ik) against FK round trips and the analytic all-solution IK."""

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.solvers import IpoptSolver

from offline_prog.joints.drake_ik import PoseIk, rotation_angle, solve_path, solve_pose
from offline_prog.robot.model import load_robot
from offline_prog.scene.drake_cell import build_drake_cell

ROBOTS = ["ur10e", "kuka_kr16_2", "abb_irb2400"]
POSE_TOL_M = 1e-6  # accepted flange position error [m]
POSE_TOL_RAD = 1e-6  # accepted flange orientation error [rad]
JOINT_TOL_RAD = 1e-6  # accepted joint difference [rad]
# Configurations whose flange Jacobian has a smaller singular value are skipped: near a
# singularity a pose does not pin q down, so "q close to the original" cannot hold.
MIN_SINGULAR_VALUE = 0.05
SEED_NOISE_RAD = 0.01  # standard deviation of the seed's offset from the true q [rad]
UNREACHABLE_DISTANCE_M = 3.0  # beyond the reach of all three robots (≤ 1.6 m)
X_IB = RigidTransform(RollPitchYaw(0.1, -0.2, 0.7), [0.3, -0.2, 0.5])  # tilted base


@pytest.fixture(scope="module", params=ROBOTS)
def robot_cell(request):
    """(RobotModel, DrakeCell) with a tilted base, built once per robot."""
    robot = load_robot(request.param)
    X_IT, X_PE = RigidTransform([1.0, 0.0, 0.5]), RigidTransform([0.0, 0.0, 0.1])
    return robot, build_drake_cell(robot, X_IB=X_IB, X_IT=X_IT, X_PE=X_PE)


@pytest.fixture
def cell(robot_cell):
    return robot_cell[1]


def smallest_singular_value(cell, q: np.ndarray) -> float:
    context = cell.plant.CreateDefaultContext()
    cell.plant.SetPositions(context, q)
    world = cell.plant.world_frame()
    J = cell.plant.CalcJacobianSpatialVelocity(
        context, JacobianWrtVariable.kQDot, cell.frame_E, np.zeros(3), world, world
    )
    return float(np.linalg.svd(J, compute_uv=False).min())


def regular_joint_vectors(rng, cell, n: int) -> np.ndarray:
    """(n, 6) random joint vectors inside the limits, away from singularities [rad]."""
    lower, upper = cell.plant.GetPositionLowerLimits(), cell.plant.GetPositionUpperLimits()
    q = []
    while len(q) < n:
        candidate = rng.uniform(lower, upper)
        if smallest_singular_value(cell, candidate) > MIN_SINGULAR_VALUE:
            q.append(candidate)
    return np.array(q)


def pose_errors(X_test: RigidTransform, X_true: RigidTransform) -> tuple[float, float]:
    """Distance [m] and angle [rad] of X_test @ X_true⁻¹ from the identity."""
    X = X_test @ X_true.inverse()
    return float(np.linalg.norm(X.translation())), rotation_angle(X.rotation().matrix())


def wrapped(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


def test_solve_pose_recovers_random_joint_vectors(cell, rng):
    for q in regular_joint_vectors(rng, cell, 20):
        X_IE = cell.X_IE(q)
        q_ik, success = solve_pose(cell, X_IE, q + rng.normal(scale=SEED_NOISE_RAD, size=6))
        assert success
        distance, angle = pose_errors(cell.X_IE(q_ik), X_IE)
        assert distance <= POSE_TOL_M and angle <= POSE_TOL_RAD
        np.testing.assert_allclose(q_ik, q, atol=JOINT_TOL_RAD, rtol=0)


def smooth_joint_path(rng, cell, n: int = 50) -> np.ndarray:
    """(n, 6) a smooth random joint curve inside the limits, away from singularities."""
    lower, upper = cell.plant.GetPositionLowerLimits(), cell.plant.GetPositionUpperLimits()
    s = np.linspace(0.0, 1.0, n)[:, None]
    while True:
        q0 = regular_joint_vectors(rng, cell, 1)[0]
        amplitude, phase = rng.uniform(0.1, 0.4, 6), rng.uniform(0, 2 * np.pi, 6)
        q = q0 + amplitude * (np.sin(np.pi * s + phase) - np.sin(phase))
        inside = np.all((lower <= q) & (q <= upper))
        if inside and min(smallest_singular_value(cell, qi) for qi in q) > MIN_SINGULAR_VALUE:
            return q


def poses(cell, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """p_IE (N, 3) [m] and R_IE (N, 3, 3) from Drake FK of q (N, 6)."""
    X = [cell.X_IE(qi) for qi in q]
    return np.array([x.translation() for x in X]), np.array([x.rotation().matrix() for x in X])


def test_solve_path_matches_analytic_branch(robot_cell, rng):
    robot, cell = robot_cell
    q_true = smooth_joint_path(rng, cell)
    p_IE, R_IE = poses(cell, q_true)
    result = solve_path(cell, p_IE, R_IE, q_true[0])
    assert result.success.all()
    assert result.q.shape == (len(q_true), 6)
    assert result.max_position_error_m <= 1e-9 and result.max_angle_error_rad <= 1e-9
    # Analytic IK of X_BE = X_IB⁻¹ X_IE; the branch is the row closest to the input.
    X_BI = X_IB.inverse().GetAsMatrix4()
    X_IE = np.tile(np.eye(4), (len(p_IE), 1, 1))
    X_IE[:, :3, :3], X_IE[:, :3, 3] = R_IE, p_IE
    solutions = robot.inverse(X_BI @ X_IE)  # (N, 8, 6)
    gap = np.abs(wrapped(solutions - q_true[:, None, :])).max(axis=-1)  # (N, 8)
    branch = np.nanargmin(gap, axis=1)
    q_analytic = solutions[np.arange(len(q_true)), branch]
    np.testing.assert_array_less(np.abs(wrapped(result.q - q_analytic)), JOINT_TOL_RAD)
    np.testing.assert_allclose(result.q, q_true, atol=JOINT_TOL_RAD, rtol=0)


def test_unreachable_pose_fails_without_exception(cell, rng):
    q = regular_joint_vectors(rng, cell, 1)[0]
    X_far = RigidTransform(
        cell.X_IE(q).rotation(), X_IB.translation() + [0, 0, UNREACHABLE_DISTANCE_M]
    )
    q_ik, success = solve_pose(cell, X_far, q)
    assert not success
    assert q_ik.shape == (6,)


def test_solve_path_marks_only_the_unreachable_sample(cell, rng):
    q_true = smooth_joint_path(rng, cell, n=20)
    p_IE, R_IE = poses(cell, q_true)
    p_IE[10] = X_IB.translation() + [UNREACHABLE_DISTANCE_M, 0.0, 0.0]
    result = solve_path(cell, p_IE, R_IE, q_true[0])
    np.testing.assert_array_equal(result.success, np.arange(20) != 10)
    assert result.max_position_error_m > 1.0
    ok = result.success
    np.testing.assert_allclose(result.q[ok], q_true[ok], atol=JOINT_TOL_RAD, rtol=0)


def test_ipopt_agrees_with_default_solver(cell, rng):
    default, ipopt = PoseIk(cell), PoseIk(cell, solver_id=IpoptSolver.id())
    assert ipopt.solver_id == IpoptSolver.id()
    for q in regular_joint_vectors(rng, cell, 5):
        X_IE = cell.X_IE(q)
        seed = q + rng.normal(scale=SEED_NOISE_RAD, size=6)
        target = (X_IE.translation(), X_IE.rotation().matrix(), seed)
        q_a, ok_a, *_ = default.solve(*target)
        q_b, ok_b, *_ = ipopt.solve(*target)
        assert ok_a and ok_b
        np.testing.assert_allclose(q_a, q_b, atol=JOINT_TOL_RAD, rtol=0)


def test_bad_arguments_raise_value_error(cell):
    q = np.zeros(6)
    with pytest.raises(ValueError, match="q_seed"):
        solve_pose(cell, RigidTransform(), np.zeros(5))
    with pytest.raises(ValueError, match="position_tol_m"):
        solve_pose(cell, RigidTransform(), q, position_tol_m=0.0)
    with pytest.raises(ValueError, match="R_IE"):
        solve_path(cell, np.zeros((3, 3)), np.zeros((2, 3, 3)), q)
    with pytest.raises(ValueError, match="p_IE"):
        solve_path(cell, np.full((3, 3), np.nan), np.zeros((3, 3, 3)), q)
