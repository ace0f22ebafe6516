"""Each process model along a planned speed profile against hand-worked cases.

Constant speed (the target exactly), a step in speed through the dispenser's exact
first-order response (y = u₂ − (u₂ − u₁)·e^{−t/τ}, here for a steep linear ramp of
length ε: the factor (τ/ε)(1 − e^{−ε/τ})), a linear slowdown that the lead cancels,
a heater at saturation, a weld slowed by a joint limit: values, the share within the
band by path length, the stretches outside and their causes.
"""

import numpy as np
import pytest

from offline_prog.config.process_keys import ProcessConfig
from offline_prog.io_events import IoEvent, ProcessIo, Signal
from offline_prog.job.assemble import Segment
from offline_prog.process.bead import BeadConfig
from offline_prog.process.heat_input import HeatInputConfig
from offline_prog.process.quality import process_quality
from offline_prog.process.registry import process_model
from offline_prog.process.tape_heating import PowerOutput, TapeHeatingConfig

DT = 1e-3  # [s] sample spacing of the synthetic profiles
BEAD = ProcessConfig(
    "bead", bead=BeadConfig(area_mm2=12.0, tolerance_pct=5, flow_mm3_s_per_unit=250.0, lag_s=0.08)
)
WELD = ProcessConfig(
    "heat_input",
    heat_input=HeatInputConfig(
        voltage_v=12.0, current_a=120.0, efficiency=0.6, target_kj_mm=[0.095, 0.125]
    ),
)
TAPE = ProcessConfig(
    "tape_heating",
    tape_heating=TapeHeatingConfig(
        width_mm=25.0,
        thickness_mm=0.2,
        density_kg_m3=1550,
        specific_heat_j_kg_k=1200,
        absorbed_fraction=0.6,
        ambient_c=20,
        target_c=[380, 420],
        max_power_w=3000,
        power_output=PowerOutput(analog_output=2, w_per_unit=300),
    ),
)


def settings_of(process: ProcessConfig) -> ProcessIo | None:
    model = process_model(process)
    fields = model.speed_output()
    if model.sets_flow:  # the flow output's number and limits are the cell's
        fields |= {"analog_output": 1, "min": 0.0, "max": 10.0}
    return ProcessIo(**fields) if fields else None


def quality(process, t, v, *, lead: bool = True):
    """The quality of one seam run at speeds v (N,) [m/s] at times t (N,) [s], the
    output live on the whole seam and leading by the lag (``lead``) as the plan sets it."""
    model, io = process_model(process), settings_of(process)
    path = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    segments = [Segment("process", "a", 0, len(t), t[0], t[-1])]
    command, events = None, []
    if io is not None:
        lag = io.lag_s if lead else 0.0
        command = io.flow(np.interp(t + lag, t, v))
        events = [  # live lag_s before the seam, cut as it ends (not led)
            IoEvent("a", Signal.ANALOG, 1, state, 0.0, at, time, at)
            for state, at, time in ((True, 0.0, t[0] - io.lag_s), (False, path[-1], t[-1] + DT))
        ]
    result = process_quality(
        model,
        t=t,
        v_tcp=v,
        path_m=path,
        segments=segments,
        command=command,
        digital=None,
        settings=io,
        events=events,
    )
    return result, path


@pytest.mark.parametrize(
    ("process", "speed", "expected"),
    [
        (BEAD, 0.1, 12.0),  # the flow follows the speed: A = A*
        (BEAD, 0.03, 12.0),
        (WELD, 0.008, 0.6 * 12 * 120 / 0.008 * 1e-6),  # 0.108 kJ/mm
        (TAPE, 0.15, 400.0),  # the heater's power follows the speed: the band's middle
    ],
)
def test_constant_speed_gives_the_hand_worked_value(process, speed, expected):
    t = np.arange(0.0, 2.0, DT)
    result, path = quality(process, t, np.full(len(t), speed))
    np.testing.assert_allclose(result.column, expected, rtol=1e-9)
    report = result.as_dict()
    assert report["min"] == pytest.approx(expected) and report["max"] == pytest.approx(expected)
    assert report["share_within_band"] == 1.0 and report["stretches_outside"] == []
    assert report["dispensed_length_m"] == pytest.approx(speed * t[-1])


