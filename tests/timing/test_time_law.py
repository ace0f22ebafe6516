"""sin² jerk time law (paper §4): limits, rest-to-rest, continuity."""

import numpy as np
import pytest

from offline_prog.timing.time_law import sin2_plateau_law, sin2_time_law

CASES = [  # length, v, a, j: long cruise, no constant-acceleration phase, short path
    (1.0, 0.1, 1.0, 10.0),
    (2.0, 0.5, 2.0, 5.0),
    (0.01, 0.2, 1.0, 10.0),
    (1e-4, 0.1, 0.5, 5.0),
]


@pytest.mark.parametrize(("length", "v", "a", "j"), CASES)
def test_limits_rest_to_rest_and_continuity(length, v, a, j):
    law = sin2_time_law(length, v_max=v, a_max=a, j_max=j)
    t = np.linspace(0.0, law.duration, 200001)
    s, sd, sdd, sddd = law(t)
    eps = 1e-9
    assert s[0] == 0.0 and s[-1] == length
    assert sd[0] == 0 and sd[-1] == 0 and sdd[0] == 0 and sdd[-1] == 0
    assert np.all(np.diff(s) >= -1e-15)  # never goes back
    assert sd.max() <= v * (1 + eps)
    assert np.abs(sdd).max() <= a * (1 + eps)
    assert np.abs(sddd).max() <= j * (1 + eps)
    # Continuous jerk: the step between neighbours shrinks with the sample step.
    dt = t[1] - t[0]
    assert (
        np.abs(np.diff(sddd)).max()
        <= j * np.pi * dt / law.durations[law.durations > 0].min() * 1.01 + 1e-12
    )
    # Each derivative is the time derivative of the one before.
    for f, df in ((s, sd), (sd, sdd), (sdd, sddd)):
        scale = max(np.abs(df).max(), 1e-12)
        assert np.abs(np.gradient(f, dt)[1:-1] - df[1:-1]).max() <= 1e-4 * scale


def test_long_path_reaches_speed_and_short_path_falls_back():
    long = sin2_time_law(1.0, v_max=0.1, a_max=1.0, j_max=10.0)
    assert long.v_peak == 0.1 and not long.reduced
    short = sin2_time_law(0.001, v_max=0.1, a_max=1.0, j_max=10.0)
    assert short.reduced and short.v_peak < 0.1
    assert short(np.array([short.duration / 2]))[1][0] == pytest.approx(short.v_peak)


def test_cruise_duration_matches_distance():
    law = sin2_time_law(1.0, v_max=0.1, a_max=1.0, j_max=10.0)
    # Accelerating to 0.1 m/s takes T_j = 2·sqrt(0.1/(2·10))… well below a_max.
    t_j = np.sqrt(2 * 0.1 / 10.0)
    assert law.durations[0] == pytest.approx(t_j)
    assert law.duration == pytest.approx(1.0 / 0.1 + 2 * t_j)


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf")])
def test_rejects_bad_limits(bad):
    with pytest.raises(ValueError, match="positive"):
        sin2_time_law(1.0, v_max=bad, a_max=1.0, j_max=1.0)


PLATEAU_CASES = [
    [(0.1, 0.0, 0.4), (0.04, 0.4, 0.5), (0.1, 0.5, 1.0)],  # one slow stretch
    [
        (0.1, 0.0, 0.3),
        (0.02, 0.3, 0.31),
        (0.1, 0.31, 0.33),
        (0.05, 0.33, 0.6),
        (0.1, 0.6, 1.0),
    ],  # a gap too short to speed up in between
    [(0.03, 0.0, 0.05), (0.1, 0.05, 1.0)],  # capped right at the start
    [(0.1, 0.0, 0.99), (0.01, 0.99, 1.0)],  # capped right at the end
]


@pytest.mark.parametrize("caps", PLATEAU_CASES)
def test_plateau_law_respects_every_cap(caps):
    law = sin2_plateau_law(1.0, caps, a_max=1.0, j_max=10.0, v_max=0.1)
    t = np.linspace(0.0, law.duration, 100001)
    s, sd, sdd, sddd = law(t)
    assert s[-1] == 1.0 and sd[-1] == 0.0 and sd[0] == 0.0
    assert np.all(np.diff(s) >= -1e-15)
    assert np.abs(sdd).max() <= 1.0 * (1 + 1e-9)
    assert np.abs(sddd).max() <= 10.0 * (1 + 1e-9)
    for v, start, end in caps:
        inside = (s >= start) & (s <= end)
        assert sd[inside].max() <= v * (1 + 1e-9)
    # Continuous velocity and acceleration (no steps beyond what one sample allows).
    dt = t[1] - t[0]
    assert np.abs(np.diff(sd)).max() <= 1.0 * dt * 1.01
    assert np.abs(np.diff(sdd)).max() <= 10.0 * dt * 1.01
    # It does reach the process speed somewhere when there is room.
    assert law.v_peak == pytest.approx(0.1)


def test_plateau_law_slows_only_where_needed():
    caps = [(0.1, 0.0, 0.45), (0.05, 0.45, 0.55), (0.1, 0.55, 1.0)]
    law = sin2_plateau_law(1.0, caps, a_max=1.0, j_max=10.0)
    t = np.linspace(0.0, law.duration, 100001)
    s, sd, _, _ = law(t)
    # Full speed up to shortly before the slow stretch and again shortly after.
    at_full = sd >= 0.1 * (1 - 1e-9)
    assert at_full[(s > 0.05) & (s < 0.4)].all()
    assert at_full[(s > 0.6) & (s < 0.95)].all()
    assert [round(v, 9) for v, _, _ in law.plateaus] == [0.1, 0.05, 0.1]
