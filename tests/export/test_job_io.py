"""Process I/O on a 240 mm straight seam, read back from every program's text.

The case of issue 24: ``on.lead_mm: -100`` puts the gun's on switch 100 mm into the
stripe, on the same LIN as the off switch (238 mm); the KRL job dropped one of them.
The cell here also has a dispenser lag of 0.1 s. Each program (KRL, RAPID, URScript)
is parsed, the tool's point on the part at each switch reconstructed from the
program's own poses and joints, and its position along the stripe compared with the
numbers computed here from the cell's ``lead_mm``, ``lag_s`` and the seam's ends.
"""

import csv
import dataclasses
import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from program_readers import Switch, krl_items, rapid_items, tool_in_part

from offline_prog.config.cell import load_cell
from offline_prog.constants import FLOW_PRIME_LAGS
from offline_prog.export.formats import controller_post
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.post import write_program
from offline_prog.io_events import IoEvent, Signal
from offline_prog.plan import plan_job
from offline_prog.results.job_folder import write_job_outputs

from conftest import CELLS

IO_TOL_M = 1e-3  # the issue: within ±1 mm
START_P = np.array([-0.120, 0.080, 0.0])  # the stripe in P [m] (cells/seal_job_kr16.yaml)
END_P = np.array([0.120, 0.080, 0.0])
LENGTH_M = float(np.linalg.norm(END_P - START_P))  # 240 mm
ON_LEAD_MM, OFF_LEAD_MM, PER_MPS, OFFSET_V, LAG_S = -100.0, 2.0, 40.0, 0.5, 0.1
SPEED_M_S = 0.15  # the stripe's speed in the cell
# The stripe runs flying (the default entry): its flow goes live this many lags ahead
# of the valve, the tool at the stripe's speed there.
PRIME_S = FLOW_PRIME_LAGS * LAG_S


def write(data: JobProgramData, fmt: str, folder: Path) -> list[Path]:
    """The files of format ``fmt``'s writer on the job (whatever the plan's controller:
    its events are what is read here)."""
    return write_program(controller_post(data, fmt), folder)


def stripe_cell(tmp_path, on_lead_mm=ON_LEAD_MM, off_lead_mm=OFF_LEAD_MM, lag_s=LAG_S):
    """seal_job_kr16 with only its stripe (run forward), and the given I/O."""
    text = (CELLS / "seal_job_kr16.yaml").read_text()
    head, rest = text.split("seams:", 1)
    stripe = rest[rest.index("  - name: stripe") : rest.index("job:")]
    tail = rest[rest.index("job:") :]
    head = re.sub(
        r"on:  \{digital_output: 1, lead_mm: 5\}",
        f"on:  {{digital_output: 1, lead_mm: {on_lead_mm}}}",
        head,
    )
    head = re.sub(
        r"off: \{digital_output: 1, lead_mm: 2\}",
        f"off: {{digital_output: 1, lead_mm: {off_lead_mm}}}",
        head,
    )
    head = head.replace("min: 0.0, max: 10.0}", f"min: 0.0, max: 10.0, lag_s: {lag_s}}}")
    stripe = stripe.replace("direction: auto", "direction: forward")
    file = tmp_path / "stripe.yaml"
    file.write_text(head + "seams:\n" + stripe + tail.replace("order: auto", "order: given"))
    return file


@pytest.fixture(scope="module")
def stripe(tmp_path_factory):
    """(JobProgramData, plan folder, cell file) of the stripe job."""
    work = tmp_path_factory.mktemp("stripe")
    cell = stripe_cell(work)
    io = load_cell(cell).tool.process_io
    assert (io.on.lead_mm, io.off.lead_mm, io.flow.lag_s) == (ON_LEAD_MM, OFF_LEAD_MM, LAG_S)
    job = plan_job(cell)
    assert job.feasible, job.failure
    write_job_outputs(job, work / "plan")
    return JobProgramData.load(work / "plan"), work / "plan", cell


