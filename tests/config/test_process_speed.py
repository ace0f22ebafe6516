"""Each seam's process speed is decided once, from the cell (issue 41): its own
``seams[k].speed``, else ``motion.speed``; the seam's inputs, its time law's limits,
its plan, the program writers' record and the session read that one record."""

import dataclasses

import pytest

from offline_prog.config.cell import load_cell
from offline_prog.config.edits import apply, initial_values
from offline_prog.config.process_speed import ProcessSpeed, process_speed
from offline_prog.job.seams import job_seams, seam_inputs
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.session.state import with_value
from offline_prog.stages import fit_path, flange_paths, load_inputs, motion_setup

from conftest import CELLS

JOB = CELLS / "seal_job_kr16.yaml"  # the stripe runs at its own 0.15 m/s, the rest at 0.1


def test_a_seam_runs_at_its_own_speed_else_the_cells():
    cell = load_cell(JOB)
    speeds = [process_speed(cell, k) for k in range(len(cell.seams))]
    stripe = [s.name for s in cell.seams].index("stripe")
    for k, speed in enumerate(speeds):
        if k == stripe:
            assert speed == ProcessSpeed(0.15, f"seams[{stripe}].speed")
        else:
            assert speed == ProcessSpeed(cell.motion.speed, "motion.speed")
    path_cell = load_cell(CELLS / "seal_plate_kr16.yaml")
    assert process_speed(path_cell, 0) == ProcessSpeed(0.1, "motion.speed")


def test_the_session_state_reads_the_same_choice():
    cell = load_cell(JOB)
    state = initial_values(cell)
    for k in range(len(cell.seams)):
        on_seam = with_value(state, "seam", k)
        assert on_seam.speed == process_speed(cell, k).v_m_s
        faster = with_value(on_seam, "speed", 120)  # mm/s in the session
        assert process_speed(apply(cell, state, faster), k).v_m_s == pytest.approx(0.12)


def test_the_seam_inputs_and_its_time_law_hold_the_record():
    """The seam's inputs carry its speed; the cell they hold keeps motion.speed (no
    second copy of the seam's speed); the time law's limits and their nominal law (built
    once) run at it."""
    inputs = load_inputs(JOB, ROBOTS_DIR)
    assert inputs.speed is None  # a job's inputs: each seam has its own
    stripe = [s.name for s in job_seams(inputs.cell)].index("stripe")
    seam = seam_inputs(inputs, stripe)
    assert seam.speed == process_speed(inputs.cell, stripe) and seam.speed.v_m_s == 0.15
    assert seam.cell.motion == inputs.cell.motion and not seam.cell.seams
    fit = fit_path(seam)
    run = motion_setup(seam, flange_paths(seam, fit).rotations[0][1])
    assert run.limits.v_process == 0.15 and run.limits.length == run.parameter.length
    assert run.limits.nominal is run.limits.nominal and run.limits.nominal.v_max == 0.15
    # The process model's caps were computed at the seam's speed, too.
    assert (run.limits.a_max, run.limits.j_max) == (run.caps.a_max, run.caps.j_max)
    slower = dataclasses.replace(seam, speed=ProcessSpeed(0.05, "seams[3].speed"))
    assert motion_setup(slower, run.flange).limits.v_process == 0.05
