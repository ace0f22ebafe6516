"""The outputs the programs set, replayed through the process model, give the report's
quality within 1 % (issue 28's acceptance).

URScript streams the output's value itself (``set_standard_analog_out`` between the
``servoj`` commands, every ``period`` seconds): the values are read back with the time
each holds from, and the model (tape: the heater's power, bead: the flow through the
dispenser's lag) replayed on them at the plan's speed. KRL programs the law instead
(``ANOUT ON ... = FK * $VEL_ACT + offset DELAY = −τ``, ``FK`` switched by
``TRIGGER``s): its factor, offset, limits and lead are read from the program and
replayed at the plan's speed in the plan's live window.
"""

import json
import re

import numpy as np
import pytest
from program_replay import (
    WORST_ALLOWED,
    acceptance,
    krl_flow,
    rapid_flow,
    ratio_to_target,
    replayed,
    switch_errors,
    urscript_flow,
    urscript_switch_errors,
)
from replay_jobs import (
    BEAD,
    UR_LEAD_MM,
    exported,
    one_seam_flying,
    plate_on_ur10e,
    seal_job_flying,
)

from offline_prog.process.registry import process_model

from conftest import CELLS, with_own_io

REPLAY_TOL = 0.01  # the issue: within 1 %
SWITCH_TOL_M = 0.12e-3  # a switch read from the program against the plan's position


def plan_folder(capsys, tmp_path, text: str):
    from offline_prog.plan import plan_job
    from offline_prog.results.job_folder import write_job_outputs

    cell = tmp_path / "cell.yaml"
    cell.write_text(text.replace(": data/", f": {CELLS}/data/"))
    job = plan_job(cell)
    assert job.feasible, job.failure
    write_job_outputs(job, tmp_path / "out")
    return job, tmp_path / "out"


def compare(job, folder, t, quality_prog):
    """Rows of the seam's moves (approach, seam, retract: wherever the gun may be open)
    where the plan's quality is defined and the tool moves (the report's stretches name
    the standstills): the replay within 1 %; and the share."""
    report = json.loads((folder / "report.json").read_text())["quality"]
    column = job.quality.column
    rows = np.zeros(len(column), bool)  # the seams' runs (not the links between them)
    for g in job.samples.segments:
        rows[g.start : g.stop] |= g.kind != "link"
    plan_t, plan_q = job.samples.t[rows], column[rows]
    keep = np.isfinite(plan_q)
    defined = np.interp(t, job.samples.t, (rows & np.isfinite(column)).astype(float)) == 1.0
    inside = (t > plan_t[keep][0]) & (t < plan_t[keep][-1]) & defined
    expected = np.interp(t[inside], plan_t[keep], plan_q[keep])
    top = job.tcp_speed[rows].max()  # the seams' (links move the part faster)
    moving = np.interp(t[inside], job.samples.t, job.tcp_speed) > 0.05 * top
    assert moving.sum() > 0.8 * inside.sum()  # the approach and retract start and stop
    # Within 1 % of the value, or of the target where the gun's lag fills or drains the
    # bead on the approach or retract (small values changing fast between samples).
    model = process_model(job.cell.process)
    np.testing.assert_allclose(
        quality_prog[inside][moving],
        expected[moving],
        rtol=REPLAY_TOL,
        atol=REPLAY_TOL * model.target * model.unit_scale,
    )
    low, high = report["band"]
    v = np.interp(t[inside], job.samples.t, job.tcp_speed)
    w = v * np.gradient(t[inside])  # path length each command stands for
    ok = (quality_prog[inside] >= low) & (quality_prog[inside] <= high)
    share = float((w * ok).sum() / w.sum())
    assert share == pytest.approx(report["share_within_band"], abs=REPLAY_TOL)
    return share


def assert_holds_the_bead(job, folder, t: np.ndarray, quality: np.ndarray) -> dict:
    """Issue 37's acceptance of a program's ``quality`` (K,) replayed at times ``t``
    (K,) [s]: within 1 % of the plan (``compare``), ≥ 99 % of the gun-on length within
    ±5 % of the target, no gun-on row beyond ±20 %, no gun-on row at a standstill.
    Returns the figures (``program_replay.acceptance``)."""
    compare(job, folder, t, quality)
    figures = acceptance(job, ratio_to_target(job, np.interp(job.samples.t, t, quality)))
    assert figures["share"] >= 0.99, figures
    assert figures["worst"] <= WORST_ALLOWED, figures
    assert figures["standstill"] == 0, figures
    return figures


