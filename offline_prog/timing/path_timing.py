"""The process time law under the robot's joint limits, as motion.time_law asks: one
entry point (``time_path``) takes the path's limits (``PathLimits``) and returns one
record (``PathTiming``) whatever the law.

``time_optimal``: TOPP-RA (``timing.time_optimal``) under the joint velocity and
acceleration limits, the process speed cap and the path acceleration, with the
steady-speed joint jerk limit as a speed limit curve; then the jerk stage
(``timing.jerk_stage``), and the time-averaged profile (``timing.filtered_stage``),
keeping for each intent the better of the two that holds every limit (the faster for
``cycle_time``; for ``constant_speed`` the one holding the process speed longer). Two
shortcuts keep the solve short: TOPP-RA is solved once when its profile already keeps
the steady jerk limit (exact), and the averaged profile's rounds are skipped when
bounds show it cannot beat the staircase by more than SKIP_SHARE of the cycle or
HELD_TIE of the held length.
``sin2``: the paper's law with plateaus lowered where the joints need it
(``timing.joint_timing``).
"""

from __future__ import annotations

import dataclasses
import functools
import time

import numpy as np

from offline_prog.constants import ProcessIntent, TimeLaw
from offline_prog.errors import Failure, PlanFailedError, PlanFailure
from offline_prog.robot.model import RobotModel
from offline_prog.timing.filtered_law import FilteredTimeLaw
from offline_prog.timing.filtered_stage import filtered_timing
from offline_prog.timing.jerk_stage import jerk_limited_law, steady_jerk_limit
from offline_prog.timing.joint_timing import JointRates, retime
from offline_prog.timing.limit_use import Slowdown
from offline_prog.timing.speed_hold import SpeedHold
from offline_prog.timing.time_law import Sin2TimeLaw, sin2_time_law
from offline_prog.timing.time_optimal import ToppProfile, topp_profile

HELD_TIE = 1e-3  # held shares closer than this tie
# The averaged profile is skipped when it cannot cut the staircase's cycle time by more
# than this share (nor hold the process speed longer, HELD_TIE).
SKIP_SHARE = 1e-3
TIME_INVERSION_POINTS = 20001  # σ ↦ t on the nominal law for a failure's time


@dataclasses.dataclass(frozen=True)
class PathLimits:
    """What the time laws need of one path: its length and process limits (the path
    parameter's speed, acceleration and jerk, as motion: asks) and the robot's joint
    limits on the controller axes.

    Attributes:
        length: the time-law parameter's length [m].
        v_process, a_max, j_max: the process speed [m/s] and the path's acceleration
            [m/s²] and jerk [m/s³] caps.
        qd_max, qdd_max, jerk_max: (6,) joint speed [rad/s], acceleration [rad/s²] and
            jerk [rad/s³] limits (controller axes).
    """

    length: float
    v_process: float
    a_max: float
    j_max: float
    qd_max: np.ndarray
    qdd_max: np.ndarray
    jerk_max: np.ndarray

    @classmethod
    def of(
        cls, robot: RobotModel, length: float, *, v_process: float, a_max: float, j_max: float
    ) -> PathLimits:
        """The limits of a path of ``length`` [m] run at the process speed ``v_process``
        [m/s] under the path caps ``a_max``, ``j_max`` [m/s², m/s³], on this robot."""
        return cls(length, v_process, a_max, j_max, robot.qd_max, robot.qdd_max, robot.jerk_limits)

    @functools.cached_property
    def nominal(self) -> Sin2TimeLaw:
        """The process sin² law over the path before any joint limit (paper §4), built
        once per limits: the sample count, the sin² plateaus and the times of failures
        read it."""
        return sin2_time_law(self.length, v_max=self.v_process, a_max=self.a_max, j_max=self.j_max)