def asked() -> tuple[float, float]:
    """(on, off) along the stripe from its start [m], from the cell's numbers."""
    return -ON_LEAD_MM * 1e-3, LENGTH_M - OFF_LEAD_MM * 1e-3


def along(data: JobProgramData, p_PT: np.ndarray, off_path_m: float = 1e-4) -> float:
    """Position of a tool point on the part along the stripe's planned path [m] (the
    plan's ``path_m``: from the seam's start, negative on the approach, beyond L on the
    retract; a flying seam's leads curve off the stripe's line): the point must lie
    within ``off_path_m`` of the tool's planned path on the part."""
    rows = data.job
    planned = np.flatnonzero(np.isfinite(rows.path_m))  # the stripe's approach .. retract
    p, s = rows.X_PT[planned, :3, 3], rows.path_m[planned]
    a, b = p[:-1], p[1:]
    step = b - a
    squared = np.maximum(np.einsum("ij,ij->i", step, step), 1e-30)  # rows at rest repeat
    x = np.clip(np.einsum("ij,ij->i", p_PT - a, step) / squared, 0.0, 1.0)
    gap = np.linalg.norm(a + x[:, None] * step - p_PT, axis=1)
    k = int(np.argmin(gap))
    assert gap[k] < off_path_m  # on the planned path
    return float(s[k] + x[k] * (s[k + 1] - s[k]))


# --- KRL ------------------------------------------------------------------------------


def krl_events(data, folder):
    """(the run's statements, [(what, value, position [m], DELAY [ms])] of every
    TRIGGER in run order): the switch point's position along the planned path
    (``along``)."""
    run, items = krl_items(data, folder)
    switches = [s for s in items if isinstance(s, Switch)]
    return run, [(s.what, s.value, along(data, s.p_PT), s.delay_s * 1e3) for s in switches]


def test_krl_keeps_both_switches_on_one_lin(stripe, tmp_path):
    data, _, _ = stripe
    files = write(data, "krl", tmp_path)
    run, events = krl_events(data, tmp_path)
    on, off = asked()
    out = [(value, position) for what, value, position, _ in events if what == "$OUT[1]"]
    assert [v for v, _ in out] == ["TRUE", "FALSE"]
    assert out[0][1] == pytest.approx(on, abs=IO_TOL_M)
    assert out[1][1] == pytest.approx(off, abs=IO_TOL_M)
    # Both fall on the stripe's own LIN(s): the seam module holds both TRIGGERs.
    module = next(f for f in files if f.name == "offline_prog_1.src").read_text()
    assert len(re.findall(r"^TRIGGER .* DO \$OUT\[1\]", module, re.M)) == 2
    # The flow: its factor goes live PRIME_S earlier: at v · PRIME_S before the on switch
    # (the stripe runs at its speed there), and is cut at the off switch (not led).
    flow = [(value, position, delay) for what, value, position, delay in events if "_FK" in what]
    assert [float(v) for v, _, _ in flow] == [pytest.approx(PER_MPS / 10), 0.0]
    assert flow[0][1] == pytest.approx(on - SPEED_M_S * PRIME_S, abs=IO_TOL_M)
    assert flow[1][1] == pytest.approx(off, abs=IO_TOL_M)  # cut as the valve closes
    assert all(delay == 0 for _, _, delay in flow)  # no negative DELAY to be clamped
    # One ANOUT ON before any motion, idle until a trigger: no constant factor.
    anout = [line for line in run if line.startswith("ANOUT ON")]
    assert len(anout) == 1 and run.index(anout[0]) < run.index("PTP XHOME")
    assert re.match(
        rf"ANOUT ON \$ANOUT\[1\]=OFFLINE_PROG_FK\*\$VEL_ACT\+{OFFSET_V / 10:.6f} "
        rf"DELAY=-{LAG_S:.3f} ",
        anout[0],
    )


# --- RAPID ----------------------------------------------------------------------------


def rapid_events(data, text):
    """[(trigger kind, value, position [m], ScaleLag or None)] in run order."""
    switches = [s for s in rapid_items(data, text) if isinstance(s, Switch)]
    return [(s.what, s.value, along(data, s.p_PT), s.lag_s) for s in switches]


