"""The cheaper law that ranks the screened candidates before any is planned: TOPP-RA
under the joints' speed and acceleration limits and the path's speed and acceleration
caps, on the tool turn and branch the planner's first attempt takes
(``SeamVariants.planner_choice``), on a coarse grid, without the jerk stage.

The planner's law (``joints.path_timing``) runs TOPP-RA on a fine grid, then its jerk
stage and the averaged profile: ~0.7 s of a one-seam candidate's ~2 s. This one takes
~25 ms. It is no bound (another turn or branch may be taken where the first collides),
and it runs ~1.5 s under the planner's law on the demos (the jerk stage's ramps), the
same for every placement: it ranks them (``scripts/place_two_stage.py``).
"""

from __future__ import annotations

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.math import RigidTransform, RotationMatrix

from offline_prog.joints.joint_plan import BranchPath
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.placement.variants import SeamVariants
from offline_prog.stages import motion_setup, smooth_turn
from offline_prog.timing.joint_timing import JointRates
from offline_prog.timing.time_optimal import topp_profile

LAW_GRID_POINTS = 200  # σ grid of the cheaper law's TOPP-RA solve


def planner_flange(view, X_IT: RigidTransform, X_PE: RigidTransform, phi: float):
    """The flange path with the tool turned by φ₀ [rad] as ``tool_rotations`` builds it."""
    tool, fit = view.inputs.cell.tool, view.fit
    unit = np.eye(3)["xyz".index(tool.symmetry_axis)]
    turn = smooth_turn(view.inputs, fit) if tool.free_rotation_deg > 0 else None
    if turn is None:
        X_IT_phi = X_IT @ RigidTransform(RotationMatrix(AngleAxis(phi, unit)), np.zeros(3))
        return FlangePath(fit.path, fit.normal, X_IT=X_IT_phi, X_PE=X_PE)
    low, high = turn.span_rad
    scale = min(1.0, 2.0 * np.deg2rad(tool.free_rotation_deg) / max(high - low, 1e-12))
    return FlangePath(
        fit.path,
        fit.normal,
        X_IT=X_IT,
        X_PE=X_PE,
        tool_turn=turn.with_offset(float(phi), scale),
        axis=unit,
    )


def law_seam_s(
    view, variants: SeamVariants, X_IT: RigidTransform, X_PE: RigidTransform
) -> tuple[float, object]:
    """(the cheaper law's duration of a seam on the planner's variant [s], NaN when no
    variant is feasible or TOPP-RA finds no profile; the flange path it runs): a flying
    seam's law runs its leads too, and a lead runs part of the approach and retract
    (``job.approach.lead_covers_m`` of that path)."""
    choice = variants.planner_choice()
    if choice is None:
        return float("nan"), None
    a, branch = choice
    inputs, robot = view.inputs, view.inputs.robot
    run = motion_setup(inputs, planner_flange(view, X_IT, X_PE, float(variants.angles[a])))
    grid = np.linspace(0.0, run.parameter.length, LAW_GRID_POINTS)
    # The variant's q on the screen's σ samples, as the 2π reference of the exact IK.
    fraction = variants.sigma / variants.sigma[-1]
    q_near = np.column_stack(
        [np.interp(grid / grid[-1], fraction, variants.q[a, branch, 1:-1, j]) for j in range(6)]
    )
    path = BranchPath(robot, inputs.X_IB, run.flange, run.parameter, branch)
    rates = path.rates(grid, q_near)
    if not np.isfinite(rates.q).all():
        return float("nan"), run.flange
    controller = JointRates(
        rates.sigma, *(robot.controller_joints(v) for v in (rates.q, rates.dq, rates.ddq))
    )
    profile = topp_profile(
        controller,
        qd_max=robot.qd_max,
        qdd_max=robot.qdd_max,
        v_cap=run.limits.v_process,
        a_path=run.limits.a_max,
    )
    return (float(profile.duration) if profile.ok else float("nan")), run.flange
