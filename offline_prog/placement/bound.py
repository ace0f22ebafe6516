"""A placement candidate's cycle time from its variants (``placement.variants``),
bounded below and estimated, without a time law or a collision check.

**Lower bound** (no plan the planner makes with its tool turns and branches is
faster): a seam takes at least, on each interval between the screen's σ samples,
max(Δσ / v̄, max_j |Δq_j| / q̇max_j), where v̄ is the most the path speed can be there
(the process speed, and the rest-to-rest ramps under the path acceleration:
v ≤ √(2aσ), v ≤ √(2a(L − σ))) and the joint term holds because a joint that turns by
Δq at q̇ ≤ q̇max needs Δq / q̇max (coarser samples only lower it). A seam at rest
(``entry: rest``) runs its approach and retract as the sin² law of their distance at the
approach speed (``job.approach``, or slower). A flying seam (the default) crosses its
ends at the process speed, so its seam stretch has no ramps, and its leads may take
the approach and retract over or shorten them (``job.approach.move_left_m``): whatever
the split, the tool runs at least the move's distance D from the move's far end to the
seam's end, on the straight move at ≤ the approach speed v_a and on the lead at ≤ the
process speed v, so an end takes at least D / max(v, v_a) (a lead that cannot be run
falls back to rest, which takes longer). A link is a rest-to-rest joint move: at
least the synchronised move at the joints' speed and acceleration limits
(``job.link_costs.ptp_time``), from home to the approach's start and from the retract's
end home; links between a job's seams count as zero. The least over every usable
variant (tool turn, branch) of each seam.

**Estimate** (a cheaper law, to rank candidates): on the variant the planner's first
attempt takes, the steady speed the joints allow, v ≤ q̇max_j / |q′_j| and
v ≤ √(q̈max_j / |q″_j|) under the same ramps, plus the approach, retract and links in
the given order at their lower bounds.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from offline_prog.config.process_speed import approach_speed
from offline_prog.job.approach import move_left_m
from offline_prog.job.link_costs import ptp_time
from offline_prog.placement.variants import SeamVariants
from offline_prog.timing.time_law import sin2_time_law


@dataclasses.dataclass(frozen=True)
class SeamTimes:
    """One seam's times at one placement.

    Attributes:
        bound_s: (A, 8) the seam's lower bound on each variant, approach and retract
            included [s] (∞ where the variant is not usable).
        estimate_s: the estimate on the planner's variant, approach and retract
            included [s] (NaN: none feasible).
        ends: (A, 8, 2, 6) the approach's start and the retract's end [rad]
            (controller axes).
        choice: the planner's (turn index, branch), or None.
        moves_s: the approach's and retract's durations [s].
    """

    bound_s: np.ndarray
    estimate_s: float
    ends: np.ndarray
    choice: tuple[int, int] | None
    moves_s: float


def _ramp_speeds(sigma: np.ndarray, *, v: float, a: float) -> np.ndarray:
    """(N − 1,) the highest path speed on each σ interval [m/s] (process speed and the
    rest-to-rest ramps under the path acceleration a)."""
    length = sigma[-1]
    rise = np.sqrt(2.0 * a * sigma[1:])
    fall = np.sqrt(2.0 * a * np.maximum(length - sigma[:-1], 0.0))
    return np.minimum(v, np.minimum(rise, fall))


def end_moves_s(seam, inputs, *, covered: tuple[float, float] = (0.0, 0.0)) -> float:
    """The approach's and retract's sin² durations [s] as ``job.approach`` times them
    (at ``config.process_speed.approach_speed``) for the seam's ``SeamConfig`` and its
    ``stages.Inputs``; ``covered`` [m]: how much of (approach, retract) a flying seam's
    leads run already (``job.approach.lead_covers_m``)."""
    motion, total = inputs.cell.motion, 0.0
    speed = approach_speed(inputs.cell, inputs.speed).v_m_s
    for spec, run in zip((seam.approach, seam.retract), covered, strict=True):
        d = move_left_m(spec, run)
        if spec.kind != "none" and d > 0.0:
            law = sin2_time_law(
                d, v_max=speed, a_max=motion.max_acceleration, j_max=motion.max_jerk
            )
            total += law.duration
    return total


def end_moves_bound_s(seam, inputs) -> float:
    """A lower bound [s] on the approach's and retract's durations with the leads that
    run them (module docstring): at rest their sin² laws (:func:`end_moves_s`), flying
    each move's distance at the faster of the process and the approach speed."""
    if inputs.cell.path.entry == "rest":
        return end_moves_s(seam, inputs)
    fastest = max(inputs.speed.v_m_s, approach_speed(inputs.cell, inputs.speed).v_m_s)
    moves = [
        spec.distance_mm * 1e-3 for spec in (seam.approach, seam.retract) if spec.kind != "none"
    ]
    return sum(moves) / fastest


