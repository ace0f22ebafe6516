"""Joint path along the flange path: one configuration branch, the best 2π start.

All eight analytic solutions are computed for every sample at once. Each branch
(the solution index of the OPW / UR closed form: shoulder, elbow and wrist sides)
is unwrapped along the path; a branch that jumps between neighbouring samples
passes a singularity (where the closed form swaps sides) and is dropped. For
joints with more than one turn of range, the multiple of 2π that keeps the whole
path inside the limits with the largest margin is chosen; a closed contour that
turns the part once about the tool therefore starts the wrist where it has the
range for the full turn. The branch with the largest margin wins.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.arrays import row_max, true_runs
from offline_prog.errors import Failure
from offline_prog.robot.model import RobotModel

# Largest joint step between neighbouring samples that is still continuous motion
# [rad]; a bigger step means the closed form swapped sides (a singularity).
MAX_JOINT_STEP_RAD = np.deg2rad(10.0)
# Candidate turns k in q + 2πk for joints with more than one turn of range.
TURN_CANDIDATES = np.arange(-2, 3)
TWO_PI = 2.0 * np.pi


@dataclasses.dataclass(frozen=True)
class BranchResult:
    """How one branch fares along the path.

    Attributes:
        branch: solution index 0..7.
        q: (N, 6) joint path [rad] with the chosen 2π offsets (NaN if unreachable).
        feasible: reachable, continuous and inside the joint limits everywhere.
        margin_rad: smallest distance to a joint limit over the path [rad]
            (negative: the amount by which a limit is exceeded).
        reason: why it is infeasible ("" if feasible), with the sample index.
        sample: index of the first failing sample (−1 if feasible).
        kind: the kind of failure (None if feasible).
    """

    branch: int
    q: np.ndarray
    feasible: bool
    margin_rad: float
    reason: str
    sample: int
    kind: Failure | None = None


def base_poses(X_IB, p_IE: np.ndarray, R_IE: np.ndarray) -> np.ndarray:
    """(N, 4, 4) flange poses X_BE = X_BI · X_IE in the robot base."""
    R_BI = X_IB.rotation().matrix().T
    X_BE = np.zeros((len(p_IE), 4, 4))
    X_BE[:, :3, :3] = R_BI @ R_IE
    X_BE[:, :3, 3] = (p_IE - X_IB.translation()) @ R_BI.T
    X_BE[:, 3, 3] = 1.0
    return X_BE


def best_turns(q: np.ndarray, lower: np.ndarray, upper: np.ndarray):
    """Per-joint offsets 2πk maximizing the limit margin of a joint path.

    Args:
        q: (B, N, 6) unwrapped joint paths of B branches [rad].
        lower, upper: (6,) joint limits [rad].

    Returns:
        offsets: (B, 6) multiples of 2π to add [rad]; margins: (B, 6) the smallest
        distance of each shifted joint path to its limits [rad].
    """
    with np.errstate(invalid="ignore"):  # branches with no solution at all stay NaN
        q_min = np.nanmin(np.where(np.isnan(q), np.inf, q), axis=1)  # (B, 6)
        q_max = np.nanmax(np.where(np.isnan(q), -np.inf, q), axis=1)
    shifts = 2.0 * np.pi * TURN_CANDIDATES  # (K,)
    margin = np.minimum(
        q_min[..., None] + shifts - lower[:, None], upper[:, None] - q_max[..., None] - shifts
    )  # (B, 6, K)
    best = np.argmax(margin, axis=-1)
    offsets = shifts[best]
    return offsets, np.take_along_axis(margin, best[..., None], axis=-1)[..., 0]


@dataclasses.dataclass(frozen=True)
class BranchTable:
    """Every branch of one or many joint paths at once (the numbers of
    :func:`branch_results`), leading batch dimensions ``...``.

    Attributes:
        q: (..., 8, N, 6) each branch unwrapped along the path with the 2π turns of its
            widest limit margin [rad] (URDF order).
        reachable: (..., 8, N) the sample has a solution on the branch.
        margins: (..., 8, 6) each joint's smallest margin to its limits [rad] (over the
            samples that choose the turns); margin: (..., 8) the smallest of them.
        first_unreachable: (..., 8) the first sample without a solution (0 if none).
        first_jump: (..., 8) the sample after the first step beyond ``max_step`` between
            two solved samples (-1 if none).
    """

    q: np.ndarray
    reachable: np.ndarray
    margins: np.ndarray
    margin: np.ndarray
    first_unreachable: np.ndarray
    first_jump: np.ndarray

    @property
    def feasible(self) -> np.ndarray:
        """(..., 8) reachable everywhere, continuous and inside the limits."""
        return self.reachable.all(axis=-1) & (self.first_jump < 0) & (self.margin >= 0)


def branch_table(
    robot: RobotModel,
    solutions: np.ndarray,
    *,
    max_step: float = MAX_JOINT_STEP_RAD,
    rows: slice = slice(None),
) -> BranchTable:
    """The branches of joint paths from their IK solutions (..., N, 8, 6) [rad]
    (``robot.inverse``): each unwrapped along the path, each step taken as its
    equivalent in [−π, π); the 2π turns with the widest margin over the samples
    ``rows`` (the limits apply to the controller's axes: ABB's axis 3 = q2 + q3), and
    the continuity test (``max_step``) on the steps between them (rows: consecutive
    samples)."""
    solutions = np.swapaxes(solutions, -3, -2)  # (..., 8, N, 6)
    reachable = ~np.isnan(solutions).any(axis=-1)
    filled = np.where(reachable[..., None], solutions, 0.0)
    step = np.diff(filled, axis=-2)
    step -= TWO_PI * np.floor((step + np.pi) / TWO_PI)
    q = np.concatenate([filled[..., :1, :], filled[..., :1, :] + np.cumsum(step, axis=-2)], axis=-2)
    shape = q.shape
    flat = q.reshape(-1, *shape[-2:])
    chosen = np.where(reachable.reshape(-1, shape[-2])[..., None], flat, np.nan)[:, rows]
    offsets, margins = best_turns(robot.controller_joints(chosen), robot.q_lower, robot.q_upper)
    q = (flat + offsets[:, None, :]).reshape(shape)
    margins = margins.reshape(*shape[:-2], 6)
    n = shape[-2]
    index = np.arange(n)[rows]
    inside = index[1:]  # the steps between the samples of rows
    jumps = (row_max(np.abs(step[..., inside - 1, :])) > max_step) & (
        reachable[..., inside] & reachable[..., inside - 1]
    )
    first_jump = np.where(jumps.any(axis=-1), inside[np.argmax(jumps, axis=-1)], -1)
    return BranchTable(
        q,
        reachable,
        margins,
        margins.min(axis=-1),
        np.argmin(reachable, axis=-1),
        first_jump,
    )


def branch_results(
    robot: RobotModel, X_BE: np.ndarray | None = None, *, solutions: np.ndarray | None = None
) -> list[BranchResult]:
    """Evaluate all eight branches along the poses X_BE (N, 4, 4), or along their IK
    ``solutions`` (N, 8, 6) [rad] (``robot.inverse(X_BE)``) when given."""
    if solutions is None:
        solutions = robot.inverse(X_BE)
    table = branch_table(robot, solutions)
    results = []
    for b in range(8):
        margin = float(table.margin[b])
        q = table.q[b]
        if not table.reachable[b].all():
            first = int(table.first_unreachable[b])
            results.append(
                BranchResult(
                    b,
                    np.full_like(q, np.nan),
                    False,
                    -np.inf,
                    "out of reach",
                    first,
                    Failure.OUT_OF_REACH,
                )
            )
            continue
        if table.first_jump[b] >= 0:
            results.append(
                BranchResult(
                    b,
                    q,
                    False,
                    margin,
                    "singularity (the configuration flips)",
                    int(table.first_jump[b]),
                    Failure.SINGULARITY,
                )
            )
            continue
        if margin < 0:
            joint = int(np.argmin(table.margins[b]))
            results.append(
                BranchResult(
                    b,
                    q,
                    False,
                    margin,
                    f"joint limit on axis {joint + 1}",
                    first_outside(robot, q, joint),
                    Failure.JOINT_LIMIT,
                )
            )
            continue
        results.append(BranchResult(b, q, True, margin, "", -1))
    return results


def first_outside(robot: RobotModel, q: np.ndarray, joint: int) -> int:
    """The first sample of a joint path q (N, 6) [rad] where ``joint`` is outside its
    limits (the controller's axes)."""
    q_c = robot.controller_joints(q)
    outside = (q_c[:, joint] < robot.q_lower[joint]) | (q_c[:, joint] > robot.q_upper[joint])
    return int(np.argmax(outside))


def choose_branch(results: list[BranchResult]) -> BranchResult:
    """The feasible branch with the largest limit margin, else the one that gets
    furthest along the path (its reason explains the failure)."""
    feasible = [r for r in results if r.feasible]
    if feasible:
        return max(feasible, key=lambda r: r.margin_rad)
    return max(results, key=lambda r: (r.sample, r.margin_rad))


def singularity_distances(robot: RobotModel, q: np.ndarray, X_BE: np.ndarray) -> dict:
    """Distances to the wrist, elbow and shoulder singularities along a joint path.

    Args:
        q: (N, 6) joint path [rad]; X_BE: (N, 4, 4) the matching flange poses.

    Returns:
        {"wrist": (N,) |sin θ5|, "elbow": (N,) |sin| of the elbow stretch angle,
        "shoulder": (N,) distance of the wrist centre from its singular locus [m]}.
    """
    p = robot.params
    if robot.family == "opw":
        theta = q * np.asarray(p.sign_corrections) - np.asarray(p.offsets)
        wrist = np.abs(np.sin(theta[:, 4]))
        elbow = np.abs(np.sin(theta[:, 2] + np.arctan2(p.a2, p.c3)))
        p_BC = X_BE[:, :3, 3] - p.c4 * X_BE[:, :3, 2]
        shoulder = np.abs(np.hypot(p_BC[:, 0], p_BC[:, 1]) - abs(p.b))
    else:  # UR: wrist q5 ∈ {0, π}, elbow q3 ∈ {0, π}, shoulder |p_05,xy| = d4
        wrist = np.abs(np.sin(q[:, 4]))
        elbow = np.abs(np.sin(q[:, 2]))
        p_05 = X_BE[:, :3, 3] - p.d6 * X_BE[:, :3, 2]
        shoulder = np.abs(np.hypot(p_05[:, 0], p_05[:, 1]) - p.d4)
    return {"wrist": wrist, "elbow": elbow, "shoulder": shoulder}


# Singularity thresholds: |sin θ5| and |sin elbow| below sin(5°), shoulder 30 mm.
NEAR_SINGULAR = {
    "wrist": np.sin(np.deg2rad(5.0)),
    "elbow": np.sin(np.deg2rad(5.0)),
    "shoulder": 0.03,
    "jacobian": 0.01,  # smallest singular value of the flange Jacobian (Drake IK robots)
}


def singularity_report(distances: dict, sigma: np.ndarray) -> dict:
    """Per kind of ``distances`` (:func:`singularity_distances`, each (N,)): the
    smallest distance (wrist and elbow as the angle [deg] whose |sin| they are), σ at
    it and the stretches [(σ_start, σ_end), ...] nearer than NEAR_SINGULAR; σ (N,) [m]
    at the samples."""
    singular = {}
    for kind, d in distances.items():
        k = int(np.argmin(d))
        near = true_runs(d < NEAR_SINGULAR[kind])
        stretches = [(float(sigma[a]), float(sigma[b - 1])) for a, b in near]
        # Wrist and elbow distances are |sin| of an angle: report that angle.
        value, unit = (
            (float(d[k]), "m" if kind == "shoulder" else "m/rad")
            if kind in ("shoulder", "jacobian")
            else (float(np.rad2deg(np.arcsin(min(d[k], 1.0)))), "deg")
        )
        singular[kind] = {
            "distance": value,
            "unit": unit,
            "sigma_m": float(sigma[k]),
            "near": stretches,
        }
    return singular


def reach_excess(robot: RobotModel, X_BE: np.ndarray, *, inner: bool = True) -> np.ndarray:
    """How far each flange pose is out of the arm's reach [m] (0 inside it): the wrist
    centre's distance from the shoulder (axis 2) beyond the arm's longest stretch, or
    inside its shortest. A measure that keeps growing where the closed form only says
    "no solution", so a search can climb back into reach.

    Args:
        X_BE: (N, 4, 4) flange poses in the robot base.
        inner: count a wrist centre inside the shortest stretch too (an estimate:
            the closed form reaches some such poses); without it, a pose with any
            excess has no solution (the longest stretch is exact).

    Returns:
        (N,) [m]; zeros for a robot without a closed form.
    """
    p, z = X_BE[:, :3, 3], X_BE[:, :3, 2]
    params = robot.params
    if robot.family == "opw":
        c = p - params.c4 * z  # wrist centre
        offset, height = params.a1, params.c1
        longest = params.c2 + np.hypot(params.a2, params.c3)
        shortest = abs(params.c2 - np.hypot(params.a2, params.c3))
        lateral = params.b
    elif robot.family == "ur":
        c = p - params.d6 * z  # wrist 3 centre
        offset, height = 0.0, params.d1
        longest = abs(params.a2) + abs(params.a3) + abs(params.d5)
        shortest = 0.0
        lateral = params.d4
    else:
        return np.zeros(len(X_BE))
    radial = np.sqrt(np.maximum(c[:, 0] ** 2 + c[:, 1] ** 2 - lateral**2, 0.0))
    h = c[:, 2] - height
    d = np.minimum(np.hypot(radial - offset, h), np.hypot(radial + offset, h))  # front, back
    return np.maximum(d - longest, 0.0) + (np.maximum(shortest - d, 0.0) if inner else 0.0)
