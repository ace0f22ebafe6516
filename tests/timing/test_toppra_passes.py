"""TOPP-RA's lean passes (timing.toppra_passes) give toppra's own profile bit for bit:
whole paths rest to rest, local spans between given speeds, with the speed and
acceleration curves, and the failures (an end speed no profile reaches) with the same
return code and failure point; seeded random paths."""

import numpy as np
import pytest
from test_time_optimal import QD_MAX, QDD_MAX, bump_rates

import offline_prog.timing.time_optimal as time_optimal
from offline_prog.timing.time_optimal import topp_profile


def both(rates, monkeypatch, **kwargs):
    """(toppra's profile, the lean passes' profile) of one problem."""
    lean = topp_profile(rates, **kwargs)
    with monkeypatch.context() as patch:
        patch.setattr(time_optimal, "lean_toppra", lambda algorithm: algorithm.TOPPRA)
        reference = topp_profile(rates, **kwargs)
    return reference, lean


def assert_same(reference, lean):
    assert lean.ok == reference.ok
    assert lean.reason == reference.reason
    np.testing.assert_array_equal(lean.sigma, reference.sigma)
    np.testing.assert_array_equal(lean.speed, reference.speed)
    assert lean.duration == reference.duration
    assert lean.failed_at_m == pytest.approx(reference.failed_at_m, nan_ok=True, abs=0)


@pytest.mark.parametrize("seed", range(4))
def test_lean_passes_equal_toppras(seed, monkeypatch):
    rng = np.random.default_rng(seed)
    rates = bump_rates(gain=rng.uniform(0.5, 8.0), joint=int(rng.integers(6)))
    common = dict(qd_max=QD_MAX, qdd_max=QDD_MAX, v_cap=rng.uniform(0.2, 1.0), a_path=2.0)
    curve = np.full(len(rates.sigma), common["v_cap"])
    curve[(rates.sigma > 0.3) & (rates.sigma < 0.4)] *= rng.uniform(0.2, 0.9)
    a_curve = np.full(len(rates.sigma), 2.0)
    a_curve[rates.sigma > 0.6] = rng.uniform(0.1, 2.0)
    whole = both(rates, monkeypatch, **common)
    curves = both(rates, monkeypatch, v_steady=curve, a_curve=a_curve, **common)
    for reference, lean in (whole, curves):
        assert reference.ok
        assert_same(reference, lean)
    # A local span between the whole profile's speeds, and one from a speed too high
    # to stop from (TOPP-RA's failure: uncontrollable).
    speed = curves[0].speed
    for span, ends in (((40, 120), (speed[40], speed[120])), ((40, 60), (speed[40], 50.0))):
        reference, lean = both(rates, monkeypatch, v_steady=curve, span=span, ends=ends, **common)
        assert_same(reference, lean)
    assert not reference.ok
