"""How much of each joint limit a timed path uses, and the slowdowns that explains.

Along the path the joints move with (′ = d/dσ)
    q̇ = q′σ̇,   q̈ = q″σ̇² + q′σ̈,   q⃛ = q‴σ̇³ + 3q″σ̇σ̈ + q′σ⃛,
so each term's use of its limit follows from the time law's σ̇, σ̈, σ⃛ and the joint
path's q′, q″ (exact, through the Jacobian) and q‴ (the σ-difference of the exact q″).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.arrays import interp_rows, true_runs
from offline_prog.timing.joint_timing import JointRates

# A speed this close below the process speed counts as holding it.
HOLD_TOLERANCE = 1e-3
# Share of each joint limit a law is planned to (room for sampling between checks).
LIMIT_SHARE = 0.98
KINDS = ("velocity", "acceleration", "jerk")


@dataclasses.dataclass(frozen=True)
class Slowdown:
    """A stretch where the process speed was lowered, and why.

    Attributes:
        sigma_m, t_s: (start, end) on the path [m] and in time [s].
        speed_min_m_s: the lowest σ̇ on it [m/s].
        joint: the limiting joint (1-based, controller axes), or None.
        constraint: "velocity" | "acceleration" | "jerk" (of that joint), or
            "start/stop" (the rest-to-rest ramps at the path's ends).
        use: that limit's largest use on the stretch (1 = at the limit).
    """

    sigma_m: tuple[float, float]
    t_s: tuple[float, float]
    speed_min_m_s: float
    joint: int | None
    constraint: str
    use: float


def with_jerk(rates: JointRates) -> np.ndarray:
    """(G, 6) q‴ [rad/m³]: ``rates.dddq`` if set, else the σ-difference of the exact q″
    on the rates' grid (it smooths q‴'s peaks over a grid step: ``joints.jerk_check``
    finds where that let the joints' jerk over its limit, and sets ``rates.dddq``)."""
    if rates.dddq is not None:
        return rates.dddq
    return np.gradient(rates.ddq, rates.sigma, axis=0)


# Each term of the joint rates (N, 6) from q′, q″, q‴ and the law's σ̇, σ̈, σ⃛ (module doc).
_TERMS = {
    "velocity": lambda dq, ddq, d3q, sd, sdd, sddd: dq * sd,
    "centripetal": lambda dq, ddq, d3q, sd, sdd, sddd: ddq * sd**2,
    "tangential": lambda dq, ddq, d3q, sd, sdd, sddd: dq * sdd,
    "jerk_speed": lambda dq, ddq, d3q, sd, sdd, sddd: d3q * sd**3,
    "jerk_change": lambda dq, ddq, d3q, sd, sdd, sddd: 3 * ddq * sd * sdd + dq * sddd,
}
# Each use: the terms summed and the limit (index into limits) it is divided by.
_USES = {
    "velocity": (("velocity",), 0),
    "acceleration": (("centripetal", "tangential"), 1),
    "acceleration_speed": (("centripetal",), 1),
    "acceleration_change": (("tangential",), 1),
    "jerk": (("jerk_speed", "jerk_change"), 2),
    "jerk_speed": (("jerk_speed",), 2),
    "jerk_change": (("jerk_change",), 2),
}


class _Use(dict):
    """joint_use's answer: each use (and each term) computed when first read, since
    most callers read a few of them."""

    def __init__(self, rates: tuple, terms: dict, limits, **known):
        super().__init__(known)
        self._rates, self._limits, self._terms = rates, limits, terms

    def __missing__(self, key: str) -> np.ndarray:
        if key not in _USES:
            raise KeyError(key)
        names, limit = _USES[key]
        for name in names:
            if name not in self._terms:
                self._terms[name] = _TERMS[name](*self._rates)
        total = sum((self._terms[name] for name in names[1:]), self._terms[names[0]])
        self[key] = value = np.abs(total) / self._limits[limit]
        return value


def joint_use(rates: JointRates, dddq: np.ndarray, law, t: np.ndarray, limits) -> dict:
    """Each limit's use at times t: σ (N,) and per term (N, 6) |term| / limit.

    Keys: sigma, speed, sdd, sddd (N,) of the law; velocity, acceleration (and its
    acceleration_speed, acceleration_change parts: q″σ̇², q′σ̈), jerk (jerk_speed,
    jerk_change: q‴σ̇³, 3q″σ̇σ̈ + q′σ⃛), each (N, 6), computed when first read.

    Args:
        limits: (qd_max, qdd_max, qddd_max), each (6,) [rad/s, rad/s², rad/s³].
    """
    sigma, sd, sdd, sddd = law(t)
    arrays = (sigma, sd, sdd, sddd, rates.sigma, rates.dq, rates.ddq, dddq)
    key = (
        tuple(np.shape(a) for a in arrays),
        b"".join(np.ascontiguousarray(a, dtype=float).tobytes() for a in arrays),
    )
    kept = _last_rates  # one read: threads may replace it
    if kept is not None and kept[0] == key:  # the same law and path: other limits
        rates_at_t, terms = kept[1], kept[2]
    else:
        dq, ddq, d3q = interp_rows(sigma, rates.sigma, rates.dq, rates.ddq, dddq)
        rates_at_t, terms = (dq, ddq, d3q, sd[:, None], sdd[:, None], sddd[:, None]), {}
        _keep(key, rates_at_t, terms)
    return _Use(rates_at_t, terms, limits, sigma=sigma, speed=sd, sdd=sdd, sddd=sddd)


# The last joint_use's rates at its times and the terms computed (they do not depend on
# the limits): the jerk stage asks for the same law under its shared limits, then the
# full ones, and its check once more.
_last_rates: tuple | None = None


def _keep(key: tuple, rates_at_t: tuple, terms: dict) -> None:
    global _last_rates
    _last_rates = (key, rates_at_t, terms)


def worst_use(use: dict) -> tuple[int, float, float]:
    """(joint index, σ, use) of the largest velocity, acceleration or jerk use."""
    kind = max(KINDS, key=lambda k: use[k].max())
    i, j = np.unravel_index(np.argmax(use[kind]), use[kind].shape)
    return int(j), float(use["sigma"][i]), float(use[kind][i, j])


def slowdowns(law, t: np.ndarray, use: dict, v_process: float) -> tuple[Slowdown, ...]:
    """Every stretch with σ̇ below the process speed (HOLD_TOLERANCE), with the joint
    limit used most on it; the runs touching the path's ends are the start and stop."""
    speed, sigma = use["speed"], use["sigma"]
    out = []
    for a, b in true_runs(speed < v_process * (1.0 - HOLD_TOLERANCE)):
        span = slice(a, b)
        ends = a == 0 or b == len(speed)
        uses = {k: use[k][span].max(axis=0) for k in KINDS}
        kind = max(KINDS, key=lambda k: uses[k].max())
        joint = int(np.argmax(uses[kind]))
        limited = uses[kind][joint] >= 0.9 * LIMIT_SHARE
        out.append(
            Slowdown(
                (float(sigma[a]), float(sigma[b - 1])),
                (float(t[a]), float(t[b - 1])),
                float(speed[span].min()),
                joint + 1 if limited else None,
                kind if limited else ("start/stop" if ends else "path acceleration"),
                float(uses[kind][joint]),
            )
        )
    return tuple(out)