def seam_times(variants: SeamVariants, seam_inputs, seam) -> SeamTimes:
    """Bound and estimate of one seam (its Inputs: the seam's speed; its SeamConfig)."""
    robot, motion = seam_inputs.robot, seam_inputs.cell.motion
    tcp = motion.speed_reference == "tcp"
    sigma = variants.sigma
    q_c = robot.controller_joints(variants.q)  # (A, 8, N + 2, 6)
    seam_q = q_c[:, :, 1:-1]
    ds = np.diff(sigma)
    joint = (np.abs(np.diff(seam_q, axis=2)) / robot.qd_max).max(axis=-1)  # (A, 8, N − 1)
    speed = seam_inputs.speed.v_m_s  # the seam's own (config.process_speed)
    v_up = _ramp_speeds(sigma, v=speed, a=motion.max_acceleration)
    flying = seam_inputs.cell.path.entry != "rest"  # its ends crossed at the speed
    path = ds / (np.full_like(ds, speed) if flying else v_up) if tcp else np.zeros_like(ds)
    with np.errstate(invalid="ignore"):
        seam_s = np.maximum(joint, path).sum(axis=-1) + end_moves_bound_s(seam, seam_inputs)
    bound = np.where(variants.usable, seam_s, np.inf)
    choice = variants.planner_choice()
    estimate, moves = math.nan, end_moves_s(seam, seam_inputs)
    if choice is not None:
        estimate = _steady_time(seam_q[choice], sigma, v_up, robot, tcp=tcp) + moves
    return SeamTimes(bound, estimate, q_c[:, :, [0, -1]], choice, moves)


def _steady_time(q_c: np.ndarray, sigma: np.ndarray, v_up, robot, *, tcp: bool) -> float:
    """∫ dσ / v [s] with v the steady speed the joints allow on the path q_c (N, 6)
    (controller axes) under the ramps v_up (N − 1,)."""
    ds = np.diff(sigma)
    d1 = np.diff(q_c, axis=0) / ds[:, None]  # q′ [rad/m] between samples
    d2 = np.zeros_like(d1)
    d2[1:] = np.diff(d1, axis=0) / ((ds[1:] + ds[:-1]) / 2)[:, None]
    with np.errstate(divide="ignore"):
        by_speed = np.min(robot.qd_max / np.abs(d1), axis=1)
        by_acceleration = np.min(np.sqrt(robot.qdd_max / np.abs(d2)), axis=1)
    v = np.minimum(by_speed, by_acceleration)
    if tcp:
        v = np.minimum(v, v_up)
    return float(np.sum(ds / v))


def job_times(times: list[SeamTimes], q_home_c: np.ndarray, robot) -> tuple[float, float]:
    """(lower bound, estimate) of a job's cycle time [s], home to home, from its seams'
    times (in the given order) and home (6,) in the controller's axes [rad]."""
    qd, qdd = robot.qd_max, robot.qdd_max
    if len(times) == 1:
        t = times[0]
        links = ptp_time(q_home_c, t.ends[:, :, 0], qd, qdd) + ptp_time(
            t.ends[:, :, 1], q_home_c, qd, qdd
        )
        bound = float(np.min(np.where(np.isfinite(t.bound_s), t.bound_s + links, np.inf)))
    else:
        seams = sum(float(np.min(t.bound_s)) for t in times)
        home = [
            np.where(np.isfinite(t.bound_s)[..., None], ptp_time(q_home_c, t.ends, qd, qdd), np.inf)
            for t in times
        ]
        bound = seams + 2.0 * min(float(np.min(h)) for h in home)
    if any(t.choice is None for t in times):
        return bound, math.nan
    estimate, q_now = 0.0, q_home_c
    for t in times:
        ends = t.ends[t.choice]
        estimate += float(ptp_time(q_now, ends[0], qd, qdd)) + t.estimate_s
        q_now = ends[1]
    estimate += float(ptp_time(q_now, q_home_c, qd, qdd))
    return bound, estimate
