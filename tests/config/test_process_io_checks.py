"""Process I/O the plan cannot honour ends with one line and exit 2, nothing written.

Reproductions (issue 24): ``flow.per_mps: -40`` clipped the flow to 0 V on the whole
seam; on at 100 mm and off at 90 mm were accepted, as was an off switch before the
seam's start; ``tool.process_io`` on a ``path:`` cell (also with ``job:`` written but
empty) was ignored without a word.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from offline_prog.cli import main
from offline_prog.config.cell import AnalogFlow, DigitalSwitch, ProcessIoConfig
from offline_prog.io_events import Signal
from offline_prog.job.assemble import JobSamples, Segment
from offline_prog.job.process_io import IoPlacementError, io_columns

from conftest import CELLS, with_own_io

IO = (
    "tool:\n  process_io:\n    on:  {digital_output: 1, lead_mm: 5}\n"
    "    off: {digital_output: 1, lead_mm: 2}\n"
    "    flow: {analog_output: 1, per_mps: 40.0, offset: 0.5}\n"
)


def run(capsys, tmp_path, cell_text: str) -> tuple[int, list[str]]:
    cell = tmp_path / "cell.yaml"
    cell.write_text(cell_text)
    capsys.readouterr()
    code = main(["plan", str(cell), "--out", str(tmp_path / "out")])
    return code, capsys.readouterr().err.strip().splitlines()


def with_cell_dir(text: str) -> str:
    return text.replace(": data/", f": {CELLS}/data/")


def test_process_io_on_a_path_cell_with_an_empty_job_switches_its_outputs(capsys, tmp_path):
    """A path: cell is a one-seam job, also with ``job:`` written but empty (without
    it: tests/test_pipeline.py): its process I/O is planned, not ignored: the output is
    on along the seam and off at home."""
    job = "job:\n"
    text = with_own_io((CELLS / "seal_plate_kr16.yaml").read_text(), IO)
    code, err = run(capsys, tmp_path, with_cell_dir(text.replace("motion:", job + "motion:", 1)))
    assert code == 0, err
    rows = np.genfromtxt(tmp_path / "out" / "trajectory.csv", delimiter=",", names=True)
    do = rows[[n for n in rows.dtype.names if n.startswith("do")][0]]
    assert do[0] == 0 and do[-1] == 0 and do.max() == 1


@pytest.mark.parametrize(
    ("flow", "key"),
    [
        ("per_mps: -40.0", "tool.process_io.flow.per_mps"),
        ("per_mps: 0.0", "tool.process_io.flow.per_mps"),
        ("per_mps: 40.0, lag_s: -0.05", "tool.process_io.flow.lag_s"),
    ],
)
def test_flow_numbers_are_checked(capsys, tmp_path, flow, key):
    text = (CELLS / "seal_job_kr16.yaml").read_text().replace("per_mps: 40.0", flow, 1)
    code, err = run(capsys, tmp_path, text)
    assert code == 2 and len(err) == 1 and f": {key}: " in err[0], err


@pytest.mark.parametrize(
    ("on_lead", "off_lead", "half_mm", "on_mm", "off_mm"),
    [
        (-100, 150, 120, 100.0, 90.0),  # the case: off before on on the stripe
        (5, 250, 120, -5.0, -10.0),  # off 250 mm before the 240 mm stripe's end
        (0, 2, 0.5, 0.0, -1.0),  # a 1 mm seam with a 2 mm off lead
    ],
)
def test_off_before_on_is_refused_naming_the_seam_and_both_positions(
    capsys, tmp_path, on_lead, off_lead, half_mm, on_mm, off_mm
):
    from export.test_job_io import stripe_cell

    text = stripe_cell(tmp_path, on_lead, off_lead).read_text()
    text = text.replace(
        "start: [-120, 80, 0], end: [120, 80, 0]",
        f"start: [{-half_mm}, 80, 0], end: [{half_mm}, 80, 0]",
    )
    code, err = run(capsys, tmp_path, text)
    assert code == 2 and len(err) == 1, err
    assert "tool.process_io" in err[0] and "seam stripe" in err[0]
    assert f"on at {on_mm:.1f} mm and off at {off_mm:.1f} mm" in err[0]
    assert not (tmp_path / "out").exists()


# --- the rule itself, on synthetic seams -----------------------------------------------


def one_seam(length_m: float, approach_m: float, retract_m: float, speed=0.1, dt=0.004):
    """JobSamples of link → approach → seam → retract → link at a constant speed, with
    path_m the signed position along the seam's path [m]."""
    pieces = [("link", np.zeros(3))]
    for kind, a, b in (
        ("approach", -approach_m, 0.0),
        ("process", 0.0, length_m),
        ("retract", length_m, length_m + retract_m),
    ):
        n = max(2, int(np.ceil((b - a) / (speed * dt))) + 1)
        pieces.append((kind, np.linspace(a, b, n)[:-1]))
    pieces.append(("link", np.full(3, np.nan)))
    path = np.concatenate([p for _, p in pieces])
    path[:3] = np.nan
    t = np.arange(len(path)) * dt
    segments, row = [], 0
    for kind, p in pieces:
        seam = "" if kind == "link" else "s"
        segments.append(Segment(kind, seam, row, row + len(p), row * dt, (row + len(p)) * dt))
        row += len(p)
    q = np.zeros((len(t), 6))
    return JobSamples(t, q, q, path, segments), np.where(np.isnan(path), 0.0, speed)


