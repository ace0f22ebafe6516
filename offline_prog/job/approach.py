"""Approach and retract: the straight moves that bring the tool onto a seam and off it.

The part moves past the fixed tool, so "the tool approaches along −n" means the tool
frame T slides in the part frame P along a straight line that ends (approach) or starts
(retract) at the seam's end frame F = X_PF(σ_end):

    p_PT(δ) = p_PF − δ·u,   R_PT = R_PF (constant),   δ ∈ [0, d],

with u = n (y of F, into the surface) for ``normal`` and u = ±t (x of F; − before the
start, + after the end) for ``tangent``. The flange follows from the paper's chain
X_IE = X_IT · X_PT⁻¹ · X_PE: with R_IE constant, p_IE(δ) = p_IE(0) + δ·R_IP·u, R_IP =
R_IE·R_PE⁻¹ (the part moves by δu in I while the tool stays put). The move is timed by
the same sin² law as the seam (speed: ``config.process_speed.approach_speed``,
``motion.approach_speed`` else the seam's process speed) and solved by analytic IK on the
seam's branch, continuous with the seam's end configuration.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.config.cell import ApproachConfig
from offline_prog.config.process_speed import approach_speed
from offline_prog.errors import Failure, PlanFailedError, PlanFailure
from offline_prog.joints.path_ik import base_poses, branch_results
from offline_prog.path.lead import path_ends, unwrapped
from offline_prog.robot.model import RobotModel
from offline_prog.timing.time_law import sin2_time_law
from offline_prog.timing.trajectory import sample_times

TWO_PI = 2.0 * np.pi
# A move whose joints would exceed their speed limits is re-timed slower by the excess
# times this margin, at most this many times.
SLOWDOWN_MARGIN, MAX_SLOWDOWNS = 1.05, 4
# The shortest approach or retract left where a flying seam's lead runs most of it [m]:
# a robot programmer writes no shorter move (the lead ends that near the move's start).
MIN_MOVE_M = 1e-3


@dataclasses.dataclass(frozen=True)
class CartesianMove:
    """An approach or a retract, sampled.

    Attributes:
        kind: "approach" | "retract"; seam: the seam's name; distance_m: d [m].
        t: (N,) time from the move's start [s].
        q: (N, 6) joint positions [rad] (URDF order), continuous with the seam.
        delta: (N,) δ(t): the tool's distance from the seam's end frame [m].
        p_IE: (N, 3) flange positions in I [m]; R_IE: (3, 3) the constant flange rotation.
        p_PT: (N, 3) the tool point in P [m]; R_PT: (3, 3) its constant rotation.
    """

    kind: str
    seam: str
    distance_m: float
    t: np.ndarray
    q: np.ndarray
    delta: np.ndarray
    p_IE: np.ndarray
    R_IE: np.ndarray
    p_PT: np.ndarray
    R_PT: np.ndarray

    @property
    def duration(self) -> float:
        return float(self.t[-1])


def offset_direction(spec: ApproachConfig, kind: str, R_PF: np.ndarray) -> np.ndarray:
    """(3,) u in P: the tool at p_PF − δ·u is off the seam's end by δ."""
    if spec.kind == "normal":
        return R_PF[:, 1]  # n: the tool backs off against the pressing direction
    sign = 1.0 if kind == "approach" else -1.0  # before the start / after the end
    return sign * R_PF[:, 0]


def cartesian_move(
    robot: RobotModel,
    *,
    X_IB,
    kind: str,
    seam: str,
    spec: ApproachConfig,
    p_PF: np.ndarray,
    R_PF: np.ndarray,
    p_IE: np.ndarray,
    R_IE: np.ndarray,
    R_PE: np.ndarray,
    q_seam: np.ndarray,
    branch: int,
    speed: float,
    a_max: float,
    j_max: float,
    rate_hz: float,
) -> CartesianMove | None:
    """The approach to (``kind="approach"``) or retract from a seam end, or None for
    ``kind: none`` or a zero distance.

    Args:
        p_PF, R_PF: (3,), (3, 3) the process frame F at the seam's end, in P [m].
        p_IE, R_IE: (3,), (3, 3) the flange at that end, in I [m].
        R_PE: (3, 3) the flange's rotation in P.
        q_seam: (6,) the seam's joints at that end [rad]; branch: its IK branch.
        speed, a_max, j_max: the sin² law's limits [m/s, m/s², m/s³].

    Raises:
        PlanFailedError: the move leaves the reach or the joint limits on the branch.
    """
    d = spec.distance_mm * 1e-3
    if spec.kind == "none" or d <= 0.0:
        return None
    u_P = offset_direction(spec, kind, R_PF)
    for _ in range(MAX_SLOWDOWNS):
        law = sin2_time_law(d, v_max=speed, a_max=a_max, j_max=j_max)
        t = sample_times(law.duration, rate_hz)
        travelled = law(t)[0]
        delta = d - travelled if kind == "approach" else travelled
        R_IP = R_IE @ R_PE.T
        p_IE_t = p_IE + delta[:, None] * (R_IP @ u_P)
        X_BE = base_poses(X_IB, p_IE_t, np.broadcast_to(R_IE, (len(t), 3, 3)))
        result = branch_results(robot, X_BE)[branch]
        if len(t) < 3 or not np.isfinite(result.q).all():
            break
        qd = robot.controller_joints(np.gradient(result.q, t, axis=0))
        ratio = float((np.abs(qd) / robot.qd_max).max())
        if ratio <= 1.0:
            break
        speed, a_max = speed / (ratio * SLOWDOWN_MARGIN), a_max / (ratio * SLOWDOWN_MARGIN) ** 2
    end = -1 if kind == "approach" else 0  # the sample at the seam
    if not np.isfinite(result.q).all():
        reason, failure = result.reason or "out of reach", result.kind or Failure.OUT_OF_REACH
        _fail(kind, seam, t, result.sample, f"{reason} on the seam's branch", failure)
    # The same 2π turns as the seam's joints at the shared end.
    q = result.q + TWO_PI * np.round((q_seam - result.q[end]) / TWO_PI)
    if np.abs(q[end] - q_seam).max() > 1e-6:
        _fail(
            kind,
            seam,
            t,
            len(t) - 1 if end else 0,
            "singularity (the configuration flips)",
            Failure.SINGULARITY,
        )
    q_c = robot.controller_joints(q)
    outside = (q_c < robot.q_lower) | (q_c > robot.q_upper)
    if outside.any():
        i, joint = np.argwhere(outside)[0]
        _fail(kind, seam, t, int(i), f"joint limit on axis {joint + 1}", Failure.JOINT_LIMIT)
    return CartesianMove(
        kind, seam, d, t, q, delta, p_IE_t, R_IE, p_PF - delta[:, None] * u_P, R_PF
    )


