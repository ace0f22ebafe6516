"""Analytic kinematics (kinematics_opw, kinematics_ur) against Drake, data sheets and
py-opw-kinematics.

Frames: B robot base (URDF ``base_link``), E flange (URDF ``tool0``), C wrist centre.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant

from offline_prog.robot.kinematics_opw import wrap_to_pi
from offline_prog.robot.model import ROBOTS_DIR, RobotModel, load_robot

from conftest import ANGLE_TOL_RAD, POSITION_TOL_M

ROBOTS = ("ur10e", "kuka_kr16_2", "abb_irb2400")
OPW_ROBOTS = ("kuka_kr16_2", "abb_irb2400")
N_SAMPLES = 1000
TOL_DATASHEET = 0.5e-3  # [m]: data sheets give millimetres


def random_joints(robot: RobotModel, n: int, seed: int = 0) -> np.ndarray:
    """(n, 6) joint vectors uniform within the robot's position limits [rad]."""
    rng = np.random.default_rng(seed)
    return rng.uniform(robot.q_lower, robot.q_upper, size=(n, 6))


def pose_errors(X_a: np.ndarray, X_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance [m] and rotation angle [rad] between poses (..., 4, 4).

    The angle uses ||R_a - R_b||_F = 2 sqrt(2) sin(angle / 2), which keeps full
    precision near zero (arccos of the trace does not).
    """
    distance = np.linalg.norm(X_a[..., :3, 3] - X_b[..., :3, 3], axis=-1)
    chord = np.linalg.norm(X_a[..., :3, :3] - X_b[..., :3, :3], axis=(-2, -1))
    angle = 2.0 * np.arcsin(np.minimum(chord / (2.0 * np.sqrt(2.0)), 1.0))
    return distance, angle


@functools.cache
def drake_plant(name: str) -> MultibodyPlant:
    """The robot's URDF in a MultibodyPlant, loaded by package:// URI, base welded."""
    plant = MultibodyPlant(time_step=0.0)
    parser = Parser(plant)
    parser.package_map().AddPackageXml(str(ROBOTS_DIR / "package.xml"))
    parser.AddModels(url=f"package://offline_prog_robots/{name}/{name}.urdf")
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("base_link"))
    plant.Finalize()
    return plant


def drake_forward(robot: RobotModel, q: np.ndarray) -> np.ndarray:
    """X_BE (N, 4, 4) from Drake's FK of the URDF for joint vectors q (N, 6)."""
    plant = drake_plant(robot.name)
    context = plant.CreateDefaultContext()
    starts = [plant.GetJointByName(n).position_start() for n in robot.joint_names]
    frame_B, frame_E = plant.GetFrameByName("base_link"), plant.GetFrameByName("tool0")
    X_BE = np.empty((q.shape[0], 4, 4))
    positions = np.zeros(plant.num_positions())
    for i, q_i in enumerate(q):
        positions[starts] = q_i
        plant.SetPositions(context, positions)
        X_BE[i] = plant.CalcRelativeTransform(context, frame_B, frame_E).GetAsMatrix4()
    return X_BE


def assert_solutions_reach(robot, solutions, valid, X_BE):
    """Every existing solution (valid (N, 8)) of solutions (N, 8, 6) reaches its pose."""
    X_solutions = robot.forward(solutions[valid])
    distance, angle = pose_errors(X_solutions, np.repeat(X_BE, valid.sum(axis=1), axis=0))
    assert distance.max() <= POSITION_TOL_M
    assert angle.max() <= ANGLE_TOL_RAD


@pytest.mark.parametrize("name", ROBOTS)
def test_forward_matches_drake_urdf(name):
    robot = load_robot(name)
    q = random_joints(robot, N_SAMPLES)
    distance, angle = pose_errors(robot.forward(q), drake_forward(robot, q))
    assert distance.max() <= POSITION_TOL_M
    assert angle.max() <= ANGLE_TOL_RAD


