"""How long a flying seam's leads are and whether they take a normal move over
(``timing.lead_length``): the turn onto the seam within the tool's acceleration, and the
weld demo no slower flying than at rest; the ramp room kept per (v, a_max, j_max)."""

import dataclasses

import numpy as np
import pytest

from offline_prog.job.seams import seam_inputs
from offline_prog.path.lead import LIFT_POWER, MAX_LIFT_RATIO, LeadPath
from offline_prog.plan import StageTimer, plan_loaded_job
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import fit_path, flange_paths, load_inputs, motion_setup
from offline_prog.timing.lead_length import (
    AT_HEIGHT_TOL_M,
    _bend,
    ramp_length_m,
    slowed_end,
    takeover_extent_m,
)

from conftest import CELLS, random_flange_path

ACCELERATION_RTOL = 1e-3  # the finite-difference curvature against the sized one


@pytest.mark.parametrize(
    ("v", "a_max", "j_max", "lift", "at_height"),
    [
        (0.008, 0.5, 5.0, 0.05, 0.0),  # the TIG weld demo
        (0.1, 1.0, 10.0, 0.05, 0.0),  # the sealing demo
        (0.1, 1.0, 10.0, 0.05, 0.005),  # the sealing job: the gun opens 5 mm before
        (0.05, 1.0, 10.0, 0.03, 0.0),
        (0.001, 1.0, 10.0, 0.05, 0.0),  # slow: MAX_LIFT_RATIO binds
    ],
)
def test_a_lead_taking_a_move_over_turns_within_the_tools_limits(v, a_max, j_max, lift, at_height):
    """The lift h = H·(u/δ)⁴ of a lead that takes a normal move of H over bends, run at
    the process speed v, with a centripetal acceleration v²κ and jerk v³·dκ/ds within
    the cell's max_acceleration and max_jerk (one of them at its cap unless
    MAX_LIFT_RATIO or the valve's stretch binds), and where the valve is open the
    nozzle is within AT_HEIGHT_TOL_M of its working height."""
    extent = takeover_extent_m(lift, v=v, a_max=a_max, j_max=j_max, at_height_m=at_height)
    u = np.linspace(0.0, extent, 100_001)
    k = lift / extent**LIFT_POWER  # h = k·u⁴ and its derivatives in u, exactly
    dh, ddh, dddh = 4.0 * k * u**3, 12.0 * k * u**2, 24.0 * k * u
    bend = ddh / (1.0 + dh**2) ** 1.5  # κ [1/m]
    bend_rate = (dddh / (1.0 + dh**2) ** 1.5 - 3.0 * ddh**2 * dh / (1.0 + dh**2) ** 2.5) / (
        1.0 + dh**2
    ) ** 0.5  # dκ/ds [1/m²]
    acceleration = v**2 * np.abs(bend).max() / a_max
    jerk = v**3 * np.abs(bend_rate).max() / j_max
    assert max(acceleration, jerk) <= 1.0 + ACCELERATION_RTOL
    bound = lift / extent == pytest.approx(MAX_LIFT_RATIO) or at_height > 0.0
    assert bound or max(acceleration, jerk) >= 1.0 - ACCELERATION_RTOL
    assert lift * (at_height / extent) ** LIFT_POWER <= AT_HEIGHT_TOL_M * (1.0 + 1e-9)


def _job(entry: str):
    inputs = load_inputs(CELLS / "weld_seam_irb2400.yaml", ROBOTS_DIR)
    cell = inputs.cell
    cell = dataclasses.replace(cell, path=dataclasses.replace(cell.path, entry=entry))
    return plan_loaded_job(
        dataclasses.replace(inputs, cell=cell),
        StageTimer(lambda stage: None),
        clearance_profile=False,
    )


@pytest.mark.slow
def test_the_weld_demo_flying_is_no_slower_than_at_rest():
    """The 8 mm/s TIG demo, flying: its leads take the 50 mm approach and retract over
    (the torch comes down onto the seam along one curve), the seam runs at 8 mm/s from
    its first millimetre to its last, and the cycle is no longer than at rest."""
    flying, rest = _job("flying"), _job("rest")
    assert flying.feasible and rest.feasible
    plan = flying.chosen[0].plan
    assert plan.entry["entry"] == "flying"
    assert plan.flange.lifts_m == pytest.approx((0.05, 0.05))
    assert flying.chosen[0].approach is None and flying.chosen[0].retract is None
    speed = plan.trajectory.tcp_speed
    assert speed.min() == pytest.approx(0.008, rel=1e-3)
    assert flying.samples.t[-1] <= rest.samples.t[-1]