def test_tape_heater_power_set_by_urscript_gives_the_reported_temperature(planned_job):
    job, folder = planned_job("tape_cylinder_ur10e")
    output = job.cell.process.tape_heating.power_output.analog_output
    script = (folder / "programs" / "offline_prog.script").read_text()
    t, value, _ = urscript_flow(job, script, output)
    compare(job, folder, t, replayed(job, t, value))


def test_bead_flow_set_by_urscript_gives_the_reported_bead(capsys, tmp_path):
    """The tape demo's UR10e laying a bead instead: the flow output leads by the lag,
    and the dispenser's lag on the streamed values gives the report's cross-section."""
    text = (CELLS / "tape_cylinder_ur10e.yaml").read_text()
    text = with_own_io(text, "tool:\n  process_io:\n    flow: {analog_output: 1}\n")
    job, folder = plan_folder(capsys, tmp_path, text.replace("motion:", BEAD + "motion:"))
    script = (folder / "programs" / "offline_prog.script").read_text()
    t, value, _ = urscript_flow(job, script, 1)
    compare(job, folder, t, replayed(job, t, value))


def bead_stripe(tmp_path, *, on_lead_mm: float, off_lead_mm: float, entry: str = "rest"):
    """Issue 24's stripe (cells/seal_job_kr16.yaml's, alone) laying the sealing demo's
    bead, run with ``entry``."""
    from export.test_job_io import stripe_cell

    cell = stripe_cell(tmp_path, on_lead_mm=on_lead_mm, off_lead_mm=off_lead_mm, lag_s=0.0)
    text = cell.read_text().replace("per_mps: 40.0, offset: 0.5, ", "")
    text = text.replace("direction: forward", f"direction: forward\n    entry: {entry}")
    cell.write_text(text.replace("motion:", BEAD + "motion:", 1))
    return cell


def test_bead_flow_written_in_krl_gives_the_reported_bead(tmp_path):
    """Issue 24's stripe (tangent approach and retract: every position on one line)
    laying the sealing demo's bead, the gun on 100 mm into it: the KRL's ``ANOUT ON
    $ANOUT[1]=FK*$VEL_ACT+offset DELAY=−τ MINIMUM MAXIMUM`` and its TRIGGERs' FK values
    and positions (from the program's own poses), replayed at the plan's speed."""
    cell = bead_stripe(tmp_path, on_lead_mm=-100.0, off_lead_mm=2.0)
    job, folder, data, krl = exported(cell, "krl")
    t, value, placed = krl_flow(job, data, krl)
    flow = [float(switch.value) for switch, _ in placed if "_FK" in switch.what]
    assert len(flow) == 2 and flow[0] > 0 and flow[1] == 0.0
    report = compare(job, folder, t, replayed(job, t, value))
    assert report < 1.0  # the bead starts 100 mm in at speed: the lag's thin start


@pytest.mark.slow
def test_a_flying_stripe_in_krl_lays_the_bead_from_its_first_millimetre(tmp_path):
    """Issue 37: the stripe run flying (``entry: flying``) with the gun on at its start,
    the bead's lag 0.08 s: the KRL's flow law and TRIGGERs replayed at the plan's speed
    give the plan's bead within 1 %, ≥ 99 % of the gun-on length within ±5 %, no row
    beyond ±20 % and no gun-on row at a standstill; the gun's TRIGGERs switch where
    the plan sets it."""
    cell = bead_stripe(tmp_path, on_lead_mm=0.0, off_lead_mm=0.0, entry="flying")
    job, folder, data, krl = exported(cell, "krl", flying=True)
    t, value, placed = krl_flow(job, data, krl)
    assert_holds_the_bead(job, folder, t, replayed(job, t, value))
    assert np.abs(switch_errors(data, placed, "$OUT[1]")).max() <= SWITCH_TOL_M


@pytest.mark.slow
def test_the_seal_job_all_flying_in_krl_lays_every_seams_bead(tmp_path):
    """cells/seal_job_kr16.yaml (border, two holes, stripe; no overlap set) with every
    seam ``entry: flying`` laying the bead (lag 0.08 s): every seam flies (report.json
    ``seams[].motion.entry``); the KRL's TRIGGERs switch the gun within 0.12 mm of the
    plan's positions, and its flow replayed at the plan's speed holds the job to issue
    37's acceptance and every seam's run to the plan's own figures."""
    cell = tmp_path / "seal_job_flying.yaml"
    cell.write_text(seal_job_flying(CELLS))
    job, folder, data, krl = exported(cell, "krl", flying=True)
    seams = json.loads((folder / "report.json").read_text())["seams"]
    assert [s["motion"]["entry"]["entry"] for s in seams] == ["flying"] * 4
    t, value, placed = krl_flow(job, data, krl)
    assert np.abs(switch_errors(data, placed, "$OUT[1]")).max() <= SWITCH_TOL_M
    quality = replayed(job, t, value)
    assert_holds_the_bead(job, folder, t, quality)
    plan = job.quality.values / job.quality.model.target - 1.0
    for name in data.seam_names:
        program, planned = (acceptance(job, r, name) for r in (ratio_to_target(job, quality), plan))
        assert program["share"] == pytest.approx(planned["share"], abs=REPLAY_TOL), name
        assert program["worst"] == pytest.approx(planned["worst"], abs=REPLAY_TOL), name
        assert program["standstill"] == 0, name


