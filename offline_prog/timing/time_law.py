"""Rest-to-rest time law σ(t) with piecewise sin² jerk (paper §4, after Biagiotti
& Melchiorri, "Trajectory Planning for Automatic Machines and Robots", 2008).

The jerk is a sequence of segments: a positive sin² pulse, constant acceleration,
a negative pulse, cruise at the top speed, and the mirror image to stop. A pulse
of duration T_j and peak J changes the acceleration by J·T_j/2, so the jerk,
acceleration and velocity are all continuous and bounded by the given limits.
Short paths lower the top speed (and, if needed, the peak acceleration) so that
the profile still comes to rest exactly at the end.

Where the robot cannot hold the process speed (joint limits, see
``joint_timing``), the speed is capped on stretches of the path: the profile
then runs through plateaus, slowing down before a capped stretch and speeding
up after it with the same sin² transitions (``sin2_plateau_law``).
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class Sin2TimeLaw:
    """σ(t) on [0, duration] from rest at 0 to rest at ``length``.

    Attributes:
        length: path length to travel [m].
        v_max, a_max, j_max: the limits asked for [m/s, m/s², m/s³].
        v_peak: the top speed reached, v_peak ≤ v_max (lower on short paths).
        signs: (K,) jerk sign per segment (+1, 0, −1).
        durations: (K,) segment durations [s].
        plateaus: ((v, σ_start, σ_end), ...) the cruise speeds and where they hold.
        jerks: (K,) peak jerk of each segment's pulse [m/s³] (None: j_max everywhere;
            the time-optimal law softens single transitions where joints need it).
    """

    length: float
    v_max: float
    a_max: float
    j_max: float
    v_peak: float
    signs: np.ndarray
    durations: np.ndarray
    plateaus: tuple[tuple[float, float, float], ...] = ()
    jerks: np.ndarray | None = None

    def _jerks(self) -> np.ndarray:
        return np.full(len(self.durations), self.j_max) if self.jerks is None else self.jerks

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
        state = np.zeros((len(self.durations), 3))
        s = v = a = 0.0
        jerks = self._jerks()
        for i in range(len(self.durations)):
            state[i] = s, v, a
            s, v, a, _ = _pulse(
                self.signs[i], self.durations[i], jerks[i], s, v, a, np.array([self.durations[i]])
            )
            s, v, a = float(s[0]), float(v[0]), float(a[0])
        return starts, state

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        """(σ, σ̇, σ̈, σ⃛) at times t (N,) [m, m/s, m/s², m/s³]; clamped outside.

        The arrays are read-only: the law keeps its last answer (a joint plan asks for
        the same output times four times: the jerk stage, its check, the workspace
        trajectory and the joints), one tuple replaced whole (threads may share a law).
        """
        t = np.asarray(t, dtype=float)
        key = (t.shape, t.tobytes())
        last = self.__dict__.get("_last")
        if last is not None and last[0] == key:
            return last[1]
        values = self._evaluate(t)
        for value in values:
            value.setflags(write=False)
        object.__setattr__(self, "_last", (key, values))  # frozen: a cache, not a field
        return values

    def __getstate__(self) -> dict:
        """Pickled (a placement worker's answer) without the kept evaluation."""
        return {k: v for k, v in self.__dict__.items() if k != "_last"}

    def _evaluate(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        t = np.clip(t, 0.0, self.duration)
        starts, state = self._segment_starts()
        seg = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(starts) - 1)
        tau = t - starts[seg]
        s, v, a, j = _pulse(
            self.signs[seg],
            self.durations[seg],
            self._jerks()[seg],
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


def _transition_distance(v_a: float, v_b: float, a_max: float, j_max: float) -> float:
    """Distance covered while changing speed from v_a to v_b [m]."""
    t_j, t_a = _acceleration_phase(abs(v_b - v_a), a_max, j_max)
    return 0.5 * (v_a + v_b) * (2.0 * t_j + t_a)


def _check_limits(**values):
    for name, value in values.items():
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"time law: {name} must be a positive number, got {value}")


def sin2_plateau_law(
    length: float,
    caps: list[tuple[float, float, float]],
    *,
    a_max: float,
    j_max: float,
    v_max: float | None = None,
    scales: list[tuple[float, float]] | None = None,
) -> Sin2TimeLaw:
    """Rest-to-rest sin² profile under piecewise-constant speed caps.

    Args:
        length: distance along the path [m].
        caps: ((v, σ_start, σ_end), ...) contiguous stretches covering [0, length]
            with the highest speed allowed on each [m/s].
        a_max, j_max: limits of σ̈ and σ⃛.
        v_max: the speed asked for (reported; default the highest cap).
        scales: per stretch, (in, out) factors in (0, 1] on a_max and j_max for the
            speed changes it hosts (default 1): a stretch hosts the speed-up from a
            slower stretch before it (or from rest) at its start, and the slow-down
            to a slower one after it (or to rest) at its end.

    Returns:
        A Sin2TimeLaw whose speed never exceeds the cap of the stretch it is on:
        it slows down before a lower cap and speeds up after it, always inside
        the faster stretch. Stretches too short to reach their cap get a lower one.
    """
    _check_limits(length=length, a_max=a_max, j_max=j_max)
    speeds = [float(v) for v, _, _ in caps]
    edges = [float(caps[0][1])] + [float(end) for _, _, end in caps]
    for v in speeds:
        _check_limits(speed_cap=v)
    v_max = max(speeds) if v_max is None else v_max
    factors = [(1.0, 1.0)] * len(speeds) if scales is None else [tuple(f) for f in scales]

    def need(i: int, v: float) -> float:
        """Room plateau i needs at speed v for the transitions it hosts."""
        before = speeds[i - 1] if i > 0 else 0.0
        after = speeds[i + 1] if i + 1 < len(speeds) else 0.0
        f_in, f_out = factors[i]
        return (
            _transition_distance(before, v, a_max * f_in, j_max * f_in) if before < v else 0.0
        ) + (_transition_distance(v, after, a_max * f_out, j_max * f_out) if after < v else 0.0)

    for _ in range(10_000):  # speeds only decrease, so this settles
        # Merge neighbours with equal speed.
        i = 0
        while i + 1 < len(speeds):
            if speeds[i] == speeds[i + 1]:
                factors[i] = (factors[i][0], factors[i + 1][1])
                del speeds[i + 1], edges[i + 1], factors[i + 1]
            else:
                i += 1
        short = [
            i
            for i in range(len(speeds))
            if need(i, speeds[i]) > (edges[i + 1] - edges[i]) * (1 + 1e-9)
        ]
        if not short:
            break
        i = max(short, key=lambda k: speeds[k])  # fix the fastest first
        room = edges[i + 1] - edges[i]
        lower = max(speeds[i - 1] if i > 0 else 0.0, speeds[i + 1] if i + 1 < len(speeds) else 0.0)
        if need(i, lower) >= room and lower > 0.0:
            speeds[i] = lower
        else:  # the highest speed whose transitions fit (slightly below, for rounding)
            from scipy.optimize import brentq  # 0.3 s of import: only where a plateau is cut

            speeds[i] = brentq(
                lambda v, i=i, room=room: need(i, v) - room,
                lower,
                speeds[i],
                xtol=1e-15,
                rtol=1e-15,
            )
    else:
        raise RuntimeError("sin2_plateau_law: plateau speeds did not settle")

    signs, durations, jerks = [], [], []

    def transition(v_a: float, v_b: float, factor: float) -> None:
        t_j, t_a = _acceleration_phase(abs(v_b - v_a), a_max * factor, j_max * factor)
        sign = 1.0 if v_b > v_a else -1.0
        signs.extend([sign, 0.0, -sign])
        durations.extend([t_j, t_a, t_j])
        jerks.extend([j_max * factor] * 3)

    for i, v in enumerate(speeds):
        before = speeds[i - 1] if i > 0 else 0.0
        after = speeds[i + 1] if i + 1 < len(speeds) else 0.0
        if before < v:
            transition(before, v, factors[i][0])
        cruise = edges[i + 1] - edges[i] - need(i, v)
        signs.append(0.0)
        durations.append(max(cruise, 0.0) / v)
        jerks.append(j_max)
        if after < v:
            transition(v, after, factors[i][1])
    keep = np.asarray(durations) > 0.0
    plateaus = tuple((v, edges[i], edges[i + 1]) for i, v in enumerate(speeds))
    return Sin2TimeLaw(
        length,
        v_max,
        a_max,
        j_max,
        float(max(speeds)),
        np.asarray(signs)[keep],
        np.asarray(durations)[keep],
        plateaus,
        None if scales is None else np.asarray(jerks)[keep],
    )


def sin2_time_law(length: float, *, v_max: float, a_max: float, j_max: float) -> Sin2TimeLaw:
    """Plan the rest-to-rest sin²-jerk profile over ``length``.

    Args:
        length: distance along the path [m], > 0.
        v_max, a_max, j_max: limits of σ̇, σ̈, σ⃛ (peak of the sin² jerk), all > 0.

    Returns:
        The Sin2TimeLaw; its v_peak is below v_max when the path is too short.
    """
    _check_limits(length=length, v_max=v_max, a_max=a_max, j_max=j_max)
    return sin2_plateau_law(length, [(v_max, 0.0, length)], a_max=a_max, j_max=j_max)