def test_a_step_in_speed_follows_the_lags_exact_response():
    """The flow command steps with the speed (compensation off: no lead), from 0.1 to
    0.05 m/s over ε = 1 ms at t₀ = 1 s: the bead is thick until the dispenser's flow has
    decayed to within 5 % of its new value, τ·ln(20 c) after the step."""
    tau, eps, t0, v1, v2 = 0.08, DT, 1.0, 0.1, 0.05
    t = np.arange(0.0, 2.0 + DT / 2, DT)
    v = np.interp(t, [0.0, t0, t0 + eps, 3.0], [v1, v1, v2, v2])
    result, path = quality(BEAD, t, v, lead=False)
    c = tau / eps * (1.0 - np.exp(-eps / tau))  # the steep ramp's factor (→ 1 as ε → 0)
    after = t >= t0 + eps - 1e-9
    # y = u₂ + (u₁ − u₂)·c·e^{−(t − t₀ − ε)/τ}, u ∝ v: A/A* = y / u₂.
    ratio = 1.0 + (v1 - v2) / v2 * c * np.exp(-(t[after] - t0 - eps) / tau)
    np.testing.assert_allclose(result.column[after], 12.0 * ratio, rtol=1e-9)
    np.testing.assert_allclose(result.column[t < t0 - 1e-9], 12.0, rtol=1e-9)
    # Outside from the step until (A/A* − 1) = 5 %: τ·ln((v₁ − v₂)/v₂ · c / 0.05) later.
    t_back = t0 + eps + tau * np.log((v1 - v2) / v2 * c / 0.05)
    report = result.as_dict()
    (stretch,) = report["stretches_outside"]
    assert stretch["t_start_s"] == pytest.approx(t0, abs=1.5 * DT)
    assert stretch["t_end_s"] == pytest.approx(t_back, abs=1.5 * DT)
    assert stretch["cause"] == "lag"
    assert stretch["worst"] == pytest.approx(12.0 * (1.0 + (v1 - v2) / v2 * c), rel=1e-3)
    outside_m = v1 * eps / 2 + v2 * eps / 2 + v2 * (t_back - t0 - eps)
    # Rows weigh half of each neighbouring interval: each edge within one sample's length.
    edges = 2 * v1 * DT / path[-1]
    assert report["share_within_band"] == pytest.approx(1 - outside_m / path[-1], abs=edges)
    assert report["share_within_band_uncompensated"] == report["share_within_band"]


def test_the_lead_cancels_the_lag_on_a_linear_slowdown():
    """A linear slowdown from 0.1 to 0.05 m/s over 1 s (a = −0.05 m/s²). With the lead
    the bead keeps A* up to the decaying kink terms a·τ·e^{−(t − t₀ + τ)/τ} / v (−1.5 %
    at t₀) and |a|·τ/e / v₂ at the slowdown's end (+2.9 %): all within ±5 %. Without
    it, the flow lags: A/A* − 1 = |a|·τ·(1 − e^{−(t − t₀)/τ}) / v, up to +8 %."""
    tau, t0, t1, v1, v2 = 0.08, 1.0, 2.0, 0.1, 0.05
    a = (v2 - v1) / (t1 - t0)
    t = np.arange(0.0, 4.0 + DT / 2, DT)
    v = np.interp(t, [0.0, t0, t1, 5.0], [v1, v1, v2, v2])
    result, path = quality(BEAD, t, v)
    on_ramp = (t >= t0) & (t <= t1 - tau)
    expected = 12.0 * (1.0 + a * tau * np.exp(-(t[on_ramp] - t0 + tau) / tau) / v[on_ramp])
    np.testing.assert_allclose(result.column[on_ramp], expected, rtol=1e-9)
    report = result.as_dict()
    assert report["share_within_band"] == 1.0
    # Without the lead, hand-worked on the samples: y lags the command by the ramp's
    # exact first-order response, then decays back after the ramp's end.
    lagged = np.where(
        t < t0,
        0.0,
        np.where(
            t <= t1,
            -a * tau * (1 - np.exp(-(t - t0) / tau)),
            -a * tau * (1 - np.exp(-(t1 - t0) / tau)) * np.exp(-(t - t1) / tau),
        ),
    )
    outside = lagged / v > 0.05
    w = np.gradient(path)
    hand = 1.0 - (w * outside).sum() / w.sum()
    edges = 2 * v1 * DT / path[-1]
    assert report["share_within_band_uncompensated"] == pytest.approx(hand, abs=edges)
    assert report["share_within_band_uncompensated"] < 0.95


