"""Collision avoidance: re-plan with other branches and tool rotations, and as the
last resort turn a symmetric tool along the path.

When no configuration branch and no fixed tool rotation is collision-free, Drake
InverseKinematics looks for joint configurations that still hold the process pose
— the path point at the TCP, the surface normal on the tool's axis — while the
rotation about that axis stays within its bound and every checked pair keeps the
clearance (MinimumDistanceLowerBoundConstraint). Solved on a coarse σ grid, each
sample seeded with the previous one, the rotations found are fitted with a smooth
quintic spline φ(s), and the flange path is rebuilt with it, so that the analytic
pipeline (branch, retiming, collision check) runs on a smooth, exact path again.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from pydrake.multibody.inverse_kinematics import InverseKinematics
from pydrake.solvers import Solve

from offline_prog.collision.check import CollisionResult
from offline_prog.errors import PlanFailedError
from offline_prog.joints.joint_plan import JointTrajectory
from offline_prog.path.bspline_fit import fit_on_knots, open_knots
from offline_prog.path.cusps import SmoothedFlangePath
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.timing.path_timing import PathLimits

GRID_POINTS = 80  # IK samples along the path
CLEARANCE_MARGIN_M = 2e-3  # asked of the IK beyond the clearance
INFLUENCE_M = 0.05  # distance at which pairs start to count in the constraint
NORMAL_TOL_RAD = 1e-6
POSITION_TOL_M = 1e-7
SPLINE_CONTROL_POINTS = (10, 20, 40)  # tried in turn: the smoothest turn that fits
# The most the tool may turn between neighbouring IK samples (a continuous turn: SNOPT
# may otherwise land on another side of the bound from one sample to the next), and how
# far the fitted turn may leave its samples and the bound.
MAX_TURN_STEP_RAD = np.deg2rad(10.0)
TURN_FIT_TOL_RAD = np.deg2rad(1.0)
N_NUDGES, NUDGE_RAD = 4, 0.1  # more IK starts at a sample where the first two fail


def _turn_angle(x_T: np.ndarray, axis_I: np.ndarray, t_I: np.ndarray) -> float:
    """Angle about axis_I from x_T to the tangent t_I [rad]."""
    return float(np.arctan2(np.cross(x_T, t_I) @ axis_I, x_T @ t_I))


def turn_profile(
    drake,
    path,
    normal_field,
    *,
    X_IT,
    s_plan: np.ndarray,
    q_plan: np.ndarray,
    axis: np.ndarray,
    bound_rad: float,
    clearance: float,
):
    """A smooth tool rotation φ(s) that keeps the clearance, or None.

    Args:
        drake: the DrakeCell with every shape (the part body frame is P).
        path: the processing path; normal_field: its surface normals.
        X_IT: the physical tool frame; axis: (3,) the symmetry axis in T.
        s_plan, q_plan: (M,) arc lengths and (M, 6) joints of the colliding plan: the
            first sample and any retry are seeded from it.
        bound_rad: largest |φ|; clearance: required distance [m].

    Returns:
        φ(s) ↦ (φ, φ′, φ″) for ``FlangePath(tool_turn=...)``, or None when some
        sample has no solution within MAX_TURN_STEP_RAD of the one before, or the
        smooth turn through them leaves them or the bound by more than
        TURN_FIT_TOL_RAD, swept from the start and then, if that fails, back from
        the end (a turn the first sweep met too late).
    """
    plant = drake.plant
    context = drake.diagram.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    part = plant.GetBodyByName("part").body_frame()
    world = plant.world_frame()
    R_IT = X_IT.rotation().matrix()
    axis_I, x_T, p_IT = R_IT @ axis, R_IT[:, 0], X_IT.translation()
    s_grid = np.linspace(0.0, path.length, GRID_POINTS)
    p_PF, t_P = path(s_grid, order=1)
    n_P = normal_field(s_grid)[0]
    n_P = n_P - np.einsum("ij,ij->i", n_P, t_P)[:, None] * t_P
    n_P /= np.linalg.norm(n_P, axis=1, keepdims=True)
    q_seed_plan = np.column_stack([np.interp(s_grid, s_plan, q_plan[:, j]) for j in range(6)])

    def sweep(order, seeds: np.ndarray):
        """(turn angles (K,) [rad], joints (K, 6)) solved sample after sample in
        ``order``, each within MAX_TURN_STEP_RAD of the one before and seeded by it,
        then by seeds[k]; None where a sample has no solution."""
        q_prev, angles, solved = seeds[order[0]], np.zeros(len(s_grid)), seeds.copy()
        for n, k in enumerate(order):
            ik = InverseKinematics(plant, plant_context)
            ik.AddPositionConstraint(
                part, p_PF[k], world, p_IT - POSITION_TOL_M, p_IT + POSITION_TOL_M
            )
            ik.AddAngleBetweenVectorsConstraint(world, axis_I, part, n_P[k], 0.0, NORMAL_TOL_RAD)
            ik.AddAngleBetweenVectorsConstraint(world, x_T, part, t_P[k], 0.0, bound_rad)
            ik.AddMinimumDistanceLowerBoundConstraint(clearance + CLEARANCE_MARGIN_M, INFLUENCE_M)
            if n:  # near the last sample's turn: x_T turned by it about the axis
                last = angles[order[n - 1]]
                x_last = np.cos(last) * x_T + np.sin(last) * np.cross(axis_I, x_T)
                ik.AddAngleBetweenVectorsConstraint(
                    world, x_last, part, t_P[k], 0.0, MAX_TURN_STEP_RAD
                )
            q = ik.q()
            ik.get_mutable_prog().AddQuadraticErrorCost(np.eye(len(q_prev)), q_prev, q)
            # The previous solution, the seed's, then a few seeded nudges of the previous
            # one (SNOPT can stall on a distance constraint's kinks from one start).
            rng = np.random.default_rng(k)
            nudges = [
                q_prev + rng.uniform(-NUDGE_RAD, NUDGE_RAD, len(q_prev)) for _ in range(N_NUDGES)
            ]
            for seed in (q_prev, seeds[k], *nudges):
                result = Solve(ik.prog(), seed)
                if result.is_success():
                    break
            else:
                return None
            q_prev = solved[k] = result.GetSolution(q)
            plant.SetPositions(plant_context, q_prev)
            R_IP = part.CalcPoseInWorld(plant_context).rotation().matrix()
            angles[k] = _turn_angle(x_T, axis_I, R_IP @ t_P[k])
        return np.unwrap(angles), solved

    def smooth(angles: np.ndarray):
        """The spline of the turn angles with the fewest control points (of
        SPLINE_CONTROL_POINTS) that stays within TURN_FIT_TOL_RAD of them and of the
        bound, or None."""
        fine_s = np.linspace(0.0, path.length, 10 * GRID_POINTS)
        for count in SPLINE_CONTROL_POINTS:
            knots = open_knots(s_grid, count, 5)
            spline = fit_on_knots(s_grid, angles[:, None], knots, 5, closed=False)
            off = np.abs(spline(s_grid)[:, 0] - angles).max()
            over = np.abs(spline(fine_s)[:, 0]).max() - bound_rad
            if max(off, over) <= TURN_FIT_TOL_RAD:
                return spline
        return None

    forward = sweep(range(len(s_grid)), q_seed_plan)
    if forward is None:
        return None
    spline = smooth(forward[0])
    if spline is None:  # a turn the sweep met too late: back from the end, near its joints
        backward = sweep(range(len(s_grid) - 1, -1, -1), forward[1])
        spline = None if backward is None else smooth(backward[0])
    if spline is None:
        return None

    def tool_turn(s: np.ndarray):
        s = np.clip(s, 0.0, path.length)
        return tuple(spline(s, nu=k)[:, 0] for k in range(3))

    return tool_turn


# Collision avoidance: at most this many re-plans (tool rotations × branches).
MAX_AVOIDANCE_ATTEMPTS = 12


@dataclasses.dataclass
class Attempt:
    """One joint plan and its collision check (None until the ``check`` stage ran)."""

    rotation: float  # the tool's turn about its symmetry axis [rad]
    flange: FlangePath | SmoothedFlangePath
    limits: PathLimits  # the process speed, caps and joint limits (their nominal law)
    joints: JointTrajectory
    collisions: CollisionResult | None


def avoid_collisions(first: Attempt, rotations, attempt) -> tuple[Attempt, dict]:
    """Re-plan with the other tool rotations and configuration branches until one is
    collision-free (cheap choices first; the process pose is held in every one).

    Returns:
        The collision-free attempt (else the one with the largest clearance) and a
        record for the report: the samples that needed avoidance, what was tried and
        what changed.
    """
    tried, best = 0, first
    candidates = [
        (first.rotation, first.flange, b.branch)
        for b in first.joints.branches
        if b.feasible and b.branch != first.joints.branch
    ]
    candidates += [(phi, flange, None) for phi, flange in rotations[1:]]
    for phi, flange, branch in candidates:
        if tried >= MAX_AVOIDANCE_ATTEMPTS:
            break
        tried += 1
        try:
            trial = attempt(phi, flange, branch)
        except PlanFailedError:
            continue
        if trial.collisions.min_distance_m > best.collisions.min_distance_m:
            best = trial
        if trial.collisions.collision_free:
            break
    sigma = first.joints.trajectory.s
    needed = sorted(set(first.collisions.samples_in_collision))
    change = []
    if best.rotation != first.rotation:
        change.append(
            f"tool rotation {np.rad2deg(first.rotation):.1f}° → {np.rad2deg(best.rotation):.1f}°"
        )
    if best.joints.branch != first.joints.branch:
        change.append(f"branch {first.joints.branch} → {best.joints.branch}")
    record = {
        "samples_that_needed_it": needed,
        "sigma_m_that_needed_it": [float(sigma[i]) for i in needed if 0 <= i < len(sigma)],
        "first_failure": first.collisions.message,
        "attempts": tried,
        "resolved": best.collisions.collision_free,
        "change": ", ".join(change) or "none",
    }
    return best, record


def turn_tool_along_path(
    chosen: Attempt, record: dict, attempt, scene, path, normal, inputs
) -> Attempt:
    """Last resort for a symmetric tool: turn it along the path (Drake IK with a
    minimum-distance constraint, :func:`turn_profile`) and re-plan with that turn.

    Args:
        chosen: the best attempt so far (colliding); record: the avoidance record,
            updated in place with the attempt and, if it worked, the change.
        attempt: (rotation, flange) ↦ Attempt, the planner of one flange path.
        scene: the DrakeCell; path, normal: the arc-length path and normal field in P;
        inputs: the plan's Inputs (cell, X_IT, X_PE).

    Returns:
        The turned attempt if it is collision-free, else ``chosen``.
    """
    cell = inputs.cell
    axis = np.eye(3)["xyz".index(cell.tool.symmetry_axis)]
    turn = turn_profile(
        scene,
        path,
        normal,
        X_IT=inputs.X_IT,
        s_plan=chosen.joints.trajectory.s,
        q_plan=chosen.joints.q,
        axis=axis,
        bound_rad=np.deg2rad(cell.tool.free_rotation_deg),
        clearance=cell.motion.clearance,
    )
    if turn is None:
        return chosen
    turned = FlangePath(path, normal, X_IT=inputs.X_IT, X_PE=inputs.X_PE, tool_turn=turn, axis=axis)
    phi = turn(np.linspace(0.0, path.length, 200))[0]
    record["attempts"] += 1
    try:
        trial = attempt(float(phi[0]), turned)
    except PlanFailedError:
        return chosen
    if not trial.collisions.collision_free:
        return chosen
    record["resolved"] = True
    record["change"] = (
        "tool turned along the path (Drake IK with a minimum-distance constraint): "
        f"φ from {np.rad2deg(phi.min()):.1f}° to {np.rad2deg(phi.max()):.1f}°"
    )
    return trial