def io_config(on_lead_mm, off_lead_mm, lag_s=0.0) -> ProcessIoConfig:
    return ProcessIoConfig(
        on=DigitalSwitch(digital_output=1, lead_mm=on_lead_mm),
        off=DigitalSwitch(digital_output=1, lead_mm=off_lead_mm),
        flow=AnalogFlow(analog_output=1, per_mps=40.0, offset=0.5, lag_s=lag_s),
    )


def test_a_1_mm_seam_with_a_2_mm_off_lead_is_refused():
    """Off 1 mm before the seam's start: the seam would get no material."""
    samples, speed = one_seam(0.001, 0.05, 0.05)
    with pytest.raises(IoPlacementError, match=r"seam s: on at 0\.0 mm and off at -1\.0 mm"):
        io_columns(samples, io_config(0.0, 2.0), {"s": 0.001}, speed)
    with pytest.raises(IoPlacementError, match=r"never on while the seam"):
        io_columns(samples, io_config(5.0, 2.0), {"s": 0.001}, speed)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(
    length_mm=st.floats(1.0, 400.0),
    approach_mm=st.floats(0.0, 60.0),
    retract_mm=st.floats(0.0, 60.0),
    on_lead_mm=st.floats(-450.0, 100.0),
    off_lead_mm=st.floats(-100.0, 450.0),
)
def test_switch_positions_are_the_cells_or_refused(
    length_mm, approach_mm, retract_mm, on_lead_mm, off_lead_mm
):
    """The events sit where the cell's leads put them along the seam, the output is on
    exactly between them and the flow live only there; any other case is refused."""
    L, a, r = length_mm * 1e-3, approach_mm * 1e-3, retract_mm * 1e-3
    samples, speed = one_seam(L, a, r)
    on, off = -on_lead_mm * 1e-3, L - off_lead_mm * 1e-3  # the cell's numbers
    valid = -a - 1e-9 <= on < off <= L + r + 1e-9 and on < L and off > 0
    if not valid:
        with pytest.raises(IoPlacementError, match=r"seam s: on at .* and off at"):
            io_columns(samples, io_config(on_lead_mm, off_lead_mm), {"s": L}, speed)
        return
    io = io_columns(samples, io_config(on_lead_mm, off_lead_mm), {"s": L}, speed)
    digital = [e for e in io.events if e.signal is Signal.DIGITAL]
    assert [e.state for e in digital] == [True, False]
    assert [e.path_m for e in digital] == [pytest.approx(on), pytest.approx(off)]
    path = samples.path_m
    expected = (path >= on - 1e-9) & (path < off - 1e-9)
    row_step = 0.1 * 0.004  # one sample at 0.1 m/s: a position between two rows
    disagree = np.flatnonzero(io.digital.astype(bool) != expected)
    assert all(min(abs(path[i] - on), abs(path[i] - off)) <= row_step for i in disagree)
    assert np.array_equal(io.analog > 0.5 + 1e-9, io.digital.astype(bool))  # lag 0


