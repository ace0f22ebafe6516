"""Path IK: one branch for the whole path, the 2π start with the largest margin,
failures that say where and why."""

import numpy as np
import pytest

from offline_prog.errors import PlanFailedError
from offline_prog.joints.path_ik import base_poses, best_turns, branch_results, choose_branch
from offline_prog.plan import plan_cell
from offline_prog.robot.model import load_robot

from conftest import CELLS

ROBOTS = ["ur10e", "kuka_kr16_2", "abb_irb2400"]


# Regular working configurations, away from every singularity.
HOME = {
    "ur10e": [0.3, -1.2, 1.5, -1.9, -1.4, 0.5],
    "kuka_kr16_2": [0.2, -1.3, 1.4, 0.4, 0.9, 0.3],
    "abb_irb2400": [0.2, 0.3, 0.2, 0.4, 0.9, 0.3],
}


def smooth_joint_path(robot, rng, n=400, amplitude=0.3):
    """A smooth joint curve around the robot's HOME configuration, and its poses."""
    phase = np.linspace(0, 1, n)[:, None]
    wave = np.sin(2 * np.pi * phase * rng.uniform(0.3, 0.8, 6) + rng.uniform(0, 6, 6))
    q = np.asarray(HOME[robot.name]) + amplitude * wave
    return q, robot.forward(q)


@pytest.mark.parametrize("name", ROBOTS)
def test_recovers_the_branch_the_path_was_made_on(rng, name):
    robot = load_robot(name)
    for _ in range(3):
        q, X_BE = smooth_joint_path(robot, rng)
        results = branch_results(robot, X_BE)
        # The branch that contains the input path reproduces it up to 2π per joint.
        matches = [
            r
            for r in results
            if r.feasible and np.allclose(np.angle(np.exp(1j * (r.q - q))), 0.0, atol=1e-7)
        ]
        assert matches, "the generating branch must be found feasible"
        chosen = choose_branch(results)
        assert chosen.feasible
        assert chosen.margin_rad >= max(r.margin_rad for r in results if r.feasible)
        # Every feasible branch reproduces the poses and stays inside the limits.
        for r in (x for x in results if x.feasible):
            q_c = robot.controller_joints(r.q)
            assert np.all(q_c >= robot.q_lower) and np.all(q_c <= robot.q_upper)
            np.testing.assert_allclose(robot.forward(r.q), X_BE, atol=1e-9)
            assert np.abs(np.diff(r.q, axis=0)).max() < np.deg2rad(10)


def test_best_turns_picks_the_multiple_of_two_pi_with_most_margin():
    lower, upper = np.full(6, -np.deg2rad(350)), np.full(6, np.deg2rad(350))
    q = np.zeros((1, 50, 6))
    q[0, :, 5] = np.linspace(np.deg2rad(100), np.deg2rad(100 + 360), 50)  # one full turn
    offsets, margins = best_turns(q, lower, upper)
    shifted = q[0, :, 5] + offsets[0, 5]
    assert shifted.min() >= lower[5] and shifted.max() <= upper[5]
    assert offsets[0, 5] == pytest.approx(-2 * np.pi)  # centre the turn in the range
    assert margins[0, 5] == pytest.approx(np.deg2rad(350 - 180 + 0), abs=np.deg2rad(81))


def test_out_of_reach_and_joint_limit_are_named_with_sigma_and_time(tmp_path):
    text = (CELLS / "seal_plate_kr16.yaml").read_text()
    far = tmp_path / "far.yaml"
    far.write_text(text.replace("translation: [1.0, 0.0, 0.5]", "translation: [2.5, 0.0, 0.5]"))
    with pytest.raises(PlanFailedError, match=r"σ = 0\.0000 m, t = 0\.000 s: out of reach"):
        plan_cell(far)


def test_unreachable_middle_of_a_path_is_located(rng):
    robot = load_robot("kuka_kr16_2")
    q, X_BE = smooth_joint_path(robot, rng, n=200)
    X_BE[120:, :3, 3] *= 3.0  # the second part of the path leaves the workspace
    results = branch_results(robot, X_BE)
    assert not any(r.feasible for r in results)
    worst = choose_branch(results)
    assert worst.reason == "out of reach" and worst.sample == 120


def test_base_poses_compose_X_BI_X_IE(rng):
    from conftest import random_transform

    X_IB = random_transform(rng)
    X_IE = [random_transform(rng) for _ in range(5)]
    X_BE = base_poses(
        X_IB,
        np.array([X.translation() for X in X_IE]),
        np.array([X.rotation().matrix() for X in X_IE]),
    )
    for i, X in enumerate(X_IE):
        np.testing.assert_allclose(X_BE[i], (X_IB.inverse() @ X).GetAsMatrix4(), atol=1e-12)


def test_abb_axis_3_limits_apply_to_q2_plus_q3():
    """The IRB 2400's controller counts axis 3 as q2 + q3 (J23 coupling): a path with
    URDF q3 = −69° (outside ABB's −60°) but q2 + q3 = −40° is inside the limits."""
    import dataclasses

    robot = load_robot("abb_irb2400")
    assert robot.j23_coupled
    n = 50
    q = np.tile([0.2, 0.5, -1.2, 0.3, 0.8, 0.2], (n, 1))
    q[:, 0] += np.linspace(0.0, 0.1, n)
    X_BE = robot.forward(q)

    def generating(results):
        return next(
            r for r in results if np.allclose(np.angle(np.exp(1j * (r.q - q))), 0.0, atol=1e-7)
        )

    coupled = generating(branch_results(robot, X_BE))
    assert coupled.feasible
    assert np.rad2deg(coupled.margin_rad) == pytest.approx(np.rad2deg(-0.7) + 60, abs=0.5)
    uncoupled = generating(branch_results(dataclasses.replace(robot, j23_coupled=False), X_BE))
    assert not uncoupled.feasible and uncoupled.reason == "joint limit on axis 3"


def test_a_reversed_normal_is_named_not_only_out_of_reach(tmp_path):
    """The seal demo with its normal pointing out of the plate instead of into it: the
    tool frame turns over and the path is out of reach; the message says the normal is
    the likely cause (the same path with it reversed is feasible)."""
    text = (CELLS / "seal_plate_kr16.yaml").read_text().replace(": data/", f": {CELLS}/data/")
    flipped = text.replace("  normal: [0, 0, 1]", "  normal: [0, 0, -1]")
    assert flipped != text
    file = tmp_path / "flipped.yaml"
    file.write_text(flipped)
    with pytest.raises(PlanFailedError) as error:
        plan_cell(file)
    message = str(error.value)
    assert "out of reach" in message and "normals reversed the robot can follow it" in message
    assert error.value.failure.kind.value == "out_of_reach"
