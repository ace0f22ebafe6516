"""Link moves: a 10 mm plate across a direct joint move is found between samples and
planned around; the same seed gives the same link; the timed link keeps the joint
limits and ends exactly at its goal; a goal inside an obstacle is a failure naming the
link, not an exception."""

import numpy as np
import pytest

from offline_prog.collision.check import check_trajectory
from offline_prog.collision.motion import MotionChecker
from offline_prog.job.links import plan_link, timed_polyline
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import build_scene, load_inputs

from conftest import CELLS

CLEARANCE = 0.005
SWEEP_RAD = np.deg2rad(60.0)  # the direct move turns axis 1 by this much


def cell_with(tmp_path, obstacle: str):
    """The seal demo cell plus one obstacle line (YAML flow mapping)."""
    text = (CELLS / "seal_plate_kr16.yaml").read_text()
    text = text.replace("obstacles:   # in I\n", f"obstacles:   # in I\n  - {obstacle}\n")
    file = tmp_path / "cell.yaml"
    file.write_text(text)
    inputs = load_inputs(file, ROBOTS_DIR)
    return inputs, build_scene(inputs)


@pytest.fixture(scope="module")
def ends():
    """Home, and home with axis 1 turned by SWEEP_RAD; the wrist point at the middle."""
    inputs = load_inputs(CELLS / "seal_plate_kr16.yaml", ROBOTS_DIR)
    robot = inputs.robot
    q_a = robot.urdf_joints(robot.home_c)
    q_b = q_a.copy()
    q_b[0] += SWEEP_RAD
    q_mid = 0.5 * (q_a + q_b)
    p_mid = robot.forward(q_mid[None])[0][:3, 3]
    return q_a, q_b, p_mid


@pytest.fixture(scope="module")
def plate_across(tmp_path_factory, ends):
    """A 10 mm plate standing across the flange's arc at its middle, its thin side
    along the motion (yaw = the arc's tangent direction)."""
    _, _, p = ends
    yaw = np.rad2deg(np.arctan2(p[1], p[0]))  # the plate lies in the radial plane
    obstacle = (
        "{name: thin_plate, shape: box, size_mm: [600, 10, 600], "
        f"pose: {{translation: [{p[0]:.4f}, {p[1]:.4f}, {p[2]:.4f}], "
        f"rotation: !Rpy {{deg: [0, 0, {yaw:.3f}]}}}}}}"
    )
    return cell_with(tmp_path_factory.mktemp("plate"), obstacle)


def test_a_thin_plate_across_a_direct_move_is_found_between_samples(plate_across, ends):
    inputs, scene = plate_across
    q_a, q_b, _ = ends
    checker = MotionChecker(scene, clearance=CLEARANCE, self_clearance=CLEARANCE)
    # Both ends and five samples of the move (12° apart on axis 1) are clear: a check of
    # samples alone would pass it.
    samples = q_a + np.linspace(0, 1, 7)[:, None] * (q_b - q_a)
    assert all(checker.clear(q) for q in samples[[0, 1, 2, 4, 5, 6]])
    assert not checker.move_clear(q_a, q_b)
    link = plan_link(
        scene,
        inputs.robot,
        q_a,
        q_b,
        clearance=CLEARANCE,
        self_clearance=CLEARANCE,
        seed=0,
        time_budget_s=20.0,
        rate_hz=250.0,
        name="home -> turned",
        checker=checker,
    )
    assert link.ok and link.method == "planned"
    # The timed link, certified between samples on the exact shapes, is clear.
    result = check_trajectory(scene, link.q, link.t, np.zeros(len(link.t)), clearance=CLEARANCE)
    assert result.collision_free, result.message


def test_direct_move_when_nothing_is_in_the_way(ends):
    inputs = load_inputs(CELLS / "seal_plate_kr16.yaml", ROBOTS_DIR)
    scene = build_scene(inputs)
    q_a, q_b, _ = ends
    link = plan_link(
        scene,
        inputs.robot,
        q_a,
        q_b,
        clearance=CLEARANCE,
        self_clearance=CLEARANCE,
        seed=0,
        time_budget_s=5.0,
        rate_hz=250.0,
        name="direct",
    )
    assert link.ok and link.method == "direct"
    np.testing.assert_array_equal(link.waypoints, [q_a, q_b])


