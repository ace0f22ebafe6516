"""Approach and retract (job.approach) run at motion.approach_speed when the cell gives
it, else at the seam's process speed; the programs' linear moves carry that speed."""

import dataclasses

import numpy as np
import pytest

from offline_prog.config.process_speed import approach_speed
from offline_prog.job.approach import plan_ends
from offline_prog.job.seams import job_seams, seam_inputs
from offline_prog.plan import StageTimer, plan_loaded_job
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import load_inputs

from conftest import CELLS

WELD = "weld_seam_irb2400"  # TIG at 8 mm/s, approach and retract 50 mm along the normal


def _ends(planned_job, speed):
    """(approach, retract, the seam's plan) of the weld demo with
    motion.approach_speed = speed (the demo's own plan for None)."""
    inputs = load_inputs(CELLS / f"{WELD}.yaml", ROBOTS_DIR)
    motion = dataclasses.replace(inputs.cell.motion, approach_speed=speed)
    inputs = dataclasses.replace(inputs, cell=dataclasses.replace(inputs.cell, motion=motion))
    if speed is None:
        job, _ = planned_job(WELD)
    else:  # its leads are planned for that speed (they take no move over then)
        job = plan_loaded_job(inputs, StageTimer(lambda stage: None), clearance_profile=False)
    option = job.chosen[0]
    ends = plan_ends(seam_inputs(inputs, 0), option.plan, job_seams(inputs.cell)[0])
    return (*ends, option.plan)


@pytest.mark.parametrize("speed", [None, pytest.param(0.05, marks=pytest.mark.slow)])
def test_approach_and_retract_run_at_the_approach_speed(planned_job, speed):
    """The tool's peak speed along the move is the approach speed; at 50 mm/s both
    moves take under 1.5 s. The move and the flying seam's lead (lifting off the part by
    its lift) together take the tool the asked 50 mm off the surface. At the default
    (the process speed, 8 mm/s) the leads take the moves over: no move is left, and the
    leads' 50 mm down onto the seam and up off it take over 12 s at 8 mm/s."""
    approach, retract, plan = _ends(planned_job, speed)
    lifts = plan.flange.lifts_m  # (lead-in, lead-out)
    if speed is None:
        assert approach is None and retract is None
        assert lifts == pytest.approx((0.05, 0.05), abs=1e-9)
        assert plan.lead_in.t[-1] - plan.lead_in.t[0] + plan.lead_out.t[-1] > 12.0
        return
    for move, lift in zip((approach, retract), lifts, strict=True):
        v = np.abs(np.gradient(move.delta, move.t))
        assert v.max() == pytest.approx(speed, rel=0.01)
        length = np.linalg.norm(move.p_PT[-1] - move.p_PT[0])
        assert length + lift == pytest.approx(0.05, abs=1e-9)
    assert approach.duration + retract.duration < 3.0


def test_the_choice_is_made_once():
    inputs = load_inputs(CELLS / f"{WELD}.yaml", ROBOTS_DIR)
    process = seam_inputs(inputs, 0).speed
    assert approach_speed(inputs.cell, process) is process  # default: the process speed
    motion = dataclasses.replace(inputs.cell.motion, approach_speed=0.05)
    chosen = approach_speed(dataclasses.replace(inputs.cell, motion=motion), process)
    assert (chosen.v_m_s, chosen.key) == (0.05, "motion.approach_speed")
