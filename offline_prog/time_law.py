"""Rest-to-rest time law σ(t) with piecewise sin² jerk (paper §4, after Biagiotti
& Melchiorri, "Trajectory Planning for Automatic Machines and Robots", 2008).

The jerk is a sequence of seven segments: a positive sin² pulse, constant
acceleration, a negative pulse, cruise at the top speed, and the mirror image
to stop. A pulse of duration T_j and peak J changes the acceleration by J·T_j/2,
so the jerk, acceleration and velocity are all continuous and bounded by the
given limits. Short paths lower the top speed (and, if needed, the peak
acceleration) so that the profile still comes to rest exactly at the end.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.optimize import brentq


@dataclasses.dataclass(frozen=True)
class Sin2TimeLaw:
    """σ(t) on [0, duration] from rest at 0 to rest at ``length``.

    Attributes:
        length: path length to travel [m].
        v_max, a_max, j_max: the limits asked for [m/s, m/s², m/s³].
        v_peak: the top speed reached, v_peak ≤ v_max (lower on short paths).
        signs: (7,) jerk sign per segment (+1, 0, −1).
        durations: (7,) segment durations [s].
    """

    length: float
    v_max: float
    a_max: float
    j_max: float
    v_peak: float
    signs: np.ndarray
    durations: np.ndarray

    @property
    def duration(self) -> float:
        return float(self.durations.sum())

    @property
    def reduced(self) -> bool:
        """True when the path is too short to reach v_max."""
        return self.v_peak < self.v_max * (1.0 - 1e-12)

    def _segment_starts(self):
        """Start time and state (σ, σ̇, σ̈) of each segment."""
        starts = np.concatenate([[0.0], np.cumsum(self.durations)[:-1]])
        state = np.zeros((7, 3))
        s = v = a = 0.0
        for i in range(7):
            state[i] = s, v, a
            s, v, a, _ = _pulse(
                self.signs[i], self.durations[i], self.j_max, s, v, a, np.array([self.durations[i]])
            )
            s, v, a = float(s[0]), float(v[0]), float(a[0])
        return starts, state

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        """(σ, σ̇, σ̈, σ⃛) at times t (N,) [m, m/s, m/s², m/s³]; clamped outside."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        starts, state = self._segment_starts()
        seg = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, 6)
        tau = t - starts[seg]
        s, v, a, j = _pulse(
            self.signs[seg],
            self.durations[seg],
            self.j_max,
            state[seg, 0],
            state[seg, 1],
            state[seg, 2],
            tau,
        )
        # Pin the end exactly at rest at the path's end (removes rounding).
        end = t >= self.duration
        s = np.where(end, self.length, s)
        return s, np.where(end, 0.0, v), np.where(end, 0.0, a), np.where(end, 0.0, j)


def _pulse(sign, T, J, s0, v0, a0, tau):
    """State after time tau into a segment whose jerk is sign·J·sin²(π τ / T)."""
    sign = np.asarray(sign, dtype=float)
    T = np.where(np.asarray(T) > 0, T, 1.0)
    omega = 2.0 * np.pi / T
    half = 0.5 * sign * J
    sin_w, cos_w = np.sin(omega * tau), np.cos(omega * tau)
    j = half * (1.0 - cos_w)
    a = a0 + half * (tau - sin_w / omega)
    v = v0 + a0 * tau + half * (0.5 * tau**2 + (cos_w - 1.0) / omega**2)
    s = s0 + v0 * tau + 0.5 * a0 * tau**2 + half * (tau**3 / 6.0 + (sin_w / omega - tau) / omega**2)
    return s, v, a, j


def _acceleration_phase(v: float, a_max: float, j_max: float) -> tuple[float, float]:
    """(T_j, T_a) to go from rest to speed v: pulse, constant acceleration, pulse."""
    if v <= 2.0 * a_max**2 / j_max:
        return float(np.sqrt(2.0 * v / j_max)), 0.0
    t_j = 2.0 * a_max / j_max
    return t_j, v / a_max - t_j


def _acceleration_distance(v: float, a_max: float, j_max: float) -> float:
    t_j, t_a = _acceleration_phase(v, a_max, j_max)
    return 0.5 * v * (2.0 * t_j + t_a)


def sin2_time_law(length: float, *, v_max: float, a_max: float, j_max: float) -> Sin2TimeLaw:
    """Plan the rest-to-rest sin²-jerk profile over ``length``.

    Args:
        length: distance along the path [m], > 0.
        v_max, a_max, j_max: limits of σ̇, σ̈, σ⃛ (peak of the sin² jerk), all > 0.

    Returns:
        The Sin2TimeLaw; its v_peak is below v_max when the path is too short.
    """
    for name, value in (("length", length), ("v_max", v_max), ("a_max", a_max), ("j_max", j_max)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"time law: {name} must be a positive number, got {value}")
    v_peak = v_max
    if 2.0 * _acceleration_distance(v_max, a_max, j_max) > length:
        v_peak = brentq(
            lambda v: 2.0 * _acceleration_distance(v, a_max, j_max) - length,
            0.0,
            v_max,
            xtol=1e-15,
            rtol=1e-15,
        )
    t_j, t_a = _acceleration_phase(v_peak, a_max, j_max)
    t_v = max(0.0, (length - 2.0 * _acceleration_distance(v_peak, a_max, j_max)) / v_peak)
    signs = np.array([1, 0, -1, 0, -1, 0, 1], dtype=float)
    durations = np.array([t_j, t_a, t_j, t_v, t_j, t_a, t_j])
    return Sin2TimeLaw(length, v_max, a_max, j_max, float(v_peak), signs, durations)