def test_same_seed_same_link(plate_across, ends):
    inputs, scene = plate_across
    q_a, q_b, _ = ends
    links = [
        plan_link(
            scene,
            inputs.robot,
            q_a,
            q_b,
            clearance=CLEARANCE,
            self_clearance=CLEARANCE,
            seed=7,
            time_budget_s=20.0,
            rate_hz=250.0,
            name="again",
        )
        for _ in range(2)
    ]
    np.testing.assert_array_equal(links[0].waypoints, links[1].waypoints)
    np.testing.assert_array_equal(links[0].q, links[1].q)


def test_timed_link_keeps_the_joint_limits_and_ends_at_its_goal(plate_across, ends):
    inputs, scene = plate_across
    robot = inputs.robot
    q_a, q_b, _ = ends
    link = plan_link(
        scene,
        robot,
        q_a,
        q_b,
        clearance=CLEARANCE,
        self_clearance=CLEARANCE,
        seed=0,
        time_budget_s=20.0,
        rate_hz=250.0,
        name="limits",
    )
    np.testing.assert_array_equal(link.q[0], q_a)
    np.testing.assert_allclose(link.q[-1], q_b, atol=1e-12)
    q_c = robot.controller_joints(link.q)
    qd = np.diff(q_c, axis=0) / np.diff(link.t)[:, None]
    qdd = np.diff(qd, axis=0) / np.diff(link.t)[1:, None]
    assert np.all(np.abs(qd) <= robot.qd_max * 1.01)
    assert np.all(np.abs(qdd) <= robot.qdd_max * 1.01)
    # Straight between waypoints: every sample on a segment of the polyline.
    w = link.waypoints
    for q in link.q[:: max(1, len(link.q) // 50)]:
        assert min(_segment_distance(q, a, b) for a, b in zip(w[:-1], w[1:], strict=True)) < 1e-9


def _segment_distance(q, a, b) -> float:
    u = b - a
    s = np.clip((q - a) @ u / (u @ u), 0.0, 1.0)
    return float(np.linalg.norm(q - (a + s * u)))


def test_goal_inside_an_obstacle_is_a_failure_naming_the_link(tmp_path, ends):
    q_a, q_b, _ = ends
    inputs = load_inputs(CELLS / "seal_plate_kr16.yaml", ROBOTS_DIR)
    p = inputs.robot.forward(q_b[None])[0][:3, 3]
    obstacle = (
        "{name: block, shape: box, size_mm: [300, 300, 300], "
        f"pose: {{translation: [{p[0]:.4f}, {p[1]:.4f}, {p[2]:.4f}]}}}}"
    )
    inputs, scene = cell_with(tmp_path, obstacle)
    link = plan_link(
        scene,
        inputs.robot,
        q_a,
        q_b,
        clearance=CLEARANCE,
        self_clearance=CLEARANCE,
        seed=0,
        time_budget_s=2.0,
        rate_hz=250.0,
        name="home -> blocked",
    )
    assert not link.ok
    assert "link home -> blocked" in link.failure.reason
    assert "goal configuration" in link.failure.reason


def test_a_link_at_half_speed_keeps_half_the_joint_speed_and_takes_longer(ends):
    """motion.link_speed_percent scales the joints' speed limits of a link (a PTP
    override): at 50 % no joint exceeds half its limit, and the link takes longer."""
    inputs = load_inputs(CELLS / "seal_plate_kr16.yaml", ROBOTS_DIR)
    robot = inputs.robot
    q_a, q_b, _ = ends
    full = timed_polyline(robot, np.array([q_a, q_b]), 250.0)
    half = timed_polyline(robot, np.array([q_a, q_b]), 250.0, speed_share=0.5)
    peak = np.abs(robot.controller_joints(half[2])).max(axis=0)
    assert np.all(peak <= 0.5 * robot.qd_max * (1 + 1e-9))
    # Axis 1 (the one that turns) reaches more than half its limit at full speed.
    assert np.abs(robot.controller_joints(full[2])[:, 0]).max() > 0.6 * robot.qd_max[0]
    assert half[0][-1] > full[0][-1] * 1.1  # 60° of axis 1: mostly ramps