@dataclasses.dataclass(frozen=True)
class PathTiming:
    """The joint-feasible time law of one path, the same record for every law.

    Attributes:
        law: the time law to use (σ ↦ σ, σ̇, σ̈, σ⃛).
        law_kind, intent: the law that made it and the process intent it served
            (``intent`` is None for sin2, which has one intent).
        reductions: ((σ_start, σ_end, speed), ...) stretches below the process speed
            [m, m, m/s].
        a_scale: factor on the path acceleration and jerk in the softest ramp (1: none).
        feasible: every joint limit the law keeps holds (sin2: speed and acceleration;
            time_optimal: speed, acceleration and jerk).
        worst: (joint index, σ, use) of the largest limit use on the final samples.
        slowdowns: every stretch below the process speed with its limiting joint and
            constraint (time_optimal; empty for sin2).
        topp: TOPP-RA's profile with the steady jerk limit (time_optimal; None for sin2).
        topp_plain_s: TOPP-RA's duration without the steady jerk limit [s]
            (time_optimal; None for sin2).
        speed_held: (share of the feasible length held at the process speed, feasible
            share of the path) (time_optimal; None for sin2).
        solve_s: wall time of the time-optimal solve [s] (time_optimal; None for sin2).
    """

    law: Sin2TimeLaw | FilteredTimeLaw
    law_kind: TimeLaw
    intent: ProcessIntent | None
    reductions: tuple[tuple[float, float, float], ...]
    a_scale: float
    feasible: bool
    worst: tuple[int, float, float]
    slowdowns: tuple[Slowdown, ...] = ()
    topp: ToppProfile | None = None
    topp_plain_s: float | None = None
    speed_held: tuple[float, float] | None = None
    solve_s: float | None = None


def time_path(
    rates: JointRates, limits: PathLimits, law: TimeLaw, intent: ProcessIntent
) -> PathTiming:
    """The time law under the joint limits, one entry point for every law: TOPP-RA plus
    the jerk stage (``TimeLaw.TIME_OPTIMAL``, for ``intent``), or sin² plateaus
    (``TimeLaw.SIN2``, ``joint_timing.retime``; ``intent`` plays no part).

    Args:
        rates: q, q′, q″ on a σ grid over [0, length] (controller axes).
        limits: the path's length and limits and the joints' limits.
        law, intent: motion.time_law and motion.process (enums, config/checks.py).
    """
    law, intent = TimeLaw(law), ProcessIntent(intent)
    if law is TimeLaw.SIN2:
        r = retime(rates, limits.nominal, qd_max=limits.qd_max, qdd_max=limits.qdd_max)
        return PathTiming(r.law, law, None, r.reductions, r.a_scale, r.feasible, r.worst)
    t = _time_optimal(rates, limits, intent)
    return PathTiming(
        t.law,
        law,
        intent,
        t.reductions,
        t.a_scale,
        t.feasible,
        t.worst,
        t.slowdowns,
        t.topp,
        t.topp_plain_s,
        t.speed_held,
        t.solve_s,
    )


def _time_optimal(rates: JointRates, limits: PathLimits, process: ProcessIntent):
    """TOPP-RA, the jerk stage and the averaged profile (module docstring)."""
    start = time.perf_counter()
    joint = (limits.qd_max, limits.qdd_max, limits.jerk_max)
    topp = dict(
        qd_max=limits.qd_max, qdd_max=limits.qdd_max, v_cap=limits.v_process, a_path=limits.a_max
    )
    plain = topp_profile(rates, **topp)
    steady = steady_jerk_limit(rates, joint)
    # Where the plain profile already keeps the steady jerk limit it is the answer with
    # it too (TOPP-RA's profile is the highest feasible one): no second solve.
    profile = plain
    if not plain.ok or np.any(plain.speed > np.interp(plain.sigma, rates.sigma, steady)):
        profile = topp_profile(rates, v_steady=steady, **topp)
    if not profile.ok:
        sigma = profile.failed_at_m
        reason = (
            f"joint speed/acceleration limits: TOPP-RA found no parameterization ({profile.reason})"
        )
        nominal = limits.nominal
        t_grid = np.linspace(0.0, nominal.duration, TIME_INVERSION_POINTS)
        t = float(np.interp(sigma, nominal(t_grid)[0], t_grid))  # on the nominal law
        raise PlanFailedError(PlanFailure(Failure.JOINT_RATE_LIMIT, sigma, t, reason))
    path = dict(v_process=limits.v_process, a_max=limits.a_max, j_max=limits.j_max)

    held = SpeedHold(rates, limits=joint, **path)
    timing = jerk_limited_law(rates, profile, limits=joint, process=process, **path)
    speed_held = held(timing.law)  # measured once per law: the choice and the report
    if not (timing.feasible and _cannot_win(timing, speed_held, profile, limits, process, held)):
        filtered = filtered_timing(rates, profile, limits=joint, **path)
        if filtered is not None:
            filtered_held = held(filtered.law)
            if not timing.feasible or _better(filtered, filtered_held, timing, speed_held, process):
                timing = dataclasses.replace(filtered, process=process, topp=profile)
                speed_held = filtered_held
    return dataclasses.replace(
        timing,
        topp_plain_s=plain.duration,
        speed_held=speed_held,
        solve_s=time.perf_counter() - start,
    )


