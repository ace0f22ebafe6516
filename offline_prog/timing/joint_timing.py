"""Slow down only where the robot's joints need it (joint speed and acceleration).

Along the path parameter σ the joints move as q(σ), so q̇ = q′σ̇ and
q̈ = q″σ̇² + q′σ̈ (′ = d/dσ). The joint limits therefore cap the path speed:
σ̇ ≤ q̇_max,j / |q′_j| and, from the centripetal part, σ̇ ≤ √(½ q̈_max,j / |q″_j|).
Where the process speed exceeds that cap, the time law gets a lower plateau on
that stretch only (``time_law.sin2_plateau_law``), so the motion stays
jerk-limited with continuous acceleration. The result is checked on the
sampled trajectory and tightened until every joint limit holds. This is the
time-optimal-under-limits idea of TOPP (Pham 2014) restricted to sin² profiles,
which keep the acceleration continuous where TOPP's bang-bang solution would not.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.arrays import interp_rows, row_max, row_min, true_runs
from offline_prog.constants import LIMIT_CHECK_RATE_HZ
from offline_prog.timing.time_law import Sin2TimeLaw, sin2_plateau_law

# Share of a joint's speed limit the planner may use, and of its acceleration
# limit spent on the centripetal term q″σ̇² (the rest is for q′σ̈).
SPEED_LIMIT_SHARE = 0.95
CENTRIPETAL_SHARE = 0.5
# A capped stretch is widened by this much on each side [m of σ].
CAP_PADDING_M = 2e-3
MAX_RETIMING_ROUNDS = 12
# Each retiming round lowers an over-limit speed, or the ramps, to this share of what
# the limit allows: a margin so the next round's samples land inside the limits.
RETIMING_STEP_SHARE = 0.9


@dataclasses.dataclass(frozen=True)
class JointRates:
    """Joint path derivatives on a σ grid.

    Attributes:
        sigma: (G,) grid of the time law's parameter [m].
        q, dq, ddq: (G, 6) q(σ) [rad], q′ [rad/m], q″ [rad/m²].
        dddq: (G, 6) q‴ [rad/m³] where known better than the σ-difference of q″
            (``limit_use.with_jerk``; ``joints.jerk_check`` sets it from the exact
            path), or None.
    """

    sigma: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    dddq: np.ndarray | None = None

    def at(self, sigma: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(q′, q″) linearly interpolated at σ (N,), each (N, 6)."""
        return tuple(interp_rows(sigma, self.sigma, self.dq, self.ddq))


def speed_cap(rates: JointRates, qd_max: np.ndarray, qdd_max: np.ndarray) -> np.ndarray:
    """(G,) highest σ̇ the joints allow at each grid point [m/s]."""
    with np.errstate(divide="ignore"):
        by_speed = SPEED_LIMIT_SHARE * qd_max / np.abs(rates.dq)
        by_accel = np.sqrt(CENTRIPETAL_SHARE * qdd_max / np.abs(rates.ddq))
    return np.minimum(row_min(by_speed), row_min(by_accel))


def _caps_from(sigma: np.ndarray, cap: np.ndarray, v_process: float, length: float):
    """Contiguous (v, σ_start, σ_end) stretches: v_process except where cap is lower."""
    low = cap < v_process
    if not low.any():
        return [(v_process, 0.0, length)]
    zones = []
    for a, b in true_runs(low):
        start = max(0.0, sigma[a] - CAP_PADDING_M)
        end = min(length, sigma[b - 1] + CAP_PADDING_M)
        v = float(cap[a:b].min())
        if zones and start <= zones[-1][2]:  # overlapping after padding: merge
            v0, s0, _ = zones.pop()
            zones.append((min(v, v0), s0, end))
        else:
            zones.append((v, start, end))
    caps, cursor = [], 0.0
    for v, start, end in zones:
        if start > cursor:
            caps.append((v_process, cursor, start))
        caps.append((v, start, end))
        cursor = end
    if cursor < length:
        caps.append((v_process, cursor, length))
    return caps


