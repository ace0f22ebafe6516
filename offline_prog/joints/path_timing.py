"""The process time law under the robot's joint limits, as motion.time_law asks.

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
import time

import numpy as np

from offline_prog.errors import Failure, PlanFailedError, PlanFailure
from offline_prog.robot.model import RobotModel
from offline_prog.timing.filtered_stage import filtered_timing
from offline_prog.timing.jerk_stage import jerk_limited_law, steady_jerk_limit
from offline_prog.timing.joint_timing import JointRates, retime
from offline_prog.timing.speed_hold import SpeedHold
from offline_prog.timing.time_law import Sin2TimeLaw, sin2_time_law
from offline_prog.timing.time_optimal import topp_profile

HELD_TIE = 1e-3  # held shares closer than this tie
# The averaged profile is skipped when it cannot cut the staircase's cycle time by more
# than this share (nor hold the process speed longer, HELD_TIE).
SKIP_SHARE = 1e-3
TIME_INVERSION_POINTS = 20001  # σ ↦ t on the nominal law for a failure's time


def path_timing(
    robot: RobotModel, rates: JointRates, nominal: Sin2TimeLaw, time_law: str, process: str
):
    """The time law under the joint limits: TOPP-RA plus the jerk stage, or sin²
    plateaus (``joint_timing.retime``)."""
    if time_law == "sin2":
        return retime(rates, nominal, qd_max=robot.qd_max, qdd_max=robot.qdd_max)
    start = time.perf_counter()
    limits = (robot.qd_max, robot.qdd_max, robot.jerk_limits)
    topp = dict(
        qd_max=robot.qd_max, qdd_max=robot.qdd_max, v_cap=nominal.v_max, a_path=nominal.a_max
    )
    plain = topp_profile(rates, **topp)
    steady = steady_jerk_limit(rates, limits)
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
        t_grid = np.linspace(0.0, nominal.duration, TIME_INVERSION_POINTS)
        t = float(np.interp(sigma, nominal(t_grid)[0], t_grid))  # on the nominal law
        raise PlanFailedError(PlanFailure(Failure.JOINT_RATE_LIMIT, sigma, t, reason))
    path = dict(v_process=nominal.v_max, a_max=nominal.a_max, j_max=nominal.j_max)

    held = SpeedHold(rates, limits=limits, **path)
    timing = jerk_limited_law(rates, profile, limits=limits, process=process, **path)
    speed_held = held(timing.law)  # measured once per law: the choice and the report
    if not (timing.feasible and _cannot_win(timing, speed_held, profile, nominal, process, held)):
        filtered = filtered_timing(rates, profile, limits=limits, **path)
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


def without_joint_limits(law, time_law: str) -> tuple[float, bool]:
    """(cycle time [s], whether the process speed is reached) of the law with no joint
    limit, from the path's limits alone (``law``: any time law over the path, its
    length, v_max, a_max, j_max): the sin² law's for sin2; for time_optimal the fastest
    rest-to-rest motion under those limits (ruckig), which the averaged profile
    reaches where no joint limit binds (L/v + v/a + a/j on a long path)."""
    if time_law == "sin2":
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


def _cannot_win(staircase, staircase_held, profile, nominal, process: str, held: SpeedHold) -> bool:
    """The averaged profile (``filtered_stage``) cannot beat the staircase, by bounds:
    its profile is TOPP-RA's under tighter limits, so never above ``profile``, and it
    runs the profile's duration plus its window T = a/j. Its speed is an average of
    the profile's over T, so it can hold the process speed only within v·T of where
    the profile does (``held.upper_bound``; staircase_held: ``held`` of the staircase)."""
    window = nominal.a_max / nominal.j_max
    if staircase.law.duration > (profile.duration + window) * (1.0 + SKIP_SHARE):
        return False
    if process == "cycle_time":
        return True
    bound = held.upper_bound(profile.sigma, profile.speed, reach=nominal.v_max * window)
    return staircase_held[0] >= bound - HELD_TIE


def _better(filtered, filtered_held, staircase, staircase_held, process: str) -> bool:
    """The averaged profile beats the staircase for the intent: shorter for
    ``cycle_time``; for ``constant_speed`` it holds the process speed over more of the
    feasible length (then: shorter). Its speed follows the joints' limit through a
    slowdown where the staircase holds one steady lower speed; both ramp only where a
    limit forces it (``*_held``: SpeedHold of each law)."""
    if process == "constant_speed":
        ours, theirs = filtered_held[0], staircase_held[0]
        if abs(ours - theirs) > HELD_TIE:
            return ours > theirs
    return filtered.law.duration < staircase.law.duration