def flying_bead_cell(tmp_path, name: str, *, lead_mm: float | None = None):
    """The one-seam demo ``name`` laying the bead, its seam flying (``replay_jobs``)."""
    cell = tmp_path / f"{name}.yaml"
    cell.write_text(one_seam_flying(CELLS, name, lead_mm=lead_mm))
    return cell


@pytest.mark.slow
def test_a_flying_seam_in_rapid_lays_the_bead_from_its_first_millimetre(tmp_path):
    """The weld demo's IRB 2400 laying the bead on its seam run flying: each
    ``TriggSpeed``'s ScaleValue and ScaleLag and each ``TriggIO`` at its point (from
    the module's own targets), replayed at the plan's speed: issue 37's acceptance."""
    cell = flying_bead_cell(tmp_path, "weld_seam_irb2400")
    job, folder, data, rapid = exported(cell, "rapid", flying=True)
    text = (rapid / "OfflineProg.mod").read_text()
    t, value, placed = rapid_flow(job, data, text)
    assert_holds_the_bead(job, folder, t, replayed(job, t, value))
    assert np.abs(switch_errors(data, placed, "do2")).max() <= SWITCH_TOL_M


@pytest.fixture(scope="module")
def flying_urscript(tmp_path_factory):
    """The tape demo's UR10e laying the bead on its seam with 5 mm leads, exported to
    URScript: (job, folder, data, the script's folder, t, flow, period)."""
    tmp_path = tmp_path_factory.mktemp("ur_flying")
    cell = flying_bead_cell(tmp_path, "tape_cylinder_ur10e", lead_mm=UR_LEAD_MM)
    job, folder, data, ur = exported(cell, "urscript", flying=True)
    script = (ur / "offline_prog.script").read_text()
    return (job, folder, data, ur, *urscript_flow(job, script, 1))


@pytest.mark.slow
def test_a_flying_seam_in_urscript_holds_the_plans_bead(flying_urscript, tmp_path):
    """The UR10e's seam run with 5 mm leads (``replay_jobs``: its default leads collide
    and fall back to rest). The servoj stream's flow replayed at the plan's speed holds
    the plan's bead within 1 %, its gun switched by the command the tool is at where
    the plan sets it; the movep program replayed from its text (path, speed, flow at
    its points)."""
    from export.test_ur_moves import check_movep_program

    job, folder, data, ur, t, value, period = flying_urscript
    compare(job, folder, t, replayed(job, t, value))
    script = (ur / "offline_prog.script").read_text()
    late = urscript_switch_errors(data, script, t)  # set as the command before ends
    assert np.all(late >= 0.0) and late.max() <= job.cell.motion.speed * period + 1e-6, late
    check_movep_program(data, tmp_path / "movep")


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="the tape demo's UR10e cannot fly at 0.15 m/s (docs/jobs.md: its default "
    "leads collide, link_3 with link_6; 5 mm leads are too short for the ramp, so the "
    "seam starts at 0.03 m/s and 96.9 % of the bead is within ±5 %)",
)
def test_a_flying_seam_in_urscript_lays_the_bead_from_its_first_millimetre(flying_urscript):
    """A bead model's acceptance (``assert_holds_the_bead``) on the tape demo's own UR
    program, whose seam runs at rest: a limit of that cell, not of URScript (its own
    tape-heating model holds from the first millimetre; a UR job that flies on its
    default leads holds the bead:
    ``test_a_flying_seam_in_urscript_on_its_default_leads_lays_the_bead``)."""
    job, folder, _, _, t, value, _ = flying_urscript
    assert_holds_the_bead(job, folder, t, replayed(job, t, value))


