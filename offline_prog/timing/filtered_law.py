"""A jerk-limited time law from TOPP-RA's profile by a moving average in time.

TOPP-RA's σ̇(σ) (``time_optimal``) has piecewise-constant σ̈: run in time, σ(t) is
piecewise quadratic and σ̈(t) jumps. Averaging σ(t) over a window of T seconds,

    σ_T(t) = (1/T) ∫_{t−T}^{t} σ(τ) dτ,

(σ = 0 before the start, σ = length after the end) gives a rest-to-rest law with

    σ̇_T(t) = (σ(t) − σ(t−T)) / T,   σ̈_T(t) = (σ̇(t) − σ̇(t−T)) / T,
    σ⃛_T(t) = (σ̈(t) − σ̈(t−T)) / T:

continuous acceleration, piecewise-constant jerk bounded by the largest change of
TOPP-RA's σ̈ over any window / T. The law runs T longer than the profile; on a
trapezoidal speed it is the constant-jerk S-curve (Biagiotti & Melchiorri 2008,
§3.4, "trajectories by FIR filters"). Every value is exact (closed form), so
finite differences of the sampled law are clean. The speed at σ_T(t) is an average
of speeds a little ahead and behind: the jerk stage lowers the profile's speed limit
where that average is over a joint limit.
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class FilteredTimeLaw:
    """σ(t) on [0, duration]: a speed profile σ̇(σ) run in time, averaged over window.

    Attributes:
        length: path length [m].
        v_max, a_max, j_max: the process limits asked for [m/s, m/s², m/s³].
        sigma: (G,) the profile's grid [m], from 0 to length.
        speed: (G,) the profile's σ̇ on it [m/s] (0 at both ends, constant σ̈ between).
        window: the averaging window T [s], > 0.
    """

    length: float
    v_max: float
    a_max: float
    j_max: float
    sigma: np.ndarray
    speed: np.ndarray
    window: float

    def __post_init__(self):
        if not (np.isfinite(self.window) and self.window > 0):
            raise ValueError(f"filtered law: window must be > 0 s, got {self.window}")
        ds = np.diff(self.sigma)
        v0, v1 = self.speed[:-1], self.speed[1:]
        if np.any(v0 + v1 <= 0):
            raise ValueError("filtered law: speed must be > 0 inside the path")
        tau = 2.0 * ds / (v0 + v1)  # each step's duration at constant σ̈
        acc = (v1 - v0) / tau
        t = np.concatenate([[0.0], np.cumsum(tau)])
        # Q(t) = ∫ σ dt at the nodes.
        steps = self.sigma[:-1] * tau + 0.5 * v0 * tau**2 + acc * tau**3 / 6.0
        q_int = np.concatenate([[0.0], np.cumsum(steps)])
        object.__setattr__(self, "_nodes", (t, acc, q_int))

    @property
    def profile_duration(self) -> float:
        """The profile's own duration (without the window) [s]."""
        return float(self._nodes[0][-1])

    @property
    def duration(self) -> float:
        return self.profile_duration + self.window

    @property
    def v_peak(self) -> float:
        return float(self.speed.max())

    @property
    def reduced(self) -> bool:
        """True when the law never reaches v_max."""
        return self.v_peak < self.v_max * (1.0 - 1e-12)

    def _profile(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        """(Q, σ, σ̇, σ̈) of the unaveraged profile at times t (any real t)."""
        nodes, acc, q_int = self._nodes
        end = nodes[-1]
        tc = np.clip(t, 0.0, end)
        i = np.clip(np.searchsorted(nodes, tc, side="right") - 1, 0, len(acc) - 1)
        tau = tc - nodes[i]
        s0, v0, a = self.sigma[i], self.speed[i], acc[i]
        s = s0 + v0 * tau + 0.5 * a * tau**2
        v = v0 + a * tau
        q = q_int[i] + s0 * tau + 0.5 * v0 * tau**2 + a * tau**3 / 6.0
        before, after = t < 0.0, t > end
        q = np.where(before, 0.0, np.where(after, q_int[-1] + self.length * (t - end), q))
        s = np.where(before, 0.0, np.where(after, self.length, s))
        inside = (t >= 0.0) & (t < end)  # σ̈ steps at the ends: 0 outside
        return q, s, np.where(inside, v, 0.0), np.where(inside, a, 0.0)

    def profile_acceleration(self) -> np.ndarray:
        """(G − 1,) the profile's constant σ̈ on each grid step [m/s²]."""
        return self._nodes[1]

    def span(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(σ(t − T), σ(t)) of the profile: the stretch each sample averages [m]."""
        t = np.asarray(t, dtype=float)
        return self._profile(t - self.window)[1], self._profile(t)[1]

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        """(σ, σ̇, σ̈, σ⃛) at times t (N,) [m, m/s, m/s², m/s³]; clamped outside."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        now, then = self._profile(t), self._profile(t - self.window)
        s, v, a, j = ((x - y) / self.window for x, y in zip(now, then, strict=True))
        end = t >= self.duration  # pin the end at rest (removes rounding)
        return (
            np.where(end, self.length, s),
            np.where(end, 0.0, v),
            np.where(end, 0.0, a),
            np.where(end, 0.0, j),
        )