def test_a_kept_ramp_is_the_fresh_one_for_each_changed_input():
    """Each input changed in turn after a first call: the kept result is the one
    computed afresh (bit for bit), and it differs from the first (the cache is keyed on
    every input the ramp depends on)."""
    base = dict(v=0.1, a_max=1.0, j_max=20.0)
    first = ramp_length_m(base["v"], a_max=base["a_max"], j_max=base["j_max"])
    for key, value in (("v", 0.05), ("a_max", 0.5), ("j_max", 5.0)):
        args = base | {key: value}
        kept = ramp_length_m(args["v"], a_max=args["a_max"], j_max=args["j_max"])
        fresh = ramp_length_m.__wrapped__(args["v"], a_max=args["a_max"], j_max=args["j_max"])
        assert kept == fresh, key
        assert kept != first, key


def test_a_kept_takeover_extent_and_bend_are_the_fresh_ones():
    """The take-over's extent and the lift's bend, kept per arguments: bit for bit the
    ones computed afresh, for each argument changed in turn."""
    base = dict(lift=0.05, v=0.1, a_max=1.0, j_max=10.0, at_height_m=0.005)
    for key, value in (("lift", 0.03), ("v", 0.008), ("a_max", 0.5), ("j_max", 5.0)):
        for args in (base, base | {key: value}):
            kept = takeover_extent_m(args["lift"], **{k: args[k] for k in list(args)[1:]})
            fresh = takeover_extent_m.__wrapped__(
                args["lift"], **{k: args[k] for k in list(args)[1:]}
            )
            assert kept == fresh, key
    for ratio in (1.0, 7.3, MAX_LIFT_RATIO):
        assert _bend(ratio) == _bend(ratio) == _bend.__wrapped__(ratio)


@pytest.mark.parametrize("k", [0, 3])
def test_the_leads_as_run_are_the_ones_built_for_what_they_ask(k):
    """A seam of the sealing job (a stripe, a circle) with its default leads: the path
    ``with_leads`` gives, joined from the leads it compared, equals a LeadPath built
    afresh for the leads it asks (lengths and lifts), sample for sample; its leads take
    the approach and retract over."""
    job = load_inputs(CELLS / "seal_job_kr16.yaml", ROBOTS_DIR)
    inputs = seam_inputs(job, k)
    flange = flange_paths(inputs, fit_path(inputs)).rotations[0][1]
    run = motion_setup(inputs, flange).flange
    fresh = LeadPath(flange, **run.asked)
    assert run.lifts_m == fresh.lifts_m and min(run.lifts_m) >= 0.03  # moves taken over
    assert (run.lead_in_m, run.lead_out_m) == (fresh.lead_in_m, fresh.lead_out_m)
    s = np.linspace(run.start, run.end, 501)
    for field in ("p_IE", "dp_IE", "ddp_IE", "R_IE", "w_s", "dw_s", "p_PF", "R_PF"):
        np.testing.assert_array_equal(getattr(run(s), field), getattr(fresh(s), field))


def test_leads_are_missed_where_the_joint_limits_slow_a_seam_end_they_meet(rng):
    """A speed reduction (on the law's σ, 0 at the lead-in's start) over the seam's start
    or end that a lead meets: the leads miss their purpose, named with the share of the
    process speed; one inside the seam, or over an end no lead meets: they do not."""
    flange = random_flange_path(rng, closed=False)
    lead = LeadPath(flange, lead_in_m=0.03, lead_out_m=0.0)
    start, end = lead.lead_in_m, lead.lead_in_m + flange.length
    reason = slowed_end(lead, ((0.0, start + 0.01, 0.033),), 0.1)
    assert "seam's start at 33 % of the process speed" in reason
    assert slowed_end(lead, ((start + 0.001, end - 0.001, 0.01),), 0.1) == ""
    assert slowed_end(lead, ((end - 0.01, end, 0.01),), 0.1) == ""  # no lead-out there


@pytest.mark.slow
def test_a_small_circle_whose_leads_the_wrist_slows_runs_at_rest(tmp_path):
    """A 7.5 mm circle on the sealing job's plate: flying, its leads turn the wrist so
    fast that the joints' jerk held the whole seam at 1 % of the process speed (50 s
    instead of 1.5 s); it runs at rest, at 40 % or more of it, and report.json says why."""
    text = (CELLS / "seal_job_kr16.yaml").read_text(encoding="utf-8")
    head, tail = text[: text.index("\nseams:") + 1], text[text.index("\njob:") + 1 :]
    circle = "{kind: arc, center: [104.6, -12.5, 0], radius: 7.5, start_deg: 0, end_deg: 360}"
    seam = f"  - {{name: dot, analytic: {circle}, closed: true, units: mm, normal: [0, 0, 1]}}"
    cell = tmp_path / "dot.yaml"
    cell.write_text(f"{head}seams:\n{seam}\n{tail}", encoding="utf-8")
    job = plan_loaded_job(
        load_inputs(cell, ROBOTS_DIR), StageTimer(lambda stage: None), clearance_profile=False
    )
    assert job.feasible
    plan = job.chosen[0].plan
    assert plan.entry["entry"] == "rest"
    assert "the joint limits hold the seam's" in plan.entry["reason"]
    assert plan.trajectory.tcp_speed.max() >= 0.4 * job.cell.motion.speed
