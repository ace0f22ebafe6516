"""A UR job program a programmer can edit: a seam run as ``movel`` / ``movep`` with
blend radii, the flow set per point.

Frames: URScript moves the active TCP to a pose in the base. The program makes the
part P on the flange its TCP (``set_tcp`` of the pose variable named after
``part.name``) and writes every target as the part's pose in the fixed tool's feature
(``pose_trans`` of the pose variable named after ``tool.name`` with X_TP), so the
controller interpolates P in B while the tool stands still: the flange style of
``export.points`` (the tool's curve on the part is checked, not only the straight line
of the poses). The nominal values of the two variables are in ``<name>_frames.script``
only.

Points: the planned samples (``export.run_samples``) from the approach's start to the
retract's end (the job's rows there, the seam's densified samples on it); the seam's
points from the writer's ``PointRule`` (half the path tolerance), the approach's start,
the seam's ends, the retract's end and the sample at which each I/O event is set
(its ``t_s``) are points; motions are split at planned samples until each holds half
the tolerance, then motions shorter than ``merge.MIN_MOTION_M`` merged where the plan
allows (``merge.PathCheck``).

Blends: each inner point gets the largest radius r whose blend keeps the tool within
what the tolerance leaves beyond the motions' own deviation: the blend leaves the
motions' line by at most r·|u_in − u_out| / 2 = r·sin(θ/2) (u the motions' directions,
θ the turn at the point; the blend curve stays in the triangle of the corner and the
two points r from it), and the motions' turn by at most r·|w_in − w_out| / 2 (w the
part's turn per metre of each motion; the tool moves by that times its distance from
P's origin); r is at most ``BLEND_SHARE`` of each adjacent motion (UR skips a blend
that overlaps the next). The approach's start and the retract's end are stops (r = 0).
This is a model of UR's blend, not UR's own: tests/export/test_ur_moves replays it.

Speeds: ``v`` of each move is the plan's mean speed of the TCP (P's origin) between its
points, ``a`` the plan's change of that speed into the move over its duration (at least
``A_MIN_M_S2``). I/O: a statement before a move runs as the move before it blends
(within r of its point): the process output's event at the point where the plan sets
it; the flow written per point at the plan's value there (``ao`` column) when it
changed by ``urscript.ANALOG_STEP_V`` or ``ANALOG_STEP_SHARE`` of its value.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.export.merge import PathCheck
from offline_prog.export.record import SeamRun
from offline_prog.export.run_samples import run_samples

MOVE_MODES = ("movel", "movep")
A_MIN_M_S2 = 0.1  # the slowest acceleration written (a speed held: UR wants one)
BLEND_SHARE = 0.45  # a blend radius at most this share of each adjacent motion
V_MIN_M_S = 1e-3  # a move's speed at least this (a pure reorientation)


@dataclasses.dataclass(frozen=True)
class UrMoves:
    """A seam run as UR moves through planned samples.

    Attributes:
        t: (N,) the samples' job time [s]; X_BP: (N, 4, 4) the part P in the base B.
        points: (K,) sample indices of the moves' ends (the first: where the run starts).
        radius_m: (K,) blend radius at each point [m] (0: the robot stops there).
        speed_m_s: (K,) the speed of the move to each point [m/s] (the first unused).
        accel_m_s2: (K,) the acceleration of the move to each point [m/s²].
        deviation_m: the largest distance of the tool's planned samples from the
            motions between the points, blends not counted [m] (≤ half the tolerance).
    """

    t: np.ndarray
    X_BP: np.ndarray
    points: np.ndarray
    radius_m: np.ndarray
    speed_m_s: np.ndarray
    accel_m_s2: np.ndarray
    deviation_m: float


def ur_moves(job, run: SeamRun, *, chord_tol_m: float, angle_tol_rad: float) -> UrMoves:
    """The run's moves (see the module docstring) within the path tolerances [m, rad]."""
    samples = run_samples(job.job, run)
    t, X_BP, seam_points = samples.t, samples.X_BP, samples.seam_points
    first, last = samples.first, samples.last
    check = PathCheck(X_BP, job.job.X_BT, 0.5 * chord_tol_m, 0.5 * angle_tol_rad)
    events = {min(int(np.searchsorted(t, e.t_s - 1e-12)), len(t) - 1) for e in run.events}
    pinned = {0, first, last, len(t) - 1} | events
    points = _split(check, sorted(set(seam_points) | pinned))
    points = np.array(check.merge(points, pinned))
    d, _ = check.deviations(points[:-1], points[1:])
    p = X_BP[points, :3, 3]
    length = np.linalg.norm(np.diff(p, axis=0), axis=1)  # (K-1,)
    duration = np.maximum(np.diff(t[points]), 1e-9)
    speed = np.concatenate([[0.0], np.maximum(length / duration, V_MIN_M_S)])
    accel = np.concatenate([[0.0], np.abs(np.diff(speed)) / duration])
    accel = np.maximum(accel, A_MIN_M_S2)
    radius = _blend_radii(
        X_BP[points],
        job.job.X_BT,
        budget_m=chord_tol_m - np.maximum(np.r_[0.0, d], np.r_[d, 0.0]),
        budget_rad=0.5 * angle_tol_rad,
    )
    return UrMoves(t, X_BP, points, radius, speed, accel, float(d.max(initial=0.0)))


