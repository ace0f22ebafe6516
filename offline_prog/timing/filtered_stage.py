"""Jerk stage for ``motion.process: cycle_time``: TOPP-RA's profile averaged in time.

The staircase of sin² plateaus (``jerk_stage``) brings the acceleration back to zero
between its 2 % steps, so it follows TOPP-RA's slopes slowly. Here the profile itself
is made jerk-limited: ``filtered_law.FilteredTimeLaw`` averages TOPP-RA's σ(t) over a
window of T = a_path / j_path seconds (the constant-jerk S-curve's jerk phase at the
full path acceleration), which costs T on the cycle and keeps the acceleration
continuous. Each round samples the law at LIMIT_CHECK_RATE_HZ and checks every
joint's velocity, acceleration and jerk (a share of each limit, SHARES) and the path
jerk; where a sample is over, TOPP-RA is solved again with lower curves over the
stretch of the profile that sample averages (``FilteredTimeLaw.span``):

* the speed curve σ̇ ≤ v(σ) where a term of the speed alone dominates
  (q′σ̇, q″σ̇², q‴σ̇³), by the excess (to the power 1, ½ or ⅓; damped, see
  EXCESS_DAMPING);
* the path acceleration curve |σ̈| ≤ a(σ) where a term of the speed change
  dominates (q′σ̈, 3q″σ̇σ̈ + q′σ⃛, or σ⃛ over the path jerk): σ⃛ of the average is
  a difference of σ̈ across the window over T.

After the first round, TOPP-RA is re-solved only around the stretches the last round
lowered (``time_optimal.resolve_locally``: exact, a few ms a round). An expected
failure (no round holds every limit) is a return value: ``None``.
"""

from __future__ import annotations

import numpy as np

from offline_prog.arrays import row_max, true_runs
from offline_prog.constants import LIMIT_CHECK_RATE_HZ, ProcessIntent
from offline_prog.timing.filtered_law import FilteredTimeLaw
from offline_prog.timing.jerk_stage import JerkLimitedTiming, steady_jerk_limit
from offline_prog.timing.joint_timing import JointRates
from offline_prog.timing.limit_use import (
    HOLD_TOLERANCE,
    KINDS,
    LIMIT_SHARE,
    joint_use,
    slowdowns,
    with_jerk,
    worst_use,
)
from offline_prog.timing.time_optimal import ToppProfile, resolve_locally, topp_profile

# Share of each joint limit (velocity, acceleration, jerk) the law is planned to. The
# jerk's is lower: q‴ is the σ-difference of q″ on the rates' 0.5 mm grid, up to 8 %
# of a joint's peak off the exact q‴ near the seal demo's corners (5 % at the
# law's worst sample, where the averaged law, unlike the staircase's 90 % plateaus,
# runs at the limit).
SHARES = (LIMIT_SHARE, LIMIT_SHARE, 0.94)
MAX_ROUNDS = 120
# Each round lowers a curve to this share of what the excess asks for ...
STEP_SHARE = 0.99
# ... taken to this power: a sample's excess is blamed on one curve (speed or
# acceleration) though both terms add to it; small steps let the next round see what
# the other curve's step did (seal demo, jerk planned to 98 %: 13.38 s with 0.2 and
# 0.99, 13.43 s with 0.3 and 0.97, 13.76 s with 1 and 0.97; scripts/bench_timing.py
# prints the solve time).
EXCESS_DAMPING = 0.2
# The acceleration curve never goes below this share of the path acceleration.
MIN_ACCELERATION_SHARE = 1e-3


def _steps(grid: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, ...]:
    """(i, j): the profile's grid steps i ≤ k < j that the spans [lo, hi] touch."""
    last = len(grid) - 2
    i = np.clip(np.searchsorted(grid, lo, side="right") - 1, 0, last)
    j = np.clip(np.searchsorted(grid, hi, side="right") - 1, 0, last) + 1
    return i, np.maximum(j, i + 1)


def _lower(curve: np.ndarray, sigma: np.ndarray, lo, hi, values) -> None:
    """curve = min(curve, value) on each [lo, hi] (inclusive, on the rates' grid σ)."""
    a = np.searchsorted(sigma, np.asarray(lo) - 1e-12, side="left")
    b = np.searchsorted(sigma, np.asarray(hi) + 1e-12, side="right")
    for i, j, value in zip(a, b, values, strict=True):
        np.minimum(curve[i:j], value, out=curve[i:j])


def _excess(use: dict, jerk_path: np.ndarray):
    """Per sample, (factor on the speed, factor on the acceleration) that would bring
    it to its limits: 1 where none is needed."""
    speed_over = row_max(
        np.maximum.reduce(
            [
                use["velocity"],
                np.where(
                    use["acceleration_speed"] >= use["acceleration_change"],
                    np.sqrt(use["acceleration"]),
                    0.0,
                ),
                np.where(use["jerk_speed"] >= use["jerk_change"], np.cbrt(use["jerk"]), 0.0),
            ]
        )
    )
    change_over = row_max(
        np.maximum.reduce(
            [
                np.where(
                    use["acceleration_speed"] < use["acceleration_change"],
                    use["acceleration"],
                    0.0,
                ),
                np.where(use["jerk_speed"] < use["jerk_change"], use["jerk"], 0.0),
            ]
        )
    )
    return np.maximum(speed_over, 1.0), np.maximum(np.maximum(change_over, jerk_path), 1.0)