@pytest.mark.parametrize("name", ROBOTS)
def test_inverse_round_trip(name):
    robot = load_robot(name)
    q = random_joints(robot, N_SAMPLES, seed=1)
    X_BE = robot.forward(q)
    solutions = robot.inverse(X_BE)
    assert solutions.shape == (N_SAMPLES, 8, 6)
    valid = ~np.isnan(solutions).any(axis=-1)
    assert np.array_equal(valid, ~np.isnan(solutions).all(axis=-1)), "partial NaN rows"
    # One of the eight solutions is the input, modulo 2 pi.
    joint_error = np.abs(wrap_to_pi(solutions - q[:, None])).max(axis=-1)
    assert np.where(valid, joint_error, np.inf).min(axis=1).max() <= ANGLE_TOL_RAD
    # Every solution that exists reaches the pose.
    assert_solutions_reach(robot, solutions, valid, X_BE)


@pytest.mark.parametrize("name", ROBOTS)
def test_inverse_branch_is_that_column_of_inverse(name):
    """A joint path evaluates its chosen branch alone: the same numbers, bit for bit,
    NaN rows included (poses out of reach of some branches, and the wrist singularity)."""
    robot = load_robot(name)
    q = random_joints(robot, N_SAMPLES, seed=5)
    q[::7, 4] = 0.0
    X_BE = robot.forward(q)
    X_BE[::11, :3, 3] *= 1.6  # some beyond the reach of some branches
    solutions = robot.inverse(X_BE)
    assert np.isnan(solutions).any() and not np.isnan(solutions).all()
    for branch in range(8):
        alone = robot.inverse_branch(X_BE, branch)
        assert np.array_equal(alone, solutions[:, branch], equal_nan=True)
    with pytest.raises(ValueError, match="branch"):
        robot.inverse_branch(X_BE, 8)


@pytest.mark.parametrize("name", ROBOTS)
def test_inverse_at_wrist_singularity(name):
    robot = load_robot(name)
    q = random_joints(robot, 100, seed=2)
    q[:, 4] = 0.0  # axes 4 and 6 aligned: only q4 + q6 (or q4 - q6) is determined
    X_BE = robot.forward(q)
    solutions = robot.inverse(X_BE)
    valid = ~np.isnan(solutions).any(axis=-1)
    assert valid.any(axis=1).all()
    assert_solutions_reach(robot, solutions, valid, X_BE)


@pytest.mark.parametrize("name", ROBOTS)
def test_inverse_out_of_reach_is_nan(name):
    robot = load_robot(name)
    X_BE = np.eye(4)[None].repeat(2, axis=0)
    X_BE[:, :3, 3] = [[5.0, 0.0, 1.0], [0.0, -4.0, 0.5]]  # well beyond reach
    assert np.isnan(robot.inverse(X_BE)).all()


@pytest.mark.parametrize("name", ROBOTS)
def test_shapes_are_checked(name):
    robot = load_robot(name)
    with pytest.raises(ValueError, match=r"q: expected .*\(N, 6\)"):
        robot.forward(np.zeros(6))
    with pytest.raises(ValueError, match=r"X_BE: expected .*\(N, 4, 4\)"):
        robot.inverse(np.eye(4))


# Flange position at q = 0 [m], in base_link. UR: from UR's DH table (base_link is
# UR's Base turned by pi about z): (-(a2 + a3), d4 + d6, d1 - d5). KUKA: data-sheet
# dimension drawing 260 + 680 + 670 + 158 mm forward, 675 - 35 mm up (arm stretched
# forward at A2 = 0, A3 = 0). ABB: data-sheet drawing 100 + 755 + 85 mm forward,
# 615 + 705 + 135 mm up (lower arm vertical, upper arm horizontal).
ZERO_POSE_P_BE = {
    "ur10e": (1.18425, 0.2907, 0.06085),
    "kuka_kr16_2": (1.768, 0.0, 0.640),
    "abb_irb2400": (0.940, 0.0, 1.455),
}
# Data-sheet reach [m]. KUKA KR 16-2: 1611 mm, wrist point (A4/A5/A6 intersection)
# from axis A1. ABB IRB 2400/10: 1.55 m, wrist centre (axis 5) from axis 1, within
# the joint limits. UR10e: 1300 mm, reached by the wrist-3 centre on the stretched
# arm, |a2 + a3| + d5 = 1304 mm (UR rounds, hence the 5 mm tolerance below).
DATASHEET_REACH = {"ur10e": 1.300, "kuka_kr16_2": 1.611, "abb_irb2400": 1.550}