def test_flow_without_switching_runs_on_the_seam_and_leads_by_the_lag():
    """No on/off: the flow is live while the seam runs; it goes live lag_s early, but
    is cut where the seam ends (a cut led by the lag would thin the seam's end)."""
    samples, speed = one_seam(0.1, 0.03, 0.03)
    lag = 0.02
    io = ProcessIoConfig(flow=AnalogFlow(analog_output=1, per_mps=40.0, offset=0.5, lag_s=lag))
    columns = io_columns(samples, io, {"s": 0.1}, speed)
    assert columns.digital is None and columns.switches == []
    live_t = samples.t[columns.analog > 0.5 + 1e-9]
    process = next(s for s in samples.segments if s.kind == "process")
    dt = np.diff(samples.t).max()
    assert live_t[0] == pytest.approx(process.t_start - lag, abs=dt)
    assert live_t[-1] == pytest.approx(process.t_stop, abs=dt)
    assert columns.analog.max() == pytest.approx(0.5 + 40.0 * 0.1)
    # The cut-off takes effect (a controller leading by the lag places it) lag_s past
    # the seam's end, so it is set as the seam ends.
    assert [(e.state, e.path_m) for e in columns.events] == [
        (True, 0.0),
        (False, pytest.approx(0.1 + 0.1 * lag)),
    ]
    assert columns.events[1].set_path_m == pytest.approx(0.1)


def test_a_lag_that_leads_before_the_approach_is_refused():
    """The on switch is 25 mm into the 30 mm approach: 0.25 s at 0.1 m/s to lead in."""
    samples, speed = one_seam(0.1, 0.03, 0.03)
    with pytest.raises(IoPlacementError, match=r"flow.lag_s: 0.5 s before seam s's output"):
        io_columns(samples, io_config(5.0, 2.0, lag_s=0.5), {"s": 0.1}, speed)
    io_columns(samples, io_config(5.0, 2.0, lag_s=0.2), {"s": 0.1}, speed)  # 20 of 25 mm


@pytest.mark.parametrize(
    ("io", "key"),
    [
        ("on: {digital_output: 0}", "tool.process_io.on.digital_output"),
        ("off: {digital_output: 0}", "tool.process_io.off.digital_output"),
        ("flow: {analog_output: 0, per_mps: 40.0}", "tool.process_io.flow.analog_output"),
    ],
)
def test_fanuc_ports_start_at_1(tmp_path, io, key):
    """FANUC's DO[n] and AO[n] count from 1: DO[0] or AO[0] in a program is refused by
    the controller, so the cell check refuses it (one line naming the key)."""
    from offline_prog.config.cell import load_cell
    from offline_prog.config.job_checks import check_process_io
    from offline_prog.errors import InputError

    text = with_own_io(
        (CELLS / "seal_plate_kr16.yaml").read_text(), f"tool:\n  process_io:\n    {io}\n"
    )
    file = tmp_path / "cell.yaml"
    file.write_text(text)
    cell = load_cell(file)
    with pytest.raises(InputError) as error:
        check_process_io(file, cell, "fanuc")
    assert error.value.key == key and "use 1..9999" in error.value.reason
    check_process_io(file, load_cell(file), "urscript")  # UR counts from 0


def test_every_controller_language_numbers_its_outputs():
    from offline_prog.config.job_checks import OUTPUT_RANGES
    from offline_prog.robot.model import LANGUAGES

    assert set(OUTPUT_RANGES) == set(LANGUAGES)