def test_a_heater_at_saturation():
    """At 0.6 m/s the heater would need ρcwh·v·(T* − T₀)/η = 3534 W: it gives its 3 kW,
    and the tape reaches T₀ + η·P_max/(ρcwh·v) = 342.6 °C, below the band."""
    capacity = 1550 * 1200 * 0.025 * 0.0002
    t = np.arange(0.0, 1.0, DT)
    v = np.full(len(t), 0.6)
    result, _ = quality(TAPE, t, v)
    expected = 20 + 0.6 * 3000 / (capacity * 0.6)
    np.testing.assert_allclose(result.column, expected, rtol=1e-9)
    report = result.as_dict()
    assert report["share_within_band"] == 0.0
    (stretch,) = report["stretches_outside"]
    assert stretch["cause"] == "output saturated"
    assert stretch["worst"] == pytest.approx(expected)


def test_a_weld_slowed_in_its_middle():
    """8 mm/s, slowed linearly to 6 mm/s and back (a joint at its limit): H = kUI/v
    leaves the band above 0.125 kJ/mm, i.e. below v = 6.912 mm/s."""
    t = np.arange(0.0, 30.0 + DT / 2, DT)
    v = np.interp(t, [0, 10, 12, 18, 20, 30], [0.008, 0.008, 0.006, 0.006, 0.008, 0.008])
    result, path = quality(WELD, t, v)
    arc = 0.6 * 12 * 120
    v_edge = arc / 0.125e6
    report = result.as_dict()
    (stretch,) = report["stretches_outside"]
    assert stretch["cause"] == "slowdown"
    t_in = 10 + 2 * (0.008 - v_edge) / 0.002
    assert stretch["t_start_s"] == pytest.approx(t_in, abs=DT)
    assert stretch["t_end_s"] == pytest.approx(30 - t_in, abs=DT)
    assert stretch["sigma_start_m"] == pytest.approx(np.interp(t_in, t, path), abs=0.008 * DT)
    assert stretch["worst"] == pytest.approx(arc / 0.006 * 1e-6)
    assert report["max"] == pytest.approx(arc / 0.006 * 1e-6)
    outside_m = np.interp(30 - t_in, t, path) - np.interp(t_in, t, path)
    assert report["share_within_band"] == pytest.approx(1 - outside_m / path[-1], abs=1e-4)
    assert "share_within_band_uncompensated" not in report


def test_a_seam_from_rest_names_its_ramps():
    """The bead on a seam timed from rest (a sin² ramp up and down): the stretches
    outside lie at its ends (within the ramp and the lag's 3 τ settling after it),
    named start ramp / end ramp or standstill."""
    t = np.arange(0.0, 3.0 + DT / 2, DT)
    ramp = np.clip(np.minimum(t, 3.0 - t) / 0.3, 0, 1)
    v = 0.1 * np.sin(0.5 * np.pi * ramp) ** 2
    result, path = quality(BEAD, t, v)
    report = result.as_dict()
    causes = {s["cause"] for s in report["stretches_outside"]}
    assert causes <= {"standstill", "start ramp", "end ramp"}, causes
    for s in report["stretches_outside"]:
        assert s["t_end_s"] <= 0.3 + 3 * 0.08 or s["t_start_s"] >= 2.7 - 3 * 0.08, s
    assert report["share_within_band"] >= report["share_within_band_uncompensated"]