def test_rapid_switches_and_flow_at_the_cells_positions(stripe, tmp_path):
    data, _, _ = stripe
    text = write(data, "rapid", tmp_path)[0].read_text()
    events = rapid_events(data, text)
    on, off = asked()
    out = [(v, p) for what, v, p, _ in events if what == "do1"]
    assert [v for v, _ in out] == ["1", "0"]
    assert [p for _, p in out] == [
        pytest.approx(on, abs=IO_TOL_M),
        pytest.approx(off, abs=IO_TOL_M),
    ]
    flow = [(float(v), p, lag) for what, v, p, lag in events if what == "ao1"]
    assert [v for v, _, _ in flow] == [pytest.approx(PER_MPS / 1000), 0.0]
    # ScaleLag leads both by lag_s: the flow goes live where the tool is lag_s after the
    # plan sets it (PRIME_S before the on switch), and the cut-off is placed where the
    # tool is lag_s after the valve closes (on the lead-out, the stripe flying), so the
    # controller sets it as the valve closes (the flow stays live until then).
    cut = next(e for e in data.events if e.signal is Signal.ANALOG and not e.state)
    close = next(e for e in data.events if e.signal is Signal.DIGITAL and not e.state)
    assert cut.t_s == pytest.approx(close.t_s) and cut.path_m > off
    assert [p for _, p, _ in flow] == [
        pytest.approx(on - SPEED_M_S * (PRIME_S - LAG_S), abs=IO_TOL_M),
        pytest.approx(cut.path_m, abs=IO_TOL_M),
    ]
    assert all(lag == LAG_S for _, _, lag in flow)  # ScaleLag is the cell's lag_s
    assert "\\Start" not in text  # nothing switches at a motion's start


# --- URScript -------------------------------------------------------------------------


def test_urscript_switches_and_flow_at_the_cells_positions(stripe, tmp_path):
    data, _, _ = stripe
    (script,) = write(data, "urscript", tmp_path)
    lines = [s.strip() for s in script.read_text().splitlines()]
    period = float(re.search(r"servoj\(.*t=([\d.]+)", "\n".join(lines))[1])
    q_of = lambda line: np.array(re.search(r"\(\[([^\]]*)\]", line)[1].split(","), float)  # noqa: E731
    servoj = [i for i, line in enumerate(lines) if line.startswith("servoj(")]
    positions = {i: along(data, tool_in_part(data, q_of(lines[i]))) for i in servoj}
    digital, analog, pending = [], [], []
    for i, line in enumerate(lines):
        if line.startswith("set_standard"):
            pending.append(line)
        elif i in positions:
            for s in pending:
                value = re.search(r", ([^,)]+)\)$", s)[1]
                (digital if "digital" in s else analog).append((value, positions[i], i))
            pending = []
    on, off = asked()
    assert [v for v, _, _ in digital] == ["True", "False"]
    # The stream advances by v·period per command: the switch is at most that late.
    for (_, p, _), asked_m in zip(digital, (on, off), strict=True):
        assert asked_m - 1e-6 <= p <= asked_m + SPEED_M_S * period + IO_TOL_M
    # The flow: idle before it goes live PRIME_S (PRIME_S / period commands) ahead of the
    # gun, the live value at once (not a ramp from idle), idle again as the gun closes
    # (the cut-off is not led: a flow cut lag_s early thins the seam's end).
    volts = [(float(v) * 10.0, p, i) for v, p, i in analog]
    live_flow = OFFSET_V + PER_MPS * SPEED_M_S
    first = next(k for k, (v, _, _) in enumerate(volts) if v > OFFSET_V + 0.01)
    assert all(v == pytest.approx(OFFSET_V) for v, _, _ in volts[:first])
    assert volts[first][0] == pytest.approx(live_flow, rel=0.01)
    assert volts[first][1] == pytest.approx(on - SPEED_M_S * PRIME_S, abs=IO_TOL_M)
    back = next(k for k in range(first, len(volts)) if volts[k][0] < OFFSET_V + 0.01)
    assert volts[back][0] == pytest.approx(OFFSET_V)
    assert all(v == pytest.approx(OFFSET_V) for v, _, _ in volts[back:])

    def commands_between(i, j):
        return servoj.index(j) - servoj.index(i)

    lead = PRIME_S / period
    assert commands_between(volts[first][2], digital[0][2]) == pytest.approx(lead, abs=1.01)
    assert commands_between(volts[back][2], digital[1][2]) == pytest.approx(0, abs=1.01)
    # The speed at the switch, from the program's own joints: the flow follows it.
    i = volts[first][2]
    v = (positions[servoj[servoj.index(i) + 1]] - positions[i]) / period
    assert volts[first][0] == pytest.approx(OFFSET_V + PER_MPS * v, rel=0.02)


