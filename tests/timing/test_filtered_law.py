"""The time-averaged profile law: rest to rest, exact derivatives, continuous
acceleration, jerk bounded by the profile's acceleration change over the window."""

import numpy as np
import pytest

from offline_prog.timing.filtered_law import FilteredTimeLaw


def trapezoid(length=1.0, v=0.2, a=1.0, n=2001):
    """(σ (n,), σ̇ (n,)): a rest-to-rest speed profile with constant σ̈ = ±a ramps."""
    sigma = np.linspace(0.0, length, n)
    return sigma, np.minimum.reduce(
        [np.sqrt(2 * a * sigma), np.sqrt(2 * a * (length - sigma)), np.full(n, v)]
    )


@pytest.mark.parametrize("window", [0.05, 0.2, 0.5])
def test_rest_to_rest_exact_derivatives_and_bounded_jerk(window):
    rng = np.random.default_rng(0)
    sigma, speed = trapezoid()
    speed[1:-1] *= 1.0 - 0.3 * rng.random(len(speed) - 2)  # rough: σ̈ jumps everywhere
    law = FilteredTimeLaw(1.0, 0.2, 1.0, 10.0, sigma, speed, window)
    t = np.linspace(0.0, law.duration, 400001)
    s, sd, sdd, sddd = law(t)
    assert s[0] == 0.0 and s[-1] == 1.0
    assert abs(sd[0]) < 1e-12 and sd[-1] == 0.0 and abs(sdd[0]) < 1e-9 and sdd[-1] == 0.0
    assert np.all(np.diff(s) >= -1e-12)
    assert sd.max() <= speed.max() * (1 + 1e-12)
    a_profile = np.abs(law.profile_acceleration()).max()
    assert np.abs(sdd).max() <= a_profile * (1 + 1e-9)
    assert np.abs(sddd).max() <= 2 * a_profile / window * (1 + 1e-9)
    dt = t[1] - t[0]
    # Continuous acceleration: its step between samples shrinks with the sample step.
    assert np.abs(np.diff(sdd)).max() <= np.abs(sddd).max() * dt * 1.01
    # Each derivative is the time derivative of the one before (a central difference
    # is off by at most the next derivative's bound times the step).
    for f, df, bound in ((s, sd, np.abs(sdd).max()), (sd, sdd, np.abs(sddd).max())):
        assert np.abs(np.gradient(f, dt)[1:-1] - df[1:-1]).max() <= bound * dt


def test_a_trapezoid_becomes_the_constant_jerk_s_curve():
    """On a trapezoidal speed with window a/j the law reaches v with jerk exactly j,
    runs the window longer than the profile and holds v exactly on the cruise."""
    sigma, speed = trapezoid(n=20001)
    law = FilteredTimeLaw(1.0, 0.2, 1.0, 10.0, sigma, speed, 0.1)
    assert law.duration == pytest.approx(law.profile_duration + 0.1)
    t = np.linspace(0.0, law.duration, 200001)
    _, sd, _, sddd = law(t)
    assert np.abs(sddd).max() == pytest.approx(10.0, rel=1e-3)
    cruise = (t > 0.4) & (t < law.duration - 0.4)
    assert np.abs(sd[cruise] - 0.2).max() < 1e-12


def test_window_must_be_positive():
    sigma, speed = trapezoid()
    with pytest.raises(ValueError, match="window"):
        FilteredTimeLaw(1.0, 0.2, 1.0, 10.0, sigma, speed, 0.0)
