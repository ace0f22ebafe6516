"""The joint paths a placement candidate may take on a seam: every tool turn φ₀ the
planner tries times the eight IK branches, screened at once on a coarse σ grid.

The planner (``stages.flange_paths``, ``joints.joint_plan.tool_rotations``) lays the
process frame onto T·R_axis(φ₀) for a symmetric tool, φ₀ ∈ [−bound, bound] in steps of
ROTATION_STEP_RAD, and plans the best of them on the best IK branch (other turns and
branches where that one collides). A turn about T's axis turns the whole flange path
about that axis, so one evaluation of the part's side of the path
(``fixed_tcp.part_in_tool``: p_TE_T, M = R_TP·R_PE) gives every φ₀:

    p_IE(σ, φ) = p_IT + R_IT R_axis(φ) p_TE_T(σ),   R_IE(σ, φ) = R_IT R_axis(φ) M(σ)

(with ``tool.turn_smoothing_mm`` φ = φ₀ + the smooth turn's φ(σ)). Besides the seam's
samples, the two points off its ends where the approach starts and the retract ends
(``job.approach``: the tool δ = d off the end frame along u) are solved on the same
branch, for the links' lower bound (``placement.bound``).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.joints.joint_plan import ROTATION_STEP_RAD, rotation_trial_points
from offline_prog.joints.path_ik import (
    MAX_JOINT_STEP_RAD,
    base_poses,
    branch_table,
    reach_excess,
)
from offline_prog.path.fixed_tcp import part_in_tool
from offline_prog.stages import smooth_turn

# σ samples of a seam's screen: the joint speed bound sums |Δq| between them, which
# only grows with more samples (it stays a bound however coarse).
VARIANT_SAMPLES = 64
# A pose this far beyond the arm's stretch [m] has no IK solution (reach_excess is the
# closed form's own test, on the wrist centre; the margin covers its rounding).
UNREACHABLE_M = 1e-3


@dataclasses.dataclass(frozen=True)
class SeamVariants:
    """Every (tool turn, branch) joint path of one seam at one placement.

    Attributes:
        angles: (A,) the tool turns φ₀ the planner tries [rad].
        sigma: (N,) σ samples of the seam [m].
        q: (A, 8, N + 2, 6) joint paths [rad] (URDF order), unwrapped along σ with the
            2π turns of the widest limit margin: row 0 the approach's start, rows 1..N
            the seam, row N + 1 the retract's end (NaN where a branch has no solution).
        reach_share: (A, 8) the share of rows with a solution.
        reach: (A, 8) every row has a solution; within: (A, 8) and inside the joint
            limits (with the 2π turns); flips: (A, 8) a step larger than the planner's
            continuity test scaled to this grid (a branch swap, by the planner's rule).
        margin: (A, 8) the smallest joint-limit margin along the seam [rad].
        reach_excess: (A, N) how far each seam pose lies beyond the arm's reach [m].
    """

    angles: np.ndarray
    sigma: np.ndarray
    q: np.ndarray
    reach_share: np.ndarray
    reach: np.ndarray
    within: np.ndarray
    flips: np.ndarray
    margin: np.ndarray
    reach_excess: np.ndarray

    @property
    def usable(self) -> np.ndarray:
        """(A, 8) the variants no planner's path can rule out on this grid: reachable
        everywhere, inside the limits (a flip is not trusted on a coarse grid)."""
        return self.reach & self.within

    def planner_choice(self) -> tuple[int, int] | None:
        """(turn index, branch) the planner's first attempt takes, as it ranks them
        (``tool_rotations``: feasible first, the widest margin, the smaller |φ₀|; then
        ``choose_branch``), or None when no variant is feasible."""
        feasible = self.usable & ~self.flips
        if not feasible.any():
            return None
        margin = np.where(feasible, self.margin, -np.inf)
        best_branch = np.argmax(margin, axis=1)  # (A,)
        best = margin[np.arange(len(self.angles)), best_branch]
        order = np.lexsort((np.abs(self.angles), -best))  # widest margin, then small |φ₀|
        a = int(order[0])
        return a, int(best_branch[a])


def _angles(bound: float, span) -> np.ndarray:
    lo, hi = -bound, bound
    if span is not None:
        low, high = span
        scale = min(1.0, 2.0 * bound / max(high - low, 1e-12))
        lo, hi = -bound - scale * low, bound - scale * high
        if scale < 1.0:
            lo = hi = 0.5 * (lo + hi)
    count = int(np.ceil((hi - lo) / (2.0 * ROTATION_STEP_RAD)))
    return np.linspace(lo, hi, 2 * count + 1) if count else np.array([lo])


def _axis_rotations(axis: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotations by phi (...) [rad] about the unit axis (3,) (Rodrigues)."""
    K = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    s, c = np.sin(phi)[..., None, None], np.cos(phi)[..., None, None]
    return np.eye(3) + s * K + (1.0 - c) * (K @ K)


def _offsets(seam, p_PF, R_PF, sigma_end: int) -> tuple[float, np.ndarray] | None:
    """(d [m], u (3,) in P) of the approach (σ = 0) or retract (σ = L) end, or None."""
    spec = seam.approach if sigma_end == 0 else seam.retract
    d = spec.distance_mm * 1e-3
    if spec.kind == "none" or d <= 0.0:
        return None
    i = 0 if sigma_end == 0 else -1
    if spec.kind == "normal":
        return d, R_PF[i][:, 1]
    return d, (1.0 if sigma_end == 0 else -1.0) * R_PF[i][:, 0]


def seam_variants(view, seam, X_IT, X_PE, *, samples: int = VARIANT_SAMPLES) -> SeamVariants:
    """Every (tool turn, branch) joint path of a seam at the placement (X_IT, X_PE).

    Args:
        view: the seam's ``context.SeamView`` (its inputs and fitted path).
        seam: its SeamConfig (approach and retract).
        X_IT, X_PE: the candidate's RigidTransforms.
    """
    inputs, fit = view.inputs, view.fit
    robot, tool = inputs.robot, inputs.cell.tool
    sigma = np.linspace(0.0, fit.path.length, samples)
    p_PF, R_PF, p_TE_T, _, _, M, _, _ = part_in_tool(fit.path, fit.normal, X_PE, sigma)
    R_PE = X_PE.rotation().matrix()
    # The off-end points: p_PT = p_PF − d·u, so p_TE_T grows by d·R_TP u; M stays.
    rows_p, rows_M = [p_TE_T[:1]], [M[:1]]
    for end in (0, -1):
        found = _offsets(seam, p_PF, R_PF, end)
        base_p, base_M = p_TE_T[end], M[end]
        if found is not None:
            d, u = found
            base_p = base_p + d * (base_M @ R_PE.T @ u)
        rows_p.append(base_p[None]), rows_M.append(base_M[None])
    p_all = np.concatenate([rows_p[1], p_TE_T, rows_p[2]])  # (N + 2, 3)
    M_all = np.concatenate([rows_M[1], M, rows_M[2]])
    axis = np.eye(3)["xyz".index(tool.symmetry_axis)]
    angles = np.zeros(1)
    phi = np.zeros((1, samples + 2))
    if tool.free_rotation_deg > 0:
        turn = smooth_turn(inputs, fit)
        bound = np.deg2rad(tool.free_rotation_deg)
        angles = _angles(bound, None if turn is None else turn.span_rad)
        phi = np.repeat(angles[:, None], samples + 2, axis=1)
        if turn is not None:
            scale = min(1.0, 2.0 * bound / max(np.ptp(turn.span_rad), 1e-12))
            along = np.concatenate([[0.0], sigma, [fit.path.length]])
            for a, phi0 in enumerate(angles):
                phi[a] = turn.with_offset(float(phi0), scale)(along)[0]
    G = X_IT.rotation().matrix() @ _axis_rotations(axis, phi)  # (A, N + 2, 3, 3)
    p_IE = X_IT.translation() + np.einsum("anij,nj->ani", G, p_all)
    R_IE = G @ M_all
    A, rows = phi.shape
    X_BE = base_poses(inputs.X_IB, p_IE.reshape(-1, 3), R_IE.reshape(-1, 3, 3))
    excess = reach_excess(robot, X_BE).reshape(A, rows)
    beyond = reach_excess(robot, X_BE, inner=False).reshape(A, rows) > UNREACHABLE_M
    if beyond.all(axis=0).any():  # a row beyond the arm's stretch on every turn
        return _unreachable(angles, sigma, excess)
    solutions = robot.inverse(X_BE).reshape(A, rows, 8, 6)
    return _judged(robot, angles, sigma, solutions, excess)


def _unreachable(angles, sigma, excess) -> SeamVariants:
    """The variants of a seam with a row beyond the arm's reach on every tool turn:
    no IK needed to rule it out (``reach_excess`` without the closed form)."""
    A, rows = excess.shape
    none = np.zeros((A, 8), dtype=bool)
    share = np.repeat((excess <= 0.0).mean(axis=1)[:, None], 8, axis=1)
    return SeamVariants(
        angles=angles,
        sigma=sigma,
        q=np.full((A, 8, rows, 6), np.nan),
        reach_share=share,
        reach=none,
        within=none,
        flips=none,
        margin=np.full((A, 8), -np.inf),
        reach_excess=excess[:, 1:-1],
    )


def _judged(robot, angles, sigma, solutions, excess) -> SeamVariants:
    """The verdicts of (A, N + 2, 8, 6) solutions (``path_ik.branch_table``, the turns
    and margins along the seam's rows); excess: (A, N + 2) each pose's distance beyond
    reach [m]."""
    rows = solutions.shape[1]
    # The planner tests continuity on rotation_trial_points samples: the same rate of
    # turn [rad/m] on this grid (a flip is a jump of about π, far beyond it).
    spacing = sigma[1] - sigma[0] if len(sigma) > 1 else 1.0
    trial = sigma[-1] / (rotation_trial_points(sigma[-1]) - 1) if sigma[-1] > 0 else spacing
    limit = min(np.pi / 2, MAX_JOINT_STEP_RAD * spacing / trial)
    seam = slice(1, rows - 1)
    table = branch_table(robot, solutions, max_step=limit, rows=seam)
    q = np.where(table.reachable[..., None], table.q, np.nan)
    q_c = robot.controller_joints(q[:, :, [0, -1]])
    with np.errstate(invalid="ignore"):
        ends_inside = ((q_c >= robot.q_lower) & (q_c <= robot.q_upper)).all(axis=(-1, -2))
    return SeamVariants(
        angles=angles,
        sigma=sigma,
        q=q,
        reach_share=table.reachable.mean(axis=-1),
        reach=table.reachable.all(axis=-1),
        within=(table.margin >= 0.0) & ends_inside,
        flips=table.first_jump >= 0,
        margin=table.margin,
        reach_excess=excess[:, seam],
    )
