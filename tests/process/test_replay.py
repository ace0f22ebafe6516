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

from offline_prog.process.registry import process_model

from conftest import CELLS, with_own_io

REPLAY_TOL = 0.01  # the issue: within 1 %
BEAD_ON_UR = (  # the bead of the sealing demo, on another demo's robot
    "process:\n  model: bead\n"
    "  bead: {area_mm2: 12.0, tolerance_pct: 5, flow_mm3_s_per_unit: 250.0, lag_s: 0.08}\n"
)


def urscript_stream(script: str, output: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(K, 6) the servoj joint targets [rad], (K,) the output's value [V] while each
    runs, and the period [s] of the first servoj block (one-seam job: one block)."""
    period = float(re.search(r"servoj\(.*t=([\d.]+)", script)[1])
    q, value, current = [], [], 0.0
    for line in script.splitlines():
        line = line.strip()
        if m := re.match(rf"set_standard_analog_out\({output}, ([-\d.]+)\)", line):
            current = float(m[1]) * 10.0  # URScript's 0..1 of the 10 V range
        elif line.startswith("servoj("):
            q.append(np.array(re.search(r"\(\[([^\]]*)\]", line)[1].split(","), float))
            value.append(current)
    return np.array(q), np.array(value), period


def stream_times(job, q_stream: np.ndarray, period: float) -> np.ndarray:
    """(K,) the plan's time of each servoj target: the block runs the approach to the
    retract every ``period``; its start is where the joints agree with the plan's."""
    s = job.samples
    start = next(g.t_start for g in s.segments if g.kind == "approach")
    best = None
    for shift in np.arange(-2, 3) * period:
        t = start + shift + period * np.arange(len(q_stream))
        q_plan = np.stack([np.interp(t, s.t, s.q[:, j]) for j in range(6)], axis=1)
        error = np.abs(job.robot.controller_joints(q_plan) - q_stream).max()
        if best is None or error < best[0]:
            best = (error, t)
    assert best[0] < 1e-3, f"the servoj stream is not the plan's motion ({best[0]:.2g} rad)"
    return best[1]


def replayed(job, t: np.ndarray, value: np.ndarray) -> np.ndarray:
    """The model on the program's values at its times, at the plan's speed there."""
    model = process_model(job.cell.process)
    v = np.interp(t, job.samples.t, job.tcp_speed)
    return model.predict(t, v, value) * model.unit_scale


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
    moves = [g for g in job.samples.segments if g.kind != "link"]
    rows = slice(moves[0].start, moves[-1].stop)
    plan_t, plan_q = job.samples.t[rows], column[rows]
    keep = np.isfinite(plan_q)
    inside = (t > plan_t[keep][0]) & (t < plan_t[keep][-1])
    expected = np.interp(t[inside], plan_t[keep], plan_q[keep])
    top = job.tcp_speed[rows].max()  # the seam's (links move the part faster)
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


def test_tape_heater_power_set_by_urscript_gives_the_reported_temperature(planned_job):
    job, folder = planned_job("tape_cylinder_ur10e")
    output = job.cell.process.tape_heating.power_output.analog_output
    script = (folder / "programs" / "offline_prog.script").read_text()
    q, value, period = urscript_stream(script, output)
    t = stream_times(job, q, period)
    compare(job, folder, t, replayed(job, t, value))


def test_bead_flow_set_by_urscript_gives_the_reported_bead(capsys, tmp_path):
    """The tape demo's UR10e laying a bead instead: the flow output leads by the lag,
    and the dispenser's lag on the streamed values gives the report's cross-section."""
    text = (CELLS / "tape_cylinder_ur10e.yaml").read_text()
    text = with_own_io(text, "tool:\n  process_io:\n    flow: {analog_output: 1}\n")
    job, folder = plan_folder(capsys, tmp_path, text.replace("motion:", BEAD_ON_UR + "motion:"))
    script = (folder / "programs" / "offline_prog.script").read_text()
    q, value, period = urscript_stream(script, 1)
    t = stream_times(job, q, period)
    compare(job, folder, t, replayed(job, t, value))


def test_bead_flow_written_in_krl_gives_the_reported_bead(tmp_path):
    """Issue 24's stripe (tangent approach and retract: every position on one line)
    laying the sealing demo's bead, the gun on 100 mm into it: the KRL's ``ANOUT ON
    $ANOUT[1]=FK*$VEL_ACT+offset DELAY=−τ MINIMUM MAXIMUM`` and its TRIGGERs' FK values
    and positions (from the program's own poses), replayed at the plan's speed."""
    from export.test_job_io import krl_events, stripe_cell

    from offline_prog.export.formats import controller_post
    from offline_prog.export.job_program import JobProgramData
    from offline_prog.export.post import write_program
    from offline_prog.plan import plan_job
    from offline_prog.results.job_folder import write_job_outputs

    cell = stripe_cell(tmp_path, on_lead_mm=-100.0, off_lead_mm=2.0, lag_s=0.0)
    text = cell.read_text().replace("per_mps: 40.0, offset: 0.5, ", "")
    cell.write_text(text.replace("motion:", BEAD_ON_UR + "motion:", 1))
    job = plan_job(cell)
    assert job.feasible, job.failure
    folder = tmp_path / "plan"
    write_job_outputs(job, folder)
    data = JobProgramData.load(folder)
    write_program(controller_post(data, "krl"), tmp_path / "krl")
    src = (tmp_path / "krl" / "offline_prog.src").read_text()
    m = re.search(
        r"ANOUT ON \$ANOUT\[1\]=(\w+)\*\$VEL_ACT\+([-\d.]+) DELAY=([-\d.]+) "
        r"MINIMUM=([-\d.]+) MAXIMUM=([-\d.]+)",
        src,
    )
    assert m, "no speed-following ANOUT in the KRL"
    offset, delay, low, high = (float(x) for x in m.groups()[1:])
    _, events = krl_events(data, tmp_path / "krl")
    flow = [(float(value), position) for what, value, position, _ in events if what == m[1]]
    (fk, p_on), (idle, p_off) = flow
    assert fk > 0 and idle == 0.0
    # The tool's time at each TRIGGER's position (the seam's rows: path_m rises).
    s = job.samples
    rows = np.flatnonzero(np.isfinite(s.path_m))
    t_on, t_off = np.interp([p_on, p_off], s.path_m[rows], s.t[rows])
    t = s.t
    live = np.where((t >= t_on) & (t < t_off), fk, 0.0)
    v_ahead = np.interp(t - delay, t, job.tcp_speed)  # DELAY < 0: the output leads
    value = 10.0 * np.clip(live * v_ahead + offset, low, high)
    report = compare(job, folder, t, replayed(job, t, value))
    assert report < 1.0  # the bead starts 100 mm in at speed: the lag's thin start


@pytest.mark.slow
def test_a_flying_stripe_in_krl_lays_the_bead_from_its_first_millimetre(tmp_path):
    """Issue 37: the stripe run flying (``entry: flying``) with the gun on at its start,
    the bead's lag 0.08 s: the KRL's flow law and TRIGGERs replayed at the plan's speed
    give the plan's bead within 1 %, ≥ 99 % of the gun-on length within ±5 %, no row
    beyond ±20 % and no gun-on row at a standstill."""
    from export.test_job_io import krl_events, stripe_cell

    from offline_prog.export.formats import controller_post
    from offline_prog.export.job_program import JobProgramData
    from offline_prog.export.post import write_program
    from offline_prog.plan import plan_job
    from offline_prog.results.job_folder import write_job_outputs

    cell = stripe_cell(tmp_path, on_lead_mm=0.0, off_lead_mm=0.0, lag_s=0.0)
    text = cell.read_text().replace("per_mps: 40.0, offset: 0.5, ", "")
    text = text.replace("direction: forward", "direction: forward\n    entry: flying")
    cell.write_text(text.replace("motion:", BEAD_ON_UR + "motion:", 1))
    job = plan_job(cell)
    assert job.feasible, job.failure
    assert job.chosen[0].plan.entry["entry"] == "flying"
    folder = tmp_path / "plan"
    write_job_outputs(job, folder)
    data = JobProgramData.load(folder)
    write_program(controller_post(data, "krl"), tmp_path / "krl")
    src = (tmp_path / "krl" / "offline_prog.src").read_text()
    m = re.search(
        r"ANOUT ON \$ANOUT\[1\]=(\w+)\*\$VEL_ACT\+([-\d.]+) DELAY=([-\d.]+) "
        r"MINIMUM=([-\d.]+) MAXIMUM=([-\d.]+)",
        src,
    )
    offset, delay, low, high = (float(x) for x in m.groups()[1:])
    _, events = krl_events(data, tmp_path / "krl", off_line_m=0.05)  # the leads lift
    flow = [(float(value), position) for what, value, position, _ in events if what == m[1]]
    (fk, p_on), (_, p_off) = flow
    s = job.samples
    rows = np.flatnonzero(np.isfinite(s.path_m))
    t_on, t_off = np.interp([p_on, p_off], s.path_m[rows], s.t[rows])
    t = s.t
    live = np.where((t >= t_on) & (t < t_off), fk, 0.0)
    v_ahead = np.interp(t - delay, t, job.tcp_speed)
    value = 10.0 * np.clip(live * v_ahead + offset, low, high)
    replay = replayed(job, t, value)
    compare(job, folder, t, replay)
    on = job.io.valve.astype(bool)
    model = process_model(job.cell.process)
    ratio = replay / (model.target * model.unit_scale) - 1.0
    w = job.tcp_speed * np.gradient(t)
    assert (w * (on & (np.abs(ratio) <= 0.05))).sum() / (w * on).sum() >= 0.99
    assert np.abs(ratio[on]).max() <= 0.20
    assert np.all(job.tcp_speed[on] > 1e-3 * job.cell.motion.speed)


def test_sealing_demo_compensation_is_at_least_as_good(planned_job):
    """The issue's figure: on the sealing demo, the share of process length within ±5 %
    of the bead's target with compensation on is at least that with it off, on the job
    and on every seam (README, Process quality)."""
    job, folder = planned_job("seal_plate_kr16")
    report = json.loads((folder / "report.json").read_text())["quality"]
    assert report["model"] == "bead" and report["band"] == pytest.approx([11.4, 12.6])
    assert report["share_within_band"] >= report["share_within_band_uncompensated"]
    for seam in report["seams"].values():
        assert seam["share_within_band"] >= seam["share_within_band_uncompensated"]
    assert report["share_within_band"] > 0.95
    # Everywhere: no row is outside the band with compensation where it is inside
    # without (the lead never spoils a good bead), and compensation wins somewhere.
    quality, (low, high) = job.quality, job.quality.model.band
    inside_on = (quality.values >= low) & (quality.values <= high)
    inside_off = (quality.uncompensated >= low) & (quality.uncompensated <= high)
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
    job, folder = plan_folder(capsys, tmp_path, text.replace("motion:", BEAD_ON_UR + "motion:"))
    module = (folder / "programs" / "OfflineProg.mod").read_text()
    speeds = re.findall(r"TriggSpeed \w+, [\d.]+, ([\d.]+), ao1, ([\d.]+);", module)
    assert speeds and float(speeds[-1][1]) == 0.0
    scale_lag, per_mm_s = (float(x) for x in speeds[0])
    io = job.io.settings  # offset and limits are the signal's configuration (header)
    value = law_replay(
        job, per_mps=per_mm_s * 1e3, lead_s=scale_lag, offset=io.offset, low=io.min, high=io.max
    )
    compare(job, folder, job.samples.t, replayed(job, job.samples.t, value))
