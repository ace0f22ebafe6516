"""Joint trajectory of whole cells: a closed contour's full turn fits the wrist,
a symmetric tool's free rotation rescues a pose the robot cannot reach otherwise,
the Drake plant agrees with the plan."""

import numpy as np
import pytest

from offline_prog.errors import PlanFailedError
from offline_prog.plan import plan_cell
from offline_prog.scene.drake_cell import build_drake_cell

from conftest import CELLS

WELD = "".join(  # the demo weld cell without its free tool rotation
    line
    for line in (CELLS / "weld_seam_irb2400.yaml").read_text().splitlines(keepends=True)
    if "free_rotation_deg" not in line
).replace("dxf: data/", f"dxf: {CELLS / 'data'}/")
TORCH_POSE = "X_IT: {translation: [1.1, 0.0, 0.9], rotation: !Rpy {deg: [-90, 0, 0]}}"


@pytest.fixture(scope="module")
def seal_plan():
    return plan_cell(CELLS / "seal_plate_kr16.yaml")


def test_closed_contour_turns_the_wrist_once_within_its_limits(seal_plan):
    q = seal_plan.joints.q
    robot = seal_plan.robot
    assert np.all(q >= robot.q_lower) and np.all(q <= robot.q_upper)
    # The part turns once about the vertical nozzle: A1 and A6 together turn 2π.
    turn = (q[-1] - q[0])[[0, 5]]
    assert abs(abs(turn[0] - turn[1]) - 2 * np.pi) < 1e-6 or abs(abs(turn[1]) - 2 * np.pi) < 0.2
    assert np.ptp(q[:, 5]) > np.pi  # more than half a turn on A6
    # Closed: the robot ends where it started, modulo full turns.
    np.testing.assert_allclose(np.angle(np.exp(1j * (q[-1] - q[0]))), 0.0, atol=1e-6)


def test_joint_path_is_continuous(seal_plan):
    joint, sigma, step = seal_plan.joints.largest_step
    qd_max, dt = seal_plan.robot.qd_max, 1 / seal_plan.cell.motion.sample_rate_hz
    assert step <= qd_max[joint] * dt  # no jump beyond what the joint speed allows
    assert np.abs(np.diff(seal_plan.joints.q, axis=0)).max() == pytest.approx(step)


def test_drake_plant_places_the_part_on_the_tool(seal_plan):
    cell = seal_plan.cell
    from offline_prog.config.cell import transform

    drake = build_drake_cell(
        seal_plan.robot,
        X_IB=transform(cell.robot.X_IB),
        X_IT=transform(cell.tool.X_IT),
        X_PE=transform(cell.part.X_PE),
    )
    plant = drake.plant
    context = plant.CreateDefaultContext()
    part = plant.GetBodyByName("part")
    tool = plant.GetBodyByName("tool")
    traj = seal_plan.trajectory
    for i in np.linspace(0, len(traj.t) - 1, 25).astype(int):
        plant.SetPositions(context, drake.robot, seal_plan.joints.q[i])
        X_IP = plant.EvalBodyPoseInWorld(context, part)
        X_IT = plant.EvalBodyPoseInWorld(context, tool)
        # The path point under the TCP, through the plant: X_IP · p_PF(σ) = p_IT.
        p_I = X_IP @ traj.flange.p_PF[i]
        assert np.linalg.norm(p_I - X_IT.translation()) <= 1e-9


def test_free_rotation_rescues_a_pose_out_of_the_joint_limits(tmp_path):
    turned = WELD.replace(TORCH_POSE, TORCH_POSE.replace("[-90, 0, 0]", "[-90, 0, -90]"))
    assert turned != WELD
    fixed = tmp_path / "turned.yaml"
    fixed.write_text(turned)
    with pytest.raises(PlanFailedError, match="joint limit on axis [0-9]"):
        plan_cell(fixed)
    free = tmp_path / "free.yaml"
    free.write_text(
        turned.replace("  name: welding_torch", "  name: welding_torch\n  free_rotation_deg: 60")
    )
    plan = plan_cell(free)
    assert 0 < abs(plan.tool_rotation_rad) <= np.deg2rad(60) + 1e-12
    assert plan.joints.margin_rad.min() > 0
    # The torch axis (y of T, the pressing direction) still meets the surface normal.
    R_IE = plan.trajectory.flange.R_IE
    R_PE = plan.flange.X_PE.rotation().matrix()
    n_I = (R_IE @ R_PE.T) @ np.array([0.0, 0.0, -1.0])  # the seam's normal, into the part
    y_T = plan.flange.X_IT.rotation().matrix()[:, 1]
    np.testing.assert_allclose(n_I, np.broadcast_to(y_T, n_I.shape), atol=1e-9)


def test_drake_ik_fallback_matches_the_analytic_plan():
    """A robot without a closed form plans through Drake IK; on the UR10e (forced to
    that route) it follows the same flange path within the joint limits."""
    import dataclasses

    from offline_prog.config.cell import transform
    from offline_prog.joints.joint_plan import plan_joint_trajectory
    from offline_prog.timing.path_timing import PathLimits
    from offline_prog.timing.trajectory import TimeLawParameter

    analytic = plan_cell(CELLS / "tape_cylinder_ur10e.yaml")
    robot = dataclasses.replace(analytic.robot, family="drake")
    parameter = TimeLawParameter(analytic.flange, "tcp")
    motion = analytic.cell.motion
    limits = PathLimits.of(
        robot,
        parameter.length,
        v_process=motion.speed,
        a_max=motion.max_acceleration,
        j_max=motion.max_jerk,
    )
    drake = plan_joint_trajectory(
        robot,
        transform(analytic.cell.robot.X_IB),
        analytic.flange,
        parameter,
        limits,
        rate_hz=motion.sample_rate_hz,
    )
    # Same poses: Drake FK of the Drake-route joints is the planned flange path.
    cell = analytic.cell
    plant_cell = build_drake_cell(
        robot,
        X_IB=transform(cell.robot.X_IB),
        X_IT=transform(cell.tool.X_IT),
        X_PE=transform(cell.part.X_PE),
    )
    traj = drake.trajectory
    for i in np.linspace(0, len(traj.t) - 1, 15).astype(int):
        X_IE = plant_cell.X_IE(drake.q[i])
        assert np.linalg.norm(X_IE.translation() - traj.flange.p_IE[i]) <= 1e-8
    assert np.all(drake.q >= robot.q_lower) and np.all(drake.q <= robot.q_upper)
    assert "jacobian" in drake.singularities and drake.singularities["jacobian"]["distance"] > 0
