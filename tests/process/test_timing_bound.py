"""The process model's bound on the time law (process.timing_bound): the jerk cap a
lagging dispenser can follow, checked against the exact first-order response, and that
it only ever lowers the user's caps."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from offline_prog.process.bead import BeadModel
from offline_prog.process.heat_input import HeatInputModel
from offline_prog.process.tape_heating import TapeHeatingModel
from offline_prog.process.timing_bound import process_caps
from offline_prog.timing.time_law import sin2_time_law

RATE_HZ = 2000.0  # samples of the speed profiles below


def bead(tolerance=0.05, lag_s=0.08) -> BeadModel:
    return BeadModel(12e-6, tolerance, 250e-9, lag_s)


def bead_error(model: BeadModel, t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(N,) relative bead error A/A* − 1 with the command leading the speed by τ (as
    job.process_io sets it: u(t) = A*/k · v(t + τ)), through the exact lag."""
    command = model.per_mps * np.interp(t + model.lag_s, t, v)
    return model.predict(t, v, command) / model.area_m2 - 1.0


def cruise(law, t):
    """The rows after the law's first ramp and before its last (speed at its top)."""
    v = law(t)[1]
    return v >= law.v_peak * (1 - 1e-9)


@settings(max_examples=200, deadline=None, derandomize=True)
@given(
    tolerance=st.floats(0.005, 0.5),
    lag_s=st.floats(0.0, 1.0),
    v=st.floats(1e-3, 2.0),
    a_max=st.floats(0.01, 50.0),
    j_max=st.floats(0.01, 1000.0),
)
def test_caps_only_lower_the_users(tolerance, lag_s, v, a_max, j_max):
    """Whatever the model, the caps are the user's or lower, and lowered only with a
    reason; a model without dynamics (heat input, tape) keeps the user's."""
    caps = process_caps(bead(tolerance, lag_s), v_process=v, a_max=a_max, j_max=j_max)
    assert caps.j_max == min(j_max, 2.0 * tolerance * v / lag_s**2 if lag_s**2 > 0 else math.inf)
    for model in (
        bead(tolerance, lag_s),
        HeatInputModel(3456.0, (0.5e6, 0.7e6)),
        TapeHeatingModel(9.3, 0.6, 20.0, (380.0, 420.0), 3000.0, 300.0),
        None,
    ):
        caps = process_caps(model, v_process=v, a_max=a_max, j_max=j_max)
        assert caps.a_max <= a_max and caps.j_max <= j_max
        assert (caps.user_a_max, caps.user_j_max) == (a_max, j_max)
        assert caps.bounded == (caps.reason is not None)
        if model is None or model.output_lag_s == 0.0:  # no lag to lead: nothing asked
            assert not caps.bounded
    assert math.isinf(bead(tolerance, 0.0).jerk_cap(v)[0])


def test_jerk_cap_is_the_exact_worst_case():
    """A speed whose jerk is held at J long enough (a long ramp of constant jerk) gives
    the bead the steady relative error τ²J/(2v) through the exact lag; at the cap J =
    2·tol·v/τ² that is the tolerance itself (the bound is tight)."""
    model = bead(0.05, 0.08)
    jerk, t = 0.5, np.arange(0.0, 3.0, 1.0 / RATE_HZ)
    v = 0.1 + 0.5 * jerk * t**2  # v'' = J throughout
    error = bead_error(model, t, v)
    steady = (t > 1.0) & (t < 2.0)  # the lag's transient gone; the lead within the data
    expected = model.lag_s**2 * jerk / (2 * v[steady])
    np.testing.assert_allclose(error[steady], expected, rtol=1e-3)
    cap = model.jerk_cap(0.1)[0]
    assert abs(model.lag_s**2 * cap / (2 * 0.1) - model.tolerance) < 1e-12


@settings(max_examples=40, deadline=None, derandomize=True)
@given(
    tolerance=st.floats(0.01, 0.2),
    lag_s=st.floats(0.01, 0.2),
    v=st.floats(0.02, 0.5),
    jerk_share=st.floats(0.05, 1.0),
    length=st.floats(0.3, 2.0),
)
def test_a_law_within_the_cap_holds_the_bead_at_its_top_speed(
    tolerance, lag_s, v, jerk_share, length
):
    """A sin² law whose jerk is within the cap (and any acceleration: the lead cancels
    it) lays a bead within tolerance wherever it runs at its top speed, measured by the
    model's exact lag (test_jerk_cap_is_the_exact_worst_case: no higher cap would)."""
    model = bead(tolerance, lag_s)
    cap = model.jerk_cap(v)[0]
    law = sin2_time_law(length, v_max=v, a_max=1e3, j_max=jerk_share * cap)
    t = np.arange(0.0, law.duration, 1.0 / RATE_HZ)
    error = bead_error(model, t, law(t)[1])
    top = cruise(law, t)
    assert np.abs(error[top]).max() <= tolerance * (1 + 1e-6)