@pytest.mark.parametrize("name", ROBOTS)
def test_zero_pose_flange_position(name):
    robot = load_robot(name)
    X_BE = robot.forward(np.zeros((1, 6)))[0]
    np.testing.assert_allclose(X_BE[:3, 3], ZERO_POSE_P_BE[name], atol=TOL_DATASHEET)
    # tool0 z points out of the flange: forward at zero for KUKA/ABB, +y for the UR.
    z_expected = (0.0, 1.0, 0.0) if name == "ur10e" else (1.0, 0.0, 0.0)
    np.testing.assert_allclose(X_BE[:3, 2], z_expected, atol=1e-12)


@pytest.mark.parametrize("name", OPW_ROBOTS)
def test_opw_wrist_reach_matches_datasheet(name):
    robot = load_robot(name)
    grid = np.radians(0.25) * np.arange(-1440, 1441)
    q2, q3 = np.meshgrid(grid, grid, indexing="ij")
    inside = (q2 >= robot.q_lower[1]) & (q2 <= robot.q_upper[1])
    inside &= (q3 >= robot.q_lower[2]) & (q3 <= robot.q_upper[2])
    q = np.zeros((inside.sum(), 6))
    q[:, 1], q[:, 2] = q2[inside], q3[inside]
    X_BE = robot.forward(q)
    p_BC = X_BE[:, :3, 3] - robot.params.c4 * X_BE[:, :3, 2]
    reach = np.hypot(p_BC[:, 0], p_BC[:, 1]).max()
    assert reach == pytest.approx(DATASHEET_REACH[name], abs=TOL_DATASHEET)


def test_ur_reach_matches_datasheet():
    robot = load_robot("ur10e")
    p = robot.params
    q = np.array([[0.0, 0.0, 0.0, -np.pi / 2, 0.0, 0.0]])  # wrist 2 turned outward
    X_BE = robot.forward(q)[0]
    p_wrist3 = X_BE[:3, 3] - p.d6 * X_BE[:3, 2]  # wrist-3 centre
    assert p_wrist3[0] == pytest.approx(abs(p.a2 + p.a3) + p.d5, abs=1e-12)
    assert p_wrist3[0] == pytest.approx(DATASHEET_REACH["ur10e"], abs=5e-3)


@pytest.mark.parametrize("name", OPW_ROBOTS)
def test_opw_matches_py_opw_kinematics(name):
    pytest.importorskip(
        "py_opw_kinematics", reason="independent OPW implementation: pip install py-opw-kinematics"
    )
    from py_opw_reference import py_opw_robot
    from scipy.spatial.transform import RigidTransform

    robot = load_robot(name)
    other = py_opw_robot(robot.params)
    q = random_joints(robot, N_SAMPLES, seed=3)
    X_BE = robot.forward(q)
    distance, angle = pose_errors(X_BE, other.batch_forward(q).as_matrix())
    assert distance.max() <= POSITION_TOL_M
    assert angle.max() <= ANGLE_TOL_RAD
    # Same solution sets (its slot order differs from ours): match each way, mod 2 pi.
    ours = robot.inverse(X_BE)
    theirs = other.reach(RigidTransform.from_matrix(X_BE)).joints
    gap = np.abs(wrap_to_pi(ours[:, :, None] - theirs[:, None])).max(axis=-1)  # (N, 8, 8)
    gap = np.where(np.isnan(gap), np.inf, gap)
    ours_valid = ~np.isnan(ours).any(axis=-1)
    theirs_valid = ~np.isnan(theirs).any(axis=-1)
    assert np.array_equal(ours_valid.sum(axis=1), theirs_valid.sum(axis=1))
    assert gap.min(axis=2)[ours_valid].max() <= ANGLE_TOL_RAD
    assert gap.min(axis=1)[theirs_valid].max() <= ANGLE_TOL_RAD