@dataclasses.dataclass(frozen=True)
class Retiming:
    """The joint-feasible time law and what it cost.

    Attributes:
        law: the time law to use.
        reductions: ((σ_start, σ_end, speed), ...) stretches where the process
            speed was lowered, with the speed held there [m, m, m/s].
        a_scale: factor applied to the path acceleration and jerk limits (1: none).
        feasible: every joint speed and acceleration limit holds.
        worst: (joint index, σ, ratio) of the largest limit use |q̇|/q̇_max or
            |q̈|/q̈_max on the final samples.
    """

    law: Sin2TimeLaw
    reductions: tuple[tuple[float, float, float], ...]
    a_scale: float
    feasible: bool
    worst: tuple[int, float, float]


def limit_use(rates, law, t, qd_max, qdd_max):
    """Limit use of the law sampled at t: σ (N,) and, each (N, 6), |q̇|/q̇_max,
    |q″σ̇²|/q̈_max (centripetal), |q′σ̈|/q̈_max (tangential) and |q̈|/q̈_max."""
    sigma, sd, sdd, _ = law(t)
    dq, ddq = rates.at(sigma)
    centripetal = ddq * (sd**2)[:, None]
    tangential = dq * sdd[:, None]
    return (
        sigma,
        np.abs(dq * sd[:, None]) / qd_max,
        np.abs(centripetal) / qdd_max,
        np.abs(tangential) / qdd_max,
        np.abs(centripetal + tangential) / qdd_max,
    )


def retime(
    rates: JointRates,
    nominal: Sin2TimeLaw,
    *,
    qd_max: np.ndarray,
    qdd_max: np.ndarray,
    check_rate_hz: float = LIMIT_CHECK_RATE_HZ,
) -> Retiming:
    """Lower the process speed only where the joints cannot follow (see module doc).

    Args:
        rates: q′ and q″ on a σ grid covering [0, nominal.length].
        nominal: the process time law (its v_max is the process speed).
        qd_max, qdd_max: (6,) joint speed [rad/s] and acceleration [rad/s²] limits.
        check_rate_hz: sample rate of the limit check.
    """
    v_process, length = nominal.v_peak, nominal.length
    cap = np.minimum(speed_cap(rates, qd_max, qdd_max), v_process)
    a_scale = 1.0
    for _ in range(MAX_RETIMING_ROUNDS):
        caps = _caps_from(rates.sigma, cap, v_process, length)
        law = sin2_plateau_law(
            length,
            caps,
            a_max=nominal.a_max * a_scale,
            j_max=nominal.j_max * a_scale,
            v_max=nominal.v_max,
        )
        t = np.arange(0.0, law.duration, 1.0 / check_rate_hz)
        sigma, speed, centripetal, tangential, accel = limit_use(rates, law, t, qd_max, qdd_max)
        if max(speed.max(), accel.max()) <= 1.0:
            break
        # Too fast (speed or centripetal acceleration): lower the cap there, by the
        # excess. Too hard a speed change (q′σ̈): lower the path acceleration.
        too_fast = np.where(speed > 1.0, speed, 1.0)
        centripetal_over = np.where(
            (accel > 1.0) & (centripetal >= tangential), np.sqrt(accel), 1.0
        )
        over_speed = row_max(np.maximum(too_fast, centripetal_over))
        bad = over_speed > 1.0
        if bad.any():
            _, sd, _, _ = law(t)
            limit = np.where(bad, RETIMING_STEP_SHARE * sd / np.maximum(over_speed, 1.0), np.inf)
            lowered = np.interp(rates.sigma, sigma, limit)
            cap = np.minimum(cap, lowered)
        hard = (accel > 1.0) & (tangential > centripetal)
        if hard.any():
            a_scale *= RETIMING_STEP_SHARE / float(np.sqrt(accel[hard].max()))
    t = np.arange(0.0, law.duration, 1.0 / check_rate_hz)
    sigma, speed, _, _, accel = limit_use(rates, law, t, qd_max, qdd_max)
    use = np.maximum(speed, accel)
    i, j = np.unravel_index(np.argmax(use), use.shape)
    reductions = tuple((s0, s1, v) for v, s0, s1 in law.plateaus if v < v_process * (1 - 1e-9))
    return Retiming(
        law,
        reductions,
        a_scale,
        bool(use.max() <= 1.0 + 1e-9),
        (int(j), float(sigma[i]), float(use[i, j])),
    )