# --- the plan's own columns -----------------------------------------------------------


def test_trajectory_csv_flow_leads_the_output_by_the_lag_and_is_cut_with_it(stripe):
    _, folder, _ = stripe
    with open(folder / "trajectory.csv") as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["t"]) for r in rows])
    do = np.array([int(float(r["do1"])) for r in rows])
    ao = np.array([float(r["ao1"]) for r in rows])
    live = ao > OFFSET_V + 1e-9
    t_on, t_off = t[np.argmax(do == 1)], t[len(do) - np.argmax(do[::-1] == 1)]
    t_live, t_idle = t[np.argmax(live)], t[len(live) - np.argmax(live[::-1])]
    dt = np.diff(t).max()
    assert t_live == pytest.approx(t_on - PRIME_S, abs=dt)
    assert t_idle == pytest.approx(t_off, abs=dt)  # the cut-off is not led
    assert np.all(ao[~live] == OFFSET_V)  # idle: the flow at zero speed


# --- export refuses what is not this plan's program ------------------------------------


def run_cli(argv, capsys) -> tuple[int, list[str]]:
    from offline_prog.cli import main

    capsys.readouterr()
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err.strip().splitlines()


@pytest.mark.parametrize("fmt", ["urscript", "rapid"])
def test_export_refuses_another_controllers_language(stripe, tmp_path, capsys, fmt):
    """A KUKA plan has no UR or ABB program (it would carry KR 16 joint angles)."""
    _, folder, _ = stripe
    code, err = run_cli(["export", folder, "--format", fmt, "--out", tmp_path], capsys)
    assert code == 2 and len(err) == 1, err
    assert f"{fmt} is not the controller language" in err[0] and "kuka_kr16_2" in err[0]
    assert not list(tmp_path.glob(f"*.{'script' if fmt == 'urscript' else 'mod'}"))
    code, _ = run_cli(["export", folder, "--format", "csv", "--out", tmp_path], capsys)
    assert code == 0  # the joint files are for every robot


def test_export_refuses_a_job_folder_without_its_job_file(stripe, tmp_path, capsys):
    import shutil

    _, folder, _ = stripe
    broken = tmp_path / "plan"
    shutil.copytree(folder, broken)
    (broken / "job.npz").unlink()
    for fmt in ("csv", "krl"):
        code, err = run_cli(["export", broken, "--format", fmt, "--out", tmp_path / fmt], capsys)
        assert code == 2 and len(err) == 1, err
        assert "job.npz" in err[0] and "missing" in err[0]


def test_export_refuses_a_foreign_plan_beside_job_npz(stripe, planned_folder, tmp_path, capsys):
    import shutil

    _, folder, _ = stripe
    broken = tmp_path / "plan"
    shutil.copytree(folder, broken)
    shutil.copy(planned_folder("seal_plate_kr16")[1] / "plan.npz", broken / "plan.npz")
    code, err = run_cli(["export", broken, "--format", "krl", "--out", tmp_path / "k"], capsys)
    assert code == 2 and len(err) == 1, err
    assert "job.npz: does not belong to" in err[0]


# --- property: any switch positions the plan decides are where the programs switch -----


