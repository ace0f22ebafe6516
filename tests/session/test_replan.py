"""The session's cache: each change re-runs only the stages that read it, the answer
is the plan `plan` makes of the same cell, and failures come back as status lines."""

import numpy as np
import pytest

from offline_prog.config.cell import load_cell
from offline_prog.config.edits import apply
from offline_prog.session.replan import Replanner
from offline_prog.session.state import with_value
from offline_prog.session.status import plan_status

from conftest import CELLS


@pytest.fixture(scope="module")
def replanner():
    """The tape cell (the fastest demo plan); its first plan made."""
    planner = Replanner(CELLS / "tape_cylinder_ur10e.yaml")
    first = planner.plan(planner.initial)
    assert first.ran == ["fit", "frames", "scene", "joints", "check"] and first.plan.feasible
    planner.first_duration_s = first.plan.trajectory.duration
    return planner


def test_a_speed_change_keeps_the_fit_the_frames_and_the_scene(replanner):
    slower = with_value(replanner.initial, "speed", 120)
    result = replanner.plan(slower)
    assert result.ran == ["joints", "check"]
    assert result.plan.trajectory.duration > replanner.first_duration_s


def test_a_clearance_change_only_checks_again(replanner):
    state = with_value(replanner.initial, "speed", 130)
    replanner.plan(state)
    result = replanner.plan(with_value(state, "clearance", 8))
    assert result.ran == ["check"]
    assert result.plan.collisions.clearance_m == 0.008


def test_a_tool_move_does_not_refit(replanner):
    moved = with_value(replanner.initial, "X_IT.z", 310)
    result = replanner.plan(moved)
    assert result.ran == ["frames", "scene", "joints", "check"]
    assert result.scene.X_IT.translation()[2] == pytest.approx(0.31)
    # The same answer again: nothing re-runs.
    assert replanner.plan(moved).ran == []


def test_the_session_plan_is_the_plan_of_the_same_cell(replanner, tmp_path):
    """Reused stages give the plan a fresh `plan` run gives of the changed cell."""
    from offline_prog.config.cell_text import save_cell
    from offline_prog.plan import plan_cell

    moved = with_value(with_value(replanner.initial, "X_IT.x", 705), "speed", 140)
    result = replanner.plan(moved)
    text = (CELLS / "tape_cylinder_ur10e.yaml").read_text().replace(": data/", f": {CELLS}/data/")
    original = tmp_path / "tape.yaml"
    original.write_text(text)
    cell = apply(load_cell(original), replanner.initial, moved)
    saved = save_cell(original, replanner.initial, moved, cell)
    reference = plan_cell(saved)
    np.testing.assert_array_equal(result.plan.joints.q, reference.joints.q)
    assert result.plan.collisions.min_distance_m == reference.collisions.min_distance_m


def test_out_of_reach_is_a_status_with_sigma_t_and_why(replanner):
    far = with_value(replanner.initial, "X_IT.x", 2500)
    result = replanner.plan(far)
    assert result.plan is None and result.failure is not None
    status = plan_status(result)
    assert status["kind"] == "failed" and "out of reach" in status["line"]
    assert "σ = " in status["line"] and "t = " in status["line"]
    # The failure is kept: only the clearance changed, nothing is planned again.
    assert replanner.plan(with_value(far, "clearance", 6)).ran == []


def test_a_tool_turn_smoothing_change_re_runs_the_frames_and_joints(replanner):
    """tool.turn_smoothing_mm from the panel: the flange paths and the joints are planned
    again with the tool turning along the path; without a free rotation it is refused."""
    free = with_value(replanner.initial, "free_rotation", 90)
    replanner.plan(free)
    turning = with_value(free, "turn_smoothing", 20)
    result = replanner.plan(turning)
    assert result.ran == ["frames", "joints", "check"] and result.plan.feasible
    phi = result.plan.flange.tool_turn(np.linspace(0.0, result.plan.path.length, 200))[0]
    assert np.ptp(phi) > np.deg2rad(1.0)  # it turns along the path
    refused = replanner.plan(with_value(replanner.initial, "turn_smoothing", 20))
    assert refused.plan is None and "tool.turn_smoothing_mm" in refused.error