@pytest.mark.parametrize(
    ("unit", "key"),
    [
        ("ao_unit: amperes", "tool.process_io.flow.ao_unit"),
        ("ao_unit: counts", "tool.process_io.flow.counts_per_volt"),
        ("ao_unit: counts, counts_per_volt: 0", "tool.process_io.flow.counts_per_volt"),
        ("counts_per_volt: 3276.7", "tool.process_io.flow.counts_per_volt"),  # with volts
    ],
)
def test_the_ao_unit_is_checked(capsys, tmp_path, unit, key):
    """Issue 42: FANUC's AO unit is volts or counts with counts per volt, else one line."""
    text = (CELLS / "seal_job_kr16.yaml").read_text()
    text = text.replace("per_mps: 40.0", f"per_mps: 40.0, {unit}", 1)
    code, err = run(capsys, tmp_path, with_cell_dir(text))
    assert code == 2 and len(err) == 1 and f": {key}: " in err[0], err


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        ("lead_mm: 5}", "lead_mm: 5, delay_s: -0.02}", "tool.process_io.on.delay_s"),
        ("lead_mm: 2}", "lead_mm: 2, delay_s: -0.01}", "tool.process_io.off.delay_s"),
        ("    closed: true\n", "    closed: true\n    overlap_mm: -3\n", "seams[0].overlap_mm"),
        ("    closed: true\n", "    closed: false\n    overlap_mm: 5\n", "seams[0].overlap_mm"),
    ],
)
def test_bad_valve_delays_and_overlaps_are_refused(capsys, tmp_path, old, new, key):
    """A negative response time, a negative overlap, an overlap on an open seam: one
    line naming the key, exit 2, nothing written."""
    text = (CELLS / "seal_job_kr16.yaml").read_text()
    assert old in text
    code, err = run(capsys, tmp_path, with_cell_dir(text.replace(old, new, 1)))
    assert code == 2 and len(err) == 1 and f": {key}: " in err[0], err
    assert not (tmp_path / "out").exists()


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    on_delay=st.floats(0.0, 0.2),
    off_delay=st.floats(0.0, 0.2),
    lag=st.floats(0.0, 0.15),
)
def test_the_valve_opens_and_closes_at_the_leads_and_the_flow_is_cut_as_it_closes(
    on_delay, off_delay, lag
):
    """The output is set ``delay_s`` before the tool reaches the lead's position, so the
    valve (open ``delay_s`` after it is set) opens and closes there; the flow goes live
    ``lag_s`` before the valve opens and stays live until it closes."""
    samples, speed = one_seam(0.1, 0.04, 0.04)  # 0.1 m/s, a 40 mm approach: 0.4 s
    io = io_config(5.0, 2.0, lag_s=lag)
    io.on.delay_s, io.off.delay_s = on_delay, off_delay
    columns = io_columns(samples, io, {"s": 0.1}, speed)
    t, path = samples.t, samples.path_m
    rows = np.isfinite(path)
    t_open, t_close = np.interp([-0.005, 0.098], path[rows], t[rows])
    on, off = columns.switches
    assert (on.path_m, off.path_m) == (pytest.approx(-0.005), pytest.approx(0.098))
    assert on.t_s == pytest.approx(t_open - on_delay, abs=1e-9)
    assert off.t_s == pytest.approx(t_close - off_delay, abs=1e-9)
    assert on.set_path_m == pytest.approx(-0.005 - 0.1 * on_delay, abs=1e-6)
    dt = np.diff(t).max()
    open_t = t[columns.valve]
    assert open_t[0] == pytest.approx(t_open, abs=dt) and open_t[-1] == pytest.approx(
        t_close, abs=dt
    )
    live_t = t[columns.analog > 0.5 + 1e-9]
    assert live_t[0] == pytest.approx(t_open - lag, abs=dt)
    assert live_t[-1] == pytest.approx(t_close, abs=dt)  # the cut-off is not led


def test_an_on_delay_before_the_approach_is_refused():
    samples, speed = one_seam(0.1, 0.03, 0.03)  # the on switch 25 mm into 30 mm: 0.25 s
    io = io_config(5.0, 2.0)
    io.on.delay_s = 0.3
    with pytest.raises(IoPlacementError, match=r"on.delay_s: seam s: the output would be set"):
        io_columns(samples, io, {"s": 0.1}, speed)