@settings(max_examples=12, deadline=None, derandomize=True)
@given(
    positions_mm=st.lists(st.floats(-30.0, 270.0), min_size=2, max_size=6, unique=True)
    .map(sorted)
    .filter(lambda p: len(p) % 2 == 0)
)
def test_programs_switch_where_the_events_say(stripe, positions_mm):
    """On/off pairs anywhere on the stripe's approach (from −30 mm), seam and retract
    (to 270 mm), several on one motion: KRL and RAPID switch at each, in order."""
    data, _, _ = stripe
    events = tuple(
        IoEvent("stripe", Signal.DIGITAL, 1, k % 2 == 0, float(k % 2 == 0), p * 1e-3, 0.0, p * 1e-3)
        for k, p in enumerate(positions_mm)
    )
    data = dataclasses.replace(data, events=events)
    expected = [(k % 2 == 0, p * 1e-3) for k, p in enumerate(positions_mm)]
    with tempfile.TemporaryDirectory() as folder:
        write(data, "krl", Path(folder))
        _, krl = krl_events(data, Path(folder))
        text = write(data, "rapid", Path(folder))[0].read_text()
    got = [(value == "TRUE", p) for what, value, p, _ in krl if what == "$OUT[1]"]
    assert [s for s, _ in got] == [s for s, _ in expected]
    assert [p for _, p in got] == [pytest.approx(p, abs=IO_TOL_M) for _, p in expected]
    got = [(value == "1", p) for what, value, p, _ in rapid_events(data, text) if what == "do1"]
    assert [s for s, _ in got] == [s for s, _ in expected]
    assert [p for _, p in got] == [pytest.approx(p, abs=IO_TOL_M) for _, p in expected]


def test_valve_delays_move_every_programs_switch_ahead_by_the_response(tmp_path):
    """``delay_s`` on both switches: KRL's TRIGGERs and RAPID's TriggIOs set the gun
    where the plan sets it (its events' ``set_path_m``), ahead of the cell's positions,
    so the valve opens and closes there; the flow's cut-off is at the valve's closing."""
    on_delay, off_delay = 0.05, 0.02
    cell = stripe_cell(tmp_path)
    text = cell.read_text()
    text = text.replace(f"lead_mm: {ON_LEAD_MM}}}", f"lead_mm: {ON_LEAD_MM}, delay_s: {on_delay}}}")
    text = text.replace(
        f"lead_mm: {OFF_LEAD_MM}}}", f"lead_mm: {OFF_LEAD_MM}, delay_s: {off_delay}}}"
    )
    cell.write_text(text)
    job = plan_job(cell)
    assert job.feasible, job.failure
    write_job_outputs(job, tmp_path / "plan")
    data = JobProgramData.load(tmp_path / "plan")
    on, off = asked()
    switches = [e for e in data.events if e.signal is Signal.DIGITAL]
    assert [e.path_m for e in switches] == [pytest.approx(on), pytest.approx(off)]
    # At the stripe's speed on the way in: v · delay ahead; the end is slowing down.
    assert switches[0].set_path_m == pytest.approx(on - SPEED_M_S * on_delay, abs=1e-4)
    assert off - SPEED_M_S * off_delay - 1e-4 < switches[1].set_path_m < off - 1e-4
    planned = [e.set_path_m for e in switches]
    write(data, "krl", tmp_path / "krl")
    _, events = krl_events(data, tmp_path / "krl")
    krl = [position for what, _, position, _ in events if what == "$OUT[1]"]
    assert krl == [pytest.approx(p, abs=IO_TOL_M) for p in planned]
    cut = [position for what, v, position, _ in events if "_FK" in what and float(v) == 0.0]
    assert cut == [pytest.approx(off, abs=IO_TOL_M)]
    rapid = rapid_events(data, write(data, "rapid", tmp_path / "rapid")[0].read_text())
    assert [p for what, _, p, _ in rapid if what == "do1"] == [
        pytest.approx(p, abs=IO_TOL_M) for p in planned
    ]