def without_joint_limits(law, time_law: TimeLaw) -> tuple[float, bool]:
    """(cycle time [s], whether the process speed is reached) of the law with no joint
    limit, from the path's limits alone (``law``: any time law over the path, its
    length, v_max, a_max, j_max): the sin² law's for sin2; for time_optimal the fastest
    rest-to-rest motion under those limits (ruckig), which the averaged profile
    reaches where no joint limit binds (L/v + v/a + a/j on a long path)."""
    if TimeLaw(time_law) is TimeLaw.SIN2:
        nominal = sin2_time_law(law.length, v_max=law.v_max, a_max=law.a_max, j_max=law.j_max)
        return nominal.duration, not nominal.reduced
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    inp, trajectory = InputParameter(1), Trajectory(1)
    inp.current_position, inp.target_position = [0.0], [law.length]
    inp.max_velocity, inp.max_acceleration = [law.v_max], [law.a_max]
    inp.max_jerk = [law.j_max]
    result = Ruckig(1).calculate(inp, trajectory)
    assert result in (Result.Working, Result.Finished), result
    top = trajectory.at_time(0.5 * trajectory.duration)[1][0]  # rest to rest: the middle
    return float(trajectory.duration), bool(top >= law.v_max * (1.0 - 1e-9))


def _cannot_win(
    staircase, staircase_held, profile, limits: PathLimits, process: str, held: SpeedHold
) -> bool:
    """The averaged profile (``filtered_stage``) cannot beat the staircase, by bounds:
    its profile is TOPP-RA's under tighter limits, so never above ``profile``, and it
    runs the profile's duration plus its window T = a/j. Its speed is an average of
    the profile's over T, so it can hold the process speed only within v·T of where
    the profile does (``held.upper_bound``; staircase_held: ``held`` of the staircase)."""
    window = limits.a_max / limits.j_max
    if staircase.law.duration > (profile.duration + window) * (1.0 + SKIP_SHARE):
        return False
    if process == ProcessIntent.CYCLE_TIME:
        return True
    bound = held.upper_bound(profile.sigma, profile.speed, reach=limits.v_process * window)
    return staircase_held[0] >= bound - HELD_TIE


def _better(filtered, filtered_held, staircase, staircase_held, process: str) -> bool:
    """The averaged profile beats the staircase for the intent: shorter for
    ``cycle_time``; for ``constant_speed`` it holds the process speed over more of the
    feasible length (then: shorter). Its speed follows the joints' limit through a
    slowdown where the staircase holds one steady lower speed; both ramp only where a
    limit forces it (``*_held``: SpeedHold of each law)."""
    if process == ProcessIntent.CONSTANT_SPEED:
        ours, theirs = filtered_held[0], staircase_held[0]
        if abs(ours - theirs) > HELD_TIE:
            return ours > theirs
    return filtered.law.duration < staircase.law.duration