def _split(check: PathCheck, points: list[int]) -> list[int]:
    """The points with planned samples added until each motion holds the check's
    tolerances (halving a motion's samples, all motions of a round at once)."""
    i, j = np.array(points[:-1]), np.array(points[1:])
    ends = [np.array(points[:1])]
    while len(i):
        d, a = check.deviations(i, j)
        split = (j - i > 1) & ((d > check.chord_tol_m) | (a > check.angle_tol_rad))
        ends.append(j[~split])
        mid = (i[split] + j[split]) // 2
        i, j = np.concatenate([i[split], mid]), np.concatenate([mid, j[split]])
    return sorted(int(k) for k in np.concatenate(ends))


def _blend_radii(X_BP: np.ndarray, X_BT: np.ndarray, *, budget_m, budget_rad) -> np.ndarray:
    """(K,) blend radius [m] at each point X_BP (K, 4, 4) (see the module docstring);
    ``budget_m`` (K,): what the tool may deviate there beyond the motions' own deviation,
    half for the blend's position, half for its orientation; ``budget_rad`` the part's
    turn from the motions'."""
    p = X_BP[:, :3, 3]
    step = np.diff(p, axis=0)
    length = np.maximum(np.linalg.norm(step, axis=1), 1e-12)
    u = step / length[:, None]  # (K-1, 3) directions
    turn = Rotation.from_matrix(X_BP[1:, :3, :3]) * Rotation.from_matrix(X_BP[:-1, :3, :3]).inv()
    w = turn.as_rotvec() / length[:, None]  # (K-1, 3) the part's turn per metre, in B
    radius = np.zeros(len(p))
    if len(p) < 3:
        return radius
    # A blend of radius r leaves the motions' line by at most r·|u_in − u_out| / 2 =
    # r·sin(θ/2), and their turn by at most r·|w_in − w_out| / 2.
    bend = 0.5 * np.linalg.norm(u[1:] - u[:-1], axis=1)
    twist = 0.5 * np.linalg.norm(w[1:] - w[:-1], axis=1)
    lever = np.linalg.norm(X_BT[:3, 3] - p[1:-1], axis=1)  # the tool from P's origin
    budget = np.maximum(budget_m[1:-1], 0.0)
    radius[1:-1] = np.min(
        [
            BLEND_SHARE * length[:-1],
            BLEND_SHARE * length[1:],
            0.5 * budget / np.maximum(bend, 1e-12),
            0.5 * budget / np.maximum(lever * twist, 1e-12),
            budget_rad / np.maximum(twist, 1e-12),
        ],
        axis=0,
    )
    return radius
