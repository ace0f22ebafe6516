"""How much of the path a time law holds the process speed where it can be held.

Where the process speed v is feasible: off the start and stop ramps (those of the
nominal sin² law at the path's a_max, j_max) and where the joints allow v at steady
speed (``jerk_stage.static_limit``: |q′v| ≤ q̇max, |q″v²| ≤ q̈max, |q‴v³| ≤ q⃛max).
Held: the law's σ̇ within ±HOLD of v (issue 14's acceptance: ≥ 90 % of the feasible
length, ``motion.process: constant_speed``).
"""

from __future__ import annotations

import numpy as np

from offline_prog.constants import LIMIT_CHECK_RATE_HZ
from offline_prog.timing.jerk_stage import static_limit
from offline_prog.timing.joint_timing import JointRates
from offline_prog.timing.limit_use import with_jerk
from offline_prog.timing.time_law import sin2_time_law

HOLD = 0.005  # ±0.5 % of the process speed
RAMP_SAMPLES = 20001  # time samples of the nominal law that find its ramps


def speed_held(
    rates: JointRates, law, *, v_process: float, a_max: float, j_max: float, limits
) -> tuple[float, float]:
    """(share of the feasible length where ``law`` holds v_process within ±HOLD,
    share of the path where v_process is feasible).

    Args:
        rates: q, q′, q″ on a σ grid over [0, length] (controller axes).
        law: a time law σ(t) (``law(t)`` → σ, σ̇, ...; ``law.duration``).
        v_process [m/s], a_max [m/s²], j_max [m/s³]: the process limits.
        limits: (qd_max, qdd_max, qddd_max), each (6,).
    """
    length = float(rates.sigma[-1])
    steady = static_limit(rates, with_jerk(rates), limits)  # (G,) [m/s]
    nominal = sin2_time_law(length, v_max=v_process, a_max=a_max, j_max=j_max)
    ramp_sigma, ramp_speed = nominal(np.linspace(0.0, nominal.duration, RAMP_SAMPLES))[:2]
    cruise = ramp_sigma[ramp_speed >= (1.0 - HOLD) * v_process]
    if not len(cruise):  # a path too short to reach the process speed
        return float("nan"), 0.0
    sigma, speed = law(np.arange(0.0, law.duration, 1.0 / LIMIT_CHECK_RATE_HZ))[:2]
    feasible = (
        (sigma >= cruise[0]) & (sigma <= cruise[-1])
        & (np.interp(sigma, rates.sigma, steady) >= v_process)
    )  # fmt: skip
    held = feasible & (np.abs(speed - v_process) <= HOLD * v_process)
    ds = np.diff(sigma)
    room = float(np.sum(ds * (feasible[1:] & feasible[:-1])))
    kept = float(np.sum(ds * (held[1:] & held[:-1])))
    return (kept / room if room > 0 else float("nan")), room / length