def test_two_seams_and_the_gun_switched_off_early():
    """Two seams (a link between them, where nothing counts); on the second the weld's
    torch goes off at 80 % of its length: nothing is dispensed there (empty column),
    and the job's share is the dispensed-length-weighted mean of the seams'."""
    t = np.arange(0.0, 9.0 + DT / 2, DT)
    v = np.where((t > 4.0) & (t < 5.0), 0.05, 0.008)  # the link moves fast
    v = np.where((t > 1.0) & (t < 2.0), 0.006, v)  # a slowdown on the first seam
    path = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    link = np.flatnonzero((t >= 4.0) & (t < 5.0))
    path[link] = np.nan
    second = np.flatnonzero(t >= 5.0)
    path[second] -= path[second[0]]
    segments = [
        Segment("process", "a", 0, link[0], t[0], t[link[0]]),
        Segment("link", "", link[0], second[0], t[link[0]], t[second[0]]),
        Segment("process", "b", second[0], len(t), t[second[0]], t[-1]),
    ]
    digital = np.ones(len(t), np.int8)
    digital[t >= 5.0 + 0.8 * 4.0] = 0
    result = process_quality(
        process_model(WELD),
        t=t,
        v_tcp=v,
        path_m=path,
        segments=segments,
        command=None,
        digital=digital,
        settings=None,
        events=[],
    )
    assert np.all(np.isnan(result.column[link]))
    assert np.all(np.isnan(result.column[digital == 0]))
    report = result.as_dict()
    a, b = report["seams"]["a"], report["seams"]["b"]
    assert b["dispensed_length_m"] == pytest.approx(0.8 * b["process_length_m"], abs=0.008 * DT)
    assert b["share_within_band"] == 1.0 and a["n_stretches_outside"] == 1
    assert a["share_within_band"] == pytest.approx(1 - 0.006 / (3 * 0.008 + 0.006), abs=1e-3)
    lengths = np.array([a["dispensed_length_m"], b["dispensed_length_m"]])
    shares = np.array([a["share_within_band"], b["share_within_band"]])
    assert report["share_within_band"] == pytest.approx((lengths * shares).sum() / lengths.sum())
    (stretch,) = report["stretches_outside"]
    assert stretch["seam"] == "a" and stretch["cause"] == "slowdown"


def test_the_part_gets_the_arc_on_the_approach_and_retract_where_it_is_on():
    """A torch switched on 10 mm before the seam's start and off 10 mm after its end:
    the gun-on rows of the approach and retract carry the predicted heat input and count
    in the dispensed length, the seam's own length stays the process length, and the
    rows where the gun is off (and links) stay NaN."""
    model = process_model(WELD)
    v = 0.008
    t = np.arange(0.0, 15.0 + DT / 2, DT)  # 5 s approach, 5 s seam, 5 s retract
    path = v * t - 0.04  # −40 mm .. 80 mm: the seam runs over [0, 40] mm
    kinds = [("approach", 0, 5000), ("process", 5000, 10000), ("retract", 10000, len(t))]
    segments = [Segment(k, "a", a, b, t[a], t[min(b, len(t) - 1)]) for k, a, b in kinds]
    digital = ((path >= -0.01) & (path < 0.05)).astype(float)
    result = process_quality(
        model,
        t=t,
        v_tcp=np.full(len(t), v),
        path_m=path,
        segments=segments,
        command=None,
        digital=digital,
        settings=None,
        events=[],
    )
    expected = 0.6 * 12 * 120 / v  # J/m
    on = digital > 0
    np.testing.assert_allclose(result.values[on], expected, rtol=1e-9)
    assert np.isnan(result.values[~on]).all()
    assert np.isfinite(result.values[:5000]).sum() == on[:5000].sum() > 1200  # 10 mm
    summary = result.seams["a"]
    assert summary.dispensed_length_m == pytest.approx(0.06, abs=2 * v * DT)
    assert summary.process_length_m == pytest.approx(0.04, abs=2 * v * DT)
    assert summary.share_within_band == pytest.approx(1.0)