def _fail(kind: str, seam: str, t: np.ndarray, i: int, reason: str, failure: Failure) -> None:
    message = f"{reason} ({kind} of seam {seam}, t = {t[i]:.3f} s into it)"
    raise PlanFailedError(PlanFailure(failure, 0.0, float(t[i]), message))


def seam_ends(
    inputs, flange, length_m: float, q_ends: np.ndarray, branch: int, seam
) -> tuple[CartesianMove | None, CartesianMove | None]:
    """The approach to a seam's first sample and the retract from its last (a flying
    seam's: its lead-in's first and its lead-out's last, ``path.lead``).

    Args:
        inputs: the seam's ``stages.Inputs``; seam: its ``SeamConfig``.
        flange: the seam's flange path as run; length_m: its path length [m].
        q_ends: (2, 6) joints at the path's first and last σ [rad]; branch: their IK
            branch.

    Raises:
        PlanFailedError: a move the robot cannot make (kind, seam and why).
    """
    motion = inputs.cell.motion
    R_PE = inputs.X_PE.rotation().matrix()
    ends = flange(np.array(path_ends(flange)))  # a flying seam's: its leads' far ends
    covered = lead_covers_m(flange, seam)
    moves = []
    for kind, i, spec, run in (
        ("approach", 0, seam.approach, covered[0]),
        ("retract", -1, seam.retract, covered[1]),
    ):
        spec = dataclasses.replace(spec, distance_mm=move_left_m(spec, run) * 1e3)
        moves.append(
            cartesian_move(
                inputs.robot,
                X_IB=inputs.X_IB,
                kind=kind,
                seam=seam.name,
                spec=spec,
                p_PF=ends.p_PF[i],
                R_PF=ends.R_PF[i],
                p_IE=ends.p_IE[i],
                R_IE=ends.R_IE[i],
                R_PE=R_PE,
                q_seam=q_ends[i],
                branch=branch,
                speed=approach_speed(inputs.cell, inputs.speed).v_m_s,
                a_max=motion.max_acceleration,
                j_max=motion.max_jerk,
                rate_hz=motion.sample_rate_hz,
            )
        )
    return moves[0], moves[1]


def lead_covers_m(flange, seam) -> tuple[float, float]:
    """(approach, retract) [m]: how much of each move a flying seam's lead already runs
    (0 at rest): a normal move's by the lead's lift, a tangent one's by the lead's reach
    along the seam's tangent at that end.

    Args:
        flange: the seam's flange path as run (a ``path.lead.LeadPath`` when flying).
        seam: its ``SeamConfig`` (the kinds of its approach and retract).
    """
    lifts = getattr(flange, "lifts_m", (0.0, 0.0))
    inner = unwrapped(flange)
    at_seam = inner(np.array([0.0, inner.length]))
    far = flange(np.array(path_ends(flange)))  # the leads' far ends
    covered = []
    for i, spec in enumerate((seam.approach, seam.retract)):
        if spec.kind == "normal":
            covered.append(float(lifts[i]))
        elif spec.kind == "tangent":
            t_P = at_seam.R_PF[i][:, 0]
            covered.append(abs(float((far.p_PF[i] - at_seam.p_PF[i]) @ t_P)))
        else:
            covered.append(0.0)
    return covered[0], covered[1]


def move_left_m(spec: ApproachConfig, covered: float) -> float:
    """The distance [m] the approach (retract) ``spec`` still runs after a lead that
    covers ``covered`` [m] of it: 0 where less than MIN_MOVE_M is left."""
    left = spec.distance_mm * 1e-3 - covered
    return left if covered <= 0.0 or left >= MIN_MOVE_M else 0.0


def plan_ends(inputs, plan, seam) -> tuple[CartesianMove | None, CartesianMove | None]:
    """:func:`seam_ends` of a timed seam plan (``job.records.Plan``)."""
    q_ends = np.array([(plan.lead_in or plan.joints).q[0], (plan.lead_out or plan.joints).q[-1]])
    return seam_ends(inputs, plan.flange, plan.path.length, q_ends, plan.joints.branch, seam)


def other_branches(results: list, chosen: int, most: int) -> list:
    """Up to ``most`` feasible IK branch results other than ``chosen``, largest
    joint-limit margin first: the branches a seam direction offers besides its best."""
    others = (b for b in results if b.feasible and b.branch != chosen)
    return sorted(others, key=lambda b: -b.margin_rad)[:most]