def filtered_timing(
    rates: JointRates,
    profile: ToppProfile,
    *,
    v_process: float,
    a_max: float,
    j_max: float,
    limits: tuple[np.ndarray, np.ndarray, np.ndarray],
    check_rate_hz: float = LIMIT_CHECK_RATE_HZ,
) -> JerkLimitedTiming | None:
    """The averaged TOPP-RA law under every limit (module doc), or None.

    Args:
        rates: q, q′, q″ on a σ grid over [0, length] (controller axes).
        profile: TOPP-RA's answer with the steady jerk limit (reported as the
            timing's topp; the rounds solve their own, to SHARES of the limits).
        v_process: the process speed cap [m/s]; a_max, j_max: path limits [m/s², m/s³].
        limits: (qd_max, qdd_max, qddd_max), each (6,) [rad/s, rad/s², rad/s³].
        check_rate_hz: sample rate of the limit check.

    Returns:
        The timing (process "cycle_time"; a_scale: the lowest acceleration curve /
        a_max), or None if no round held every limit.
    """
    length = float(rates.sigma[-1])
    dddq = with_jerk(rates)
    shared = tuple(share * np.asarray(x) for share, x in zip(SHARES, limits, strict=True))
    window = a_max / j_max
    steady = steady_jerk_limit(rates, limits) * np.cbrt(SHARES[2] / LIMIT_SHARE)
    v_curve = np.minimum(steady, v_process)
    a_curve = np.full(len(rates.sigma), a_max)

    def solve(span=None, ends=(0.0, 0.0)):
        return topp_profile(
            rates,
            qd_max=shared[0],
            qdd_max=shared[1],
            v_cap=v_process,
            a_path=a_max,
            v_steady=v_curve,
            a_curve=a_curve,
            span=span,
            ends=ends,
        )

    profile, lowered = solve(), []
    for _ in range(MAX_ROUNDS):
        if lowered:  # only around the stretches the last round lowered
            profile = resolve_locally(profile, lowered, solve, v_process**2 / (2.0 * a_max))
        if not profile.ok:
            return None
        law = FilteredTimeLaw(length, v_process, a_max, j_max, profile.sigma, profile.speed, window)
        t = np.arange(0.0, law.duration, 1.0 / check_rate_hz)
        use = joint_use(rates, dddq, law, t, shared)
        jerk_path = np.abs(use["sddd"]) / (LIMIT_SHARE * j_max)
        if max(use[k].max() for k in KINDS) <= 1.0 and jerk_path.max() <= 1.0:
            use = joint_use(rates, dddq, law, t, limits)
            worst = worst_use(use)
            return JerkLimitedTiming(
                law,
                reductions(use, v_process),
                float(a_curve.min() / a_max),
                worst[2] <= 1.0 + 1e-9,
                worst,
                slowdowns(law, t, use, v_process),
                profile,
                ProcessIntent.CYCLE_TIME,
            )
        speed_over, change_over = (x**EXCESS_DAMPING for x in _excess(use, jerk_path))
        # The profile's steps each sample averages; TOPP-RA's curves hold at a step's
        # first grid point, so the lowered stretch runs from there to the last's end.
        grid = profile.sigma
        first, end = _steps(grid, *law.span(t))
        over = np.flatnonzero(speed_over > 1.0)
        cap = STEP_SHARE * use["speed"][over] / speed_over[over]
        _lower(v_curve, rates.sigma, grid[first[over]], grid[end[over]], cap)
        lowered = list(zip(grid[first[over]], grid[end[over]], strict=True))
        over = np.flatnonzero(change_over > 1.0)
        steps = np.abs(law.profile_acceleration())
        hardest = np.array([steps[i:j].max() for i, j in zip(first[over], end[over], strict=True)])
        cap = np.maximum(STEP_SHARE * hardest / change_over[over], MIN_ACCELERATION_SHARE * a_max)
        _lower(a_curve, rates.sigma, grid[first[over]], grid[end[over]], cap)
        lowered += list(zip(grid[first[over]], grid[end[over]], strict=True))
    return None


def reductions(use: dict, v_process: float) -> tuple[tuple[float, float, float], ...]:
    """((σ_start, σ_end, lowest speed), ...) the stretches between start and stop
    where the law runs below the process speed (HOLD_TOLERANCE)."""
    speed, sigma = use["speed"], use["sigma"]
    runs = true_runs(speed < v_process * (1.0 - HOLD_TOLERANCE))
    return tuple(
        (float(sigma[a]), float(sigma[b - 1]), float(speed[a:b].min()))
        for a, b in runs
        if a > 0 and b < len(speed)
    )
