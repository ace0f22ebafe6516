"""The session's parameters: typed values parsed in the controls' units, bad ones
refused with one line (the state kept), and the Cell they make."""

import dataclasses

import pytest
from pydrake.common.yaml import yaml_dump_typed

from offline_prog.config.cell import load_cell, transform
from offline_prog.config.edits import apply, initial_values
from offline_prog.session.state import controls, values, with_value

from conftest import CELLS


@pytest.fixture(scope="module")
def seal():
    cell = load_cell(CELLS / "seal_plate_kr16.yaml")
    return cell, initial_values(cell)


def test_initial_state_reads_the_cell(seal):
    cell, state = seal
    assert state.p_IT == (1.0, 0.0, 0.5) and state.rpy_IT_deg == (90.0, 0.0, 0.0)
    assert state.speed == cell.motion.speed and state.clearance == cell.motion.clearance
    assert values(state)["X_IT.x"] == 1000.0 and values(state)["speed"] == 100.0
    # Nothing changed: the very same cell.
    assert yaml_dump_typed(apply(cell, state, state)) == yaml_dump_typed(cell)


def test_values_in_mm_and_degrees_make_the_cell(seal):
    cell, state = seal
    moved = with_value(with_value(state, "X_IT.x", "1012.5"), "X_IT.yaw", 3)
    moved = with_value(with_value(moved, "speed", "80"), "clearance", "7")
    new = apply(cell, state, moved)
    assert transform(new.tool.X_IT).translation()[0] == pytest.approx(1.0125, abs=1e-15)
    assert list(new.tool.X_IT.rotation.value.deg) == [90.0, 0.0, 3.0]
    assert new.motion.speed == 0.08 and new.motion.clearance == 0.007
    assert new.part.X_PE is cell.part.X_PE  # unchanged: the original schema value


@pytest.mark.parametrize(
    ("key", "text", "reason"),
    [
        ("speed", "0", "must be > 0"),
        ("speed", "-5", "must be > 0"),
        ("speed", "abc", "is not a number"),
        ("speed", "nan", "not a finite number"),
        ("clearance", "-1", "must be ≥ 0"),
        ("X_IT.x", "1e9", "must be ≥ -10000"),
        ("X_PE.roll", "inf", "not a finite number"),
        ("free_rotation", "200", "≤ 180"),
        ("turn_smoothing", "-1", "must be ≥ 0"),
        ("seam", "1", "no such seam"),
        ("nozzle", "1", "not a control"),
    ],
)
def test_bad_values_are_refused_in_one_line(seal, key, text, reason):
    _, state = seal
    with pytest.raises(ValueError, match=reason) as error:
        with_value(state, key, text)
    assert "\n" not in str(error.value)


def test_a_seam_with_its_own_speed_is_edited_there():
    cell = load_cell(CELLS / "seal_job_kr16.yaml")
    state = initial_values(cell)
    stripe = [s.name for s in cell.seams].index("stripe")
    on_stripe = with_value(state, "seam", stripe)
    assert on_stripe.speed == 0.15  # the stripe's own speed, not motion.speed
    faster = with_value(on_stripe, "speed", 200)
    assert faster.motion_speed == state.motion_speed
    new = apply(cell, state, faster)
    assert new.seams[stripe].speed == 0.2 and new.motion.speed == cell.motion.speed
    assert [c.key for c in controls(state, [s.name for s in cell.seams])][-1] == "seam"
    assert dataclasses.replace(faster, seam=0).speed == state.motion_speed