@pytest.mark.slow
def test_a_flying_seam_in_urscript_on_its_default_leads_lays_the_bead(tmp_path):
    """Issue 37's acceptance on a UR job: the sealing demo's plate border carried by the
    tape demo's UR10e (``replay_jobs.plate_on_ur10e``), flying on its default leads
    (no ``motion.lead_mm``), exported to URScript: the servoj stream's flow replayed at
    the plan's speed holds the plan's bead within 1 %, ≥ 99 % of the gun-on length
    within ±5 %, no row beyond ±20 % and no gun-on row at a standstill; the gun is
    switched by the command the tool is at where the plan sets it."""
    cell = tmp_path / "plate_on_ur10e.yaml"
    cell.write_text(plate_on_ur10e(CELLS), encoding="utf-8")
    job, folder, data, ur = exported(cell, "urscript", flying=True)
    entry = job.chosen[0].plan.entry
    assert job.cell.motion.lead_mm is None and entry["lead_in_mm"] > UR_LEAD_MM, entry
    script = (ur / "offline_prog.script").read_text(encoding="utf-8")
    t, value, period = urscript_flow(job, script, 1)
    assert_holds_the_bead(job, folder, t, replayed(job, t, value))
    late = urscript_switch_errors(data, script, t)  # set as the command before ends
    assert np.all(late >= 0.0) and late.max() <= job.cell.motion.speed * period + 1e-6, late


def _compensation_rows(job):
    """(inside with compensation, inside without) (N,) per row."""
    quality, (low, high) = job.quality, job.quality.model.band
    inside_on = (quality.values >= low) & (quality.values <= high)
    inside_off = (quality.uncompensated >= low) & (quality.uncompensated <= high)
    return inside_on, inside_off


def test_sealing_demo_compensation_is_at_least_as_good(planned_job, tmp_path):
    """The issue's figure: on the sealing demo, the share of process length within ±5 %
    of the bead's target with compensation on is at least that with it off, on the job
    and on every seam (README, Process quality); no row is outside the band with
    compensation where it is inside without (the lead never spoils a good bead). Flying
    at a steady speed there is little to compensate; the demo at rest (its ramps)
    shows compensation winning."""
    from conftest import planned_text

    job, folder = planned_job("seal_plate_kr16")
    report = json.loads((folder / "report.json").read_text())["quality"]
    assert report["model"] == "bead" and report["band"] == pytest.approx([11.4, 12.6])
    assert report["share_within_band"] >= report["share_within_band_uncompensated"]
    for seam in report["seams"].values():
        assert seam["share_within_band"] >= seam["share_within_band_uncompensated"]
    assert report["share_within_band"] > 0.99
    inside_on, inside_off = _compensation_rows(job)
    assert not np.any(inside_off & ~inside_on)
    text = (CELLS / "seal_plate_kr16.yaml").read_text(encoding="utf-8")
    text = text.replace("  closed: true\n", "  closed: true\n  entry: rest\n")
    rest, _ = planned_text(text, tmp_path)
    inside_on, inside_off = _compensation_rows(rest)
    assert not np.any(inside_off & ~inside_on)
    assert np.count_nonzero(inside_on & ~inside_off) > 0


def law_replay(job, *, per_mps: float, lead_s: float, offset: float, low: float, high: float):
    """(N,) the speed-following output [V] a controller sets from its law at the plan's
    speed, leading by ``lead_s``, live in the plan's flow windows (the TRIGGERs'
    positions), idle (offset) otherwise, within [low, high]."""
    t = job.samples.t
    window = np.zeros(len(t), bool)
    flow = [e for e in job.io.events if e.signal.value == "analog"]
    for on, off in zip(flow[::2], flow[1::2], strict=True):
        window |= (t >= on.t_s) & (t < off.t_s)
    v_ahead = np.interp(t + lead_s, t, job.tcp_speed)
    return np.clip(np.where(window, per_mps, 0.0) * v_ahead + offset, low, high)


def test_bead_flow_law_written_in_rapid_gives_the_reported_bead(capsys, tmp_path):
    """The weld demo's IRB 2400 laying a bead: ``TriggSpeed tFlowOn, d, ScaleLag, ao1,
    ScaleValue`` (V per mm/s) read from the module, replayed at the plan's speed."""
    text = (CELLS / "weld_seam_irb2400.yaml").read_text()
    text = with_own_io(text, "tool:\n  process_io:\n    flow: {analog_output: 1}\n")
    job, folder = plan_folder(capsys, tmp_path, text.replace("motion:", BEAD + "motion:"))
    module = (folder / "programs" / "OfflineProg.mod").read_text()
    speeds = re.findall(r"TriggSpeed \w+, [\d.]+, ([\d.]+), ao1, ([\d.]+);", module)
    assert speeds and float(speeds[-1][1]) == 0.0
    scale_lag, per_mm_s = (float(x) for x in speeds[0])
    io = job.io.settings  # offset and limits are the signal's configuration (header)
    value = law_replay(
        job, per_mps=per_mm_s * 1e3, lead_s=scale_lag, offset=io.offset, low=io.min, high=io.max
    )
    compare(job, folder, job.samples.t, replayed(job, job.samples.t, value))
