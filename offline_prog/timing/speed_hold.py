"""How much of the path a time law holds the process speed where it can be held.

Where the process speed v is feasible: off the start and stop ramps (those of the
nominal sin² law at the path's a_max, j_max) and where the joints allow v at steady
speed (``jerk_stage.static_limit``: |q′v| ≤ q̇max, |q″v²| ≤ q̈max, |q‴v³| ≤ q⃛max).
Held: the law's σ̇ within ±HOLD of v (issue 14's acceptance: ≥ 90 % of the feasible
length, ``motion.process: constant_speed``).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import maximum_filter1d

from offline_prog.constants import LIMIT_CHECK_RATE_HZ
from offline_prog.timing.jerk_stage import static_limit
from offline_prog.timing.joint_timing import JointRates
from offline_prog.timing.limit_use import with_jerk
from offline_prog.timing.time_law import sin2_time_law

HOLD = 0.005  # ±0.5 % of the process speed
RAMP_SAMPLES = 20001  # time samples of the nominal law that find its ramps
BOUND_SPACING_M = 2.5e-4  # grid of upper_bound [m]


class SpeedHold:
    """The feasible set of a path, once; :meth:`__call__` measures a law on it.

    Args:
        rates: q, q′, q″ on a σ grid over [0, length] (controller axes).
        v_process [m/s], a_max [m/s²], j_max [m/s³]: the process limits.
        limits: (qd_max, qdd_max, qddd_max), each (6,).
    """

    def __init__(self, rates: JointRates, *, v_process: float, a_max: float, j_max: float, limits):
        self.v, self.length = v_process, float(rates.sigma[-1])
        self.sigma, self.steady = rates.sigma, static_limit(rates, with_jerk(rates), limits)
        nominal = sin2_time_law(self.length, v_max=v_process, a_max=a_max, j_max=j_max)
        ramp_sigma, ramp_speed = nominal(np.linspace(0.0, nominal.duration, RAMP_SAMPLES))[:2]
        cruise = ramp_sigma[ramp_speed >= (1.0 - HOLD) * v_process]
        self.cruise = (cruise[0], cruise[-1]) if len(cruise) else None

    def __call__(self, law) -> tuple[float, float]:
        """:meth:`on_samples` of ``law`` (``law(t)`` → σ, σ̇, ...) at
        LIMIT_CHECK_RATE_HZ."""
        sigma, speed = law(np.arange(0.0, law.duration, 1.0 / LIMIT_CHECK_RATE_HZ))[:2]
        return self.on_samples(sigma, speed)

    def upper_bound(self, sigma: np.ndarray, speed: np.ndarray, reach: float) -> float:
        """The most of the feasible length a law can hold whose speed at each σ is an
        average of ``speed`` within ``reach`` of it (the averaged profile's): where the
        highest speed within reach is below the hold band, no average reaches it.

        Args:
            sigma: (G,) increasing grid [m]; speed: (G,) a profile on it [m/s].
            reach: how far along the path the average looks each way [m].
        """
        grid = np.arange(0.0, self.length + BOUND_SPACING_M, BOUND_SPACING_M)
        grid[-1] = min(grid[-1], self.length)
        size = 2 * int(np.ceil(reach / BOUND_SPACING_M)) + 1
        highest = maximum_filter1d(np.interp(grid, sigma, speed), size, mode="nearest")
        return self.on_samples(grid, np.minimum(highest, self.v))[0]

    def on_samples(self, sigma: np.ndarray, speed: np.ndarray) -> tuple[float, float]:
        """(share of the feasible length where the speed holds the process speed within
        ±HOLD, share of the path where the process speed is feasible).

        Args:
            sigma: (N,) the law's position along the path [m], in time order.
            speed: (N,) the speed there [m/s].
        """
        if self.cruise is None:  # a path too short to reach the process speed
            return float("nan"), 0.0
        v = self.v
        feasible = (
            (sigma >= self.cruise[0])
            & (sigma <= self.cruise[1])
            & (np.interp(sigma, self.sigma, self.steady) >= v)
        )
        held = feasible & (np.abs(speed - v) <= HOLD * v)
        ds = np.abs(np.diff(sigma))
        room = float(np.sum(ds * (feasible[1:] & feasible[:-1])))
        kept = float(np.sum(ds * (held[1:] & held[:-1])))
        return (kept / room if room > 0 else float("nan")), room / self.length
