"""Joint-limit retiming: every joint limit holds, the process speed is lowered only
where the joints need it, and the motion keeps continuous acceleration."""

import numpy as np
import pytest

from offline_prog.timing.joint_timing import JointRates, limit_use, retime
from offline_prog.timing.time_law import sin2_time_law

QD_MAX = np.full(6, 2.0)
QDD_MAX = np.full(6, 5.0)


def rates_with_a_fast_stretch(length=1.0, peak=40.0):
    """q′ is 1 rad/m except near σ = 0.5 m, where joint 6 needs `peak` rad/m."""
    sigma = np.linspace(0, length, 4001)
    bump = np.exp(-(((sigma - 0.5) / 0.01) ** 2))
    dq = np.ones((len(sigma), 6))
    dq[:, 5] += (peak - 1.0) * bump
    ddq = np.zeros_like(dq)
    ddq[:, 5] = np.gradient(dq[:, 5], sigma)
    q = np.cumsum(dq, axis=0) * (sigma[1] - sigma[0])
    return JointRates(sigma, q, dq, ddq)


def test_slows_down_only_near_the_fast_stretch():
    rates = rates_with_a_fast_stretch()
    nominal = sin2_time_law(1.0, v_max=0.2, a_max=1.0, j_max=10.0)
    before = limit_use(rates, nominal, np.arange(0, nominal.duration, 1e-3), QD_MAX, QDD_MAX)
    assert max(before[1].max(), before[4].max()) > 1.0  # the nominal law breaks a limit
    result = retime(rates, nominal, qd_max=QD_MAX, qdd_max=QDD_MAX)
    assert result.feasible
    t = np.arange(0, result.law.duration, 1e-3)
    sigma, speed, _, _, accel = limit_use(rates, result.law, t, QD_MAX, QDD_MAX)
    assert speed.max() <= 1.0 + 1e-9 and accel.max() <= 1.0 + 1e-9
    # Lowered once, around σ = 0.5 m; full process speed elsewhere (away from ramps).
    assert len(result.reductions) >= 1
    for start, end, v in result.reductions:
        assert start > 0.35 and end < 0.65 and v < 0.2
    _, sd, sdd, sddd = result.law(t)
    far = (sigma > 0.1) & (sigma < 0.3) | (sigma > 0.7) & (sigma < 0.9)
    assert np.all(sd[far] >= 0.2 * (1 - 1e-9))
    # Continuous acceleration, bounded jerk.
    assert np.abs(np.diff(sdd)).max() <= 10.0 * 1e-3 * 1.01
    assert np.abs(sddd).max() <= 10.0 * (1 + 1e-9)


def test_no_change_when_the_joints_can_follow():
    rates = rates_with_a_fast_stretch(peak=1.0)
    nominal = sin2_time_law(1.0, v_max=0.2, a_max=1.0, j_max=10.0)
    result = retime(rates, nominal, qd_max=QD_MAX, qdd_max=QDD_MAX)
    assert result.feasible and result.reductions == () and result.a_scale == 1.0
    assert result.law.duration == pytest.approx(nominal.duration)


def test_ramps_are_softened_when_q_prime_times_acceleration_is_too_much():
    rates = rates_with_a_fast_stretch(peak=1.0)
    rates = JointRates(rates.sigma, rates.q, rates.dq * 8.0, rates.ddq)  # 8 rad/m everywhere
    nominal = sin2_time_law(1.0, v_max=0.2, a_max=1.0, j_max=10.0)  # q′σ̈ = 8 > 5 rad/s²
    result = retime(rates, nominal, qd_max=QD_MAX, qdd_max=QDD_MAX)
    assert result.feasible
    assert result.a_scale < 1.0 and result.reductions == ()  # speed held, ramps longer
