"""Jerk stage: the TOPP-RA profile made jerk-limited, re-checked against every limit.

TOPP-RA's σ̇(σ) (``time_optimal``) has piecewise-constant σ̈: its joint acceleration
jumps, which neither a controller nor a bead of sealant accepts. The jerk stage lays
a rest-to-rest sin² law (``time_law.sin2_plateau_law``: continuous acceleration,
bounded jerk) under it:

* ``constant_speed``: the process speed, except on the stretches where the joints
  cannot hold it steadily; each of those holds one steady speed (the lowest the
  joints allow on it, ``static_limit``).
* ``cycle_time``: a staircase under the TOPP-RA profile in steps of LEVEL_STEP
  (``path_timing`` keeps it where it beats ``filtered_stage``'s averaged profile).

Along the path the joints move with (′ = d/dσ)
    q̇ = q′σ̇,   q̈ = q″σ̇² + q′σ̈,   q⃛ = q‴σ̇³ + 3q″σ̇σ̈ + q′σ⃛.
Each round samples the law at LIMIT_CHECK_RATE_HZ and checks every joint's velocity,
acceleration and jerk (a LIMIT_SHARE of each limit). Where a term that grows with
the speed alone is over (q′σ̇, q″σ̇², q‴σ̇³) the speed cap is lowered there; where a
term of the speed change is over (q′σ̈, q′σ⃛ + 3q″σ̇σ̈) the path acceleration and jerk
of the stretch hosting that change are softened. q‴ is ``limit_use.with_jerk``'s (the
σ-difference of the exact q″ on the rates' grid, unless ``joints.jerk_check`` set it).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.arrays import row_max, row_min, true_runs
from offline_prog.constants import LIMIT_CHECK_RATE_HZ, ProcessIntent
from offline_prog.timing.filtered_law import FilteredTimeLaw
from offline_prog.timing.joint_timing import JointRates
from offline_prog.timing.limit_use import (
    HOLD_TOLERANCE,
    KINDS,
    LIMIT_SHARE,
    Slowdown,
    joint_use,
    slowdowns,
    with_jerk,
    worst_use,
)
from offline_prog.timing.time_law import Sin2TimeLaw, sin2_plateau_law
from offline_prog.timing.time_optimal import ToppProfile

# cycle_time: the staircase's step under the TOPP-RA profile (share of the level).
LEVEL_STEP = 0.02
# Share of each limit a steady speed may use: the rest is for the speed changes.
STEADY_SHARE = 0.9
MAX_ROUNDS = 30
# Each round lowers an over-limit speed, or softens a transition, to this share of
# what the limit allows.
STEP_SHARE = 0.97


@dataclasses.dataclass(frozen=True)
class JerkLimitedTiming:
    """The jerk-limited law and what it cost (the fields of ``joint_timing.Retiming``
    plus the time-optimal ones).

    Attributes:
        law: the time law to use.
        reductions: ((σ_start, σ_end, speed), ...) plateaus below the process speed.
        a_scale: the softest transition's factor on the path acceleration and jerk
            (FilteredTimeLaw: the lowest path acceleration curve / a_max).
        feasible: every joint velocity, acceleration and jerk limit holds.
        worst: (joint index, σ, use) of the largest limit use on the final samples.
        slowdowns: every stretch below the process speed, with its limiting joint.
        topp: the TOPP-RA profile underneath, with the steady jerk limit as a speed
            limit curve (its duration: without the jerk stage).
        process: the intent (constants.ProcessIntent).
    """

    law: Sin2TimeLaw | FilteredTimeLaw
    reductions: tuple[tuple[float, float, float], ...]
    a_scale: float
    feasible: bool
    worst: tuple[int, float, float]
    slowdowns: tuple[Slowdown, ...]
    topp: ToppProfile | None = None
    process: ProcessIntent = ProcessIntent.CONSTANT_SPEED
    topp_plain_s: float = float("nan")  # TOPP-RA without the steady jerk limit [s]
    # (share of the feasible length holding the process speed ±0.5 %, feasible share
    # of the path): timing.speed_hold.SpeedHold.
    speed_held: tuple[float, float] = (float("nan"), float("nan"))
    solve_s: float = float("nan")  # wall time of the whole time-optimal law [s]


def envelope(profile: ToppProfile) -> np.ndarray:
    """(G,) TOPP-RA's speed with the rest-to-rest ramps at the ends lifted to the
    first and last peak (the sin² law makes its own start and stop)."""
    speed = profile.speed.copy()
    for values in (speed, speed[::-1]):  # the view turns the end into a start
        falls = np.flatnonzero(np.diff(values) <= 0.0)
        peak = int(falls[0]) if len(falls) else len(values) - 1
        values[:peak] = values[peak]
    return speed


def static_limit(rates: JointRates, dddq: np.ndarray, limits) -> np.ndarray:
    """(G,) the highest steady speed each grid point allows [m/s]: with σ̈ = σ⃛ = 0,
    |q′σ̇| ≤ q̇_max, |q″σ̇²| ≤ q̈_max and |q‴σ̇³| ≤ q⃛_max (exact on a plateau)."""
    qd_max, qdd_max, qddd_max = limits
    with np.errstate(divide="ignore"):
        by_velocity = qd_max / np.abs(rates.dq)
        by_acceleration = np.sqrt(qdd_max / np.abs(rates.ddq))
        by_jerk = np.cbrt(qddd_max / np.abs(dddq))
    return row_min(np.minimum.reduce([by_velocity, by_acceleration, by_jerk]))


def steady_jerk_limit(rates: JointRates, limits) -> np.ndarray:
    """(G,) the steady speed the joint jerk limits allow, |q‴σ̇³| ≤ LIMIT_SHARE · q⃛_max
    [m/s] (a speed limit curve TOPP-RA can take; it knows no jerk)."""
    with np.errstate(divide="ignore"):
        by_jerk = np.cbrt(LIMIT_SHARE * limits[2] / np.abs(with_jerk(rates)))
    return row_min(by_jerk)


def ceiling(profile: ToppProfile, steady: np.ndarray, v_process: float, process: str):
    """(G,) the speed cap at each of TOPP-RA's grid points for the intent (module doc).

    Args:
        steady: (G,) the highest steady speed the joints allow there (static_limit).
    """
    if process == ProcessIntent.CYCLE_TIME:
        speed = np.minimum(envelope(profile), steady)
        ratio = np.clip(speed / (v_process * (1.0 - HOLD_TOLERANCE)), 1e-9, 1.0)
        level = np.ceil(np.log(ratio) / np.log1p(-LEVEL_STEP))
        return np.minimum(v_process * (1.0 - LEVEL_STEP) ** level, v_process)
    cap = np.full_like(steady, v_process)
    for a, b in true_runs(steady < v_process):
        cap[a:b] = steady[a:b].min()
    return cap


def stretches(sigma: np.ndarray, cap: np.ndarray, soft: np.ndarray):
    """Contiguous (v, σ_start, σ_end) stretches of equal cap and their (in, out)
    softening factors: each grid interval takes the lower cap of its two ends, each
    stretch the softest factors (soft: (G, 2)) on it."""
    v = np.minimum(cap[1:], cap[:-1])
    change = np.flatnonzero(np.diff(v) != 0.0) + 1
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change, [len(v)]])
    caps, factors = [], []
    for a, b in zip(starts, ends, strict=True):
        caps.append((float(v[a]), float(sigma[a]), float(sigma[b])))
        factors.append(tuple(float(x) for x in soft[a : b + 1].min(axis=0)))
    return caps, factors


def jerk_limited_law(
    rates: JointRates,
    profile: ToppProfile,
    *,
    v_process: float,
    a_max: float,
    j_max: float,
    limits: tuple[np.ndarray, np.ndarray, np.ndarray],
    process: ProcessIntent = ProcessIntent.CONSTANT_SPEED,
    check_rate_hz: float = LIMIT_CHECK_RATE_HZ,
) -> JerkLimitedTiming:
    """The jerk stage (module doc).

    Args:
        rates: q, q′, q″ on a σ grid over [0, length] (controller axes).
        profile: TOPP-RA's answer for the same path and limits.
        v_process: the process speed [m/s]; a_max, j_max: path limits [m/s², m/s³].
        limits: (qd_max, qdd_max, qddd_max), each (6,).
        process: the intent (constants.ProcessIntent).
    """
    length = float(rates.sigma[-1])
    dddq = with_jerk(rates)
    shared = tuple(LIMIT_SHARE * np.asarray(x) for x in limits)
    sigma = profile.sigma
    # Plateaus plan to STEADY_SHARE of each limit, leaving room for the speed changes.
    steady = static_limit(rates, dddq, tuple(STEADY_SHARE * np.asarray(x) for x in limits))
    steady = np.interp(sigma, rates.sigma, steady)  # re-checked on the samples
    cap = ceiling(profile, steady, v_process, process)
    soft = np.ones((len(cap), 2))  # (in, out) factors on a_max, j_max
    for _ in range(MAX_ROUNDS):
        caps, factors = stretches(sigma, cap, soft)
        law = sin2_plateau_law(
            length, caps, a_max=a_max, j_max=j_max, v_max=v_process, scales=factors
        )
        t = np.arange(0.0, law.duration, 1.0 / check_rate_hz)
        use = joint_use(rates, dddq, law, t, shared)
        if max(use[k].max() for k in KINDS) <= 1.0:
            break
        # On a plateau (σ̈ = σ⃛ = 0) every term is the speed's, and so is the velocity
        # and any term over on its own: lower the cap there by the excess.
        on_plateau = (np.abs(use["sdd"]) < 1e-9) & (np.abs(use["sddd"]) < 1e-9)
        plateau = on_plateau[:, None]
        speed_over = row_max(
            np.maximum.reduce(
                [
                    use["velocity"],
                    np.sqrt(np.where(plateau, use["acceleration"], use["acceleration_speed"])),
                    np.cbrt(np.where(plateau, use["jerk"], use["jerk_speed"])),
                ]
            )
        )
        over = speed_over > 1.0
        if over.any():
            lowered = STEP_SHARE * use["speed"][over] / speed_over[over]
            index = np.clip(np.searchsorted(sigma, use["sigma"][over]), 1, len(sigma) - 1)
            for i in (index - 1, index):
                np.minimum.at(cap, i, lowered)
        # Over during a speed change: soften that change (the speed-up at the start of
        # the law's plateau it lies on, or the slow-down at its end).
        change_over = np.where(
            on_plateau, 0.0, row_max(np.maximum(use["acceleration"], use["jerk"]))
        )
        sdd = use["sdd"]
        ends = np.array([b for _, _, b in law.plateaus])
        worst_over: dict[tuple[int, int], float] = {}  # (plateau, side): largest excess
        for k in np.flatnonzero(change_over > 1.0):
            host = min(int(np.searchsorted(ends, use["sigma"][k])), len(ends) - 1)
            key = (host, 0 if sdd[k] > 0 else 1)
            worst_over[key] = max(worst_over.get(key, 1.0), float(change_over[k]))
        for (host, side), excess in worst_over.items():
            _, a, b = law.plateaus[host]
            inside = (sigma >= a - 1e-12) & (sigma <= b + 1e-12)
            soft[inside, side] = soft[inside, side].min() * STEP_SHARE / excess
    t = np.arange(0.0, law.duration, 1.0 / check_rate_hz)
    use = joint_use(rates, dddq, law, t, limits)
    worst = worst_use(use)
    reductions = tuple((a, b, v) for v, a, b in law.plateaus if v < v_process * (1 - 1e-9))
    return JerkLimitedTiming(
        law,
        reductions,
        float(np.min(factors)),
        worst[2] <= 1.0 + 1e-9,
        worst,
        slowdowns(law, t, use, v_process),
        profile,
        process,
    )
