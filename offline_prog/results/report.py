"""report.json: what a plan did, measured, in SI units (keys carry the unit).

Path and fit, motion limits and the measured speed errors, the robot's branch,
margins, singularities and speed reductions, the collision summary, cusps and the
stage timings.
"""

from __future__ import annotations

import datetime
from pathlib import Path

import numpy as np

from offline_prog import __version__
from offline_prog.constants import TimeLaw
from offline_prog.export.payload import payload, payload_note
from offline_prog.job.records import Plan
from offline_prog.robot.record import robot_source
from offline_prog.scene.payload import payload_record
from offline_prog.scene.shapes import gripper_shapes
from offline_prog.timing.path_timing import without_joint_limits
from offline_prog.timing.speed_hold import HOLD


def speed_checks(plan: Plan) -> dict[str, float]:
    """Independent checks of the speed that the time law promised.

    ``tcp_speed_max_error_rel``: max |v_Q − σ̇| / v_peak, with v_Q the rigid-body
    speed of the part point under the TCP (tcp reference; for the flange
    reference the flange speed |v_IE| is compared instead).
    ``chord_speed_max_error_rel``: during cruise, max |chord/Δt − v_peak| / v_peak
    from consecutive sampled positions alone (no derivatives): this checks that
    σ is the true arc length.
    """
    tr = plan.trajectory
    v_peak = tr.law.v_peak
    _, v_law, _, _ = tr.law(tr.t)
    if tr.reference == "tcp":
        commanded, measured, points = tr.s_dot, tr.tcp_speed, tr.flange.p_PF
    else:
        commanded, measured, points = v_law, np.linalg.norm(tr.v_IE, axis=1), tr.flange.p_IE
    chord = np.linalg.norm(np.diff(points, axis=0), axis=1) / np.diff(tr.t)
    cruise = (v_law[:-1] >= v_peak * (1 - 1e-12)) & (v_law[1:] >= v_peak * (1 - 1e-12))
    chord_error = np.abs(chord[cruise] - v_peak).max() / v_peak if cruise.any() else 0.0
    return {
        "tcp_speed_max_error_rel": float(np.abs(measured - commanded).max() / v_peak),
        "chord_speed_max_error_rel": float(chord_error),
        "cruise_samples": int(cruise.sum()),
    }


def _merged(stretches):
    """Contiguous (σ_start, σ_end, speed) stretches joined, keeping the lowest speed."""
    out = []
    for start, end, speed in stretches:
        if out and start <= out[-1][1] + 1e-9:
            out[-1] = (out[-1][0], end, min(out[-1][2], speed))
        else:
            out.append((start, end, speed))
    return out


def tool_turn_range_deg(plan: Plan) -> list[float]:
    """[lowest, highest] turn of a symmetric tool about its axis along the path [deg]:
    tool_rotation_deg twice unless the tool turns along the path (tool.turn_smoothing_mm
    or collision avoidance)."""
    flange = getattr(plan.flange, "exact", plan.flange)  # under cusp smoothing
    turn = getattr(flange, "tool_turn", None)
    if turn is None:
        return [float(np.rad2deg(plan.tool_rotation_rad))] * 2
    phi = np.rad2deg(turn(plan.trajectory.s)[0])
    return [float(phi.min()), float(phi.max())]


def robot_report(plan: Plan) -> dict:
    """Branch, joint-limit margins, joint steps, singularities and speed reductions."""
    robot, joints = plan.robot, plan.joints
    retiming, top = joints.retiming, plan.process_speed.v_m_s
    origin = plan.law_origin[0]  # the law's σ less this is the seam's
    joint, sigma, step = joints.largest_step
    use_speed = np.abs(robot.controller_joints(joints.qd)) / robot.qd_max
    use_accel = np.abs(robot.controller_joints(joints.qdd)) / robot.qdd_max
    return {
        "model": robot.name,
        "joint_names": list(robot.joint_names),
        "branch": joints.branch,
        "feasible_branches": [b.branch for b in joints.branches if b.feasible],
        "tool_rotation_deg": float(np.rad2deg(plan.tool_rotation_rad)),
        "tool_turn_deg": tool_turn_range_deg(plan),
        "joint_limit_margin_deg": np.rad2deg(joints.margin_rad).round(3).tolist(),
        "min_joint_limit_margin_deg": float(np.rad2deg(joints.margin_rad.min())),
        "largest_joint_step": {
            "joint": joint + 1,
            "sigma_m": sigma,
            "step_deg": float(np.rad2deg(step)),
        },
        "max_joint_speed_use": use_speed.max(axis=0).round(4).tolist(),
        "max_joint_acceleration_use": use_accel.max(axis=0).round(4).tolist(),
        "singularities": joints.singularities,
        "speed_reductions": [
            {
                "sigma_start_m": a,
                "sigma_end_m": b,
                "speed_m_s": v,
                "reduction_percent": 100.0 * (1.0 - v / top),
            }
            for a, b, v in _merged(
                tuple((a + origin, b + origin, v) for a, b, v in retiming.reductions)
            )
        ],
        "ramp_acceleration_scale": retiming.a_scale,
        "cycle_time_without_joint_limits_s": plan.nominal_duration_s,
        **timing_report(plan),
    }


def timing_report(plan: Plan) -> dict:
    """The time law, the joints' jerk use and, for the time-optimal law, TOPP-RA's
    duration and every slowdown with its limiting joint and constraint."""
    motion, robot, joints = plan.cell.motion, plan.robot, plan.joints
    t = plan.trajectory.t
    qd = robot.controller_joints(joints.qd)
    qdd = np.diff(qd, axis=0) / np.diff(t)[:, None]
    qddd = np.diff(qdd, axis=0) / np.diff(0.5 * (t[1:] + t[:-1]))[:, None]
    jerk_use = (np.abs(qddd) / robot.jerk_limits).max(axis=0) if len(t) > 2 else np.zeros(6)
    out = {
        "time_law": motion.time_law,
        "max_joint_jerk_use": jerk_use.round(4).tolist(),  # finite differences of qd
    }
    retiming = joints.retiming
    if motion.time_law != TimeLaw.TIME_OPTIMAL:
        return out
    sigma0, t0 = plan.law_origin
    return out | {
        "process": motion.process,
        # TOPP-RA under the joint velocity/acceleration limits, the TCP cap and the path
        # acceleration; then with the steady jerk limit as a speed limit curve too.
        "time_optimal_without_jerk_stage_s": retiming.topp_plain_s,
        "time_optimal_steady_jerk_s": retiming.topp.duration,
        "time_optimal_solve_s": retiming.solve_s,
        # Where the process speed is feasible (off the start/stop ramps, within the
        # joints' steady limits), the share of that length held within ±0.5 %.
        "process_speed_held": {
            "share_of_feasible_length": _finite_or_none(retiming.speed_held[0]),
            "feasible_share_of_path": _finite_or_none(retiming.speed_held[1]),
            "tolerance_percent": 100.0 * HOLD,
        },
        "slowdowns": [  # on the seam's scale (a flying seam's lead-in: σ, t < 0)
            {
                "sigma_start_m": slow.sigma_m[0] + sigma0,
                "sigma_end_m": slow.sigma_m[1] + sigma0,
                "t_start_s": slow.t_s[0] + t0,
                "t_end_s": slow.t_s[1] + t0,
                "speed_min_m_s": slow.speed_min_m_s,
                "joint": slow.joint,
                "constraint": slow.constraint,
                "limit_use": slow.use,
            }
            for slow in retiming.slowdowns
        ],
    }


def _finite_or_none(value: float) -> float | None:
    """JSON has no NaN: None for a value that does not exist."""
    return float(value) if np.isfinite(value) else None


def collision_summary(plan: Plan) -> dict:
    """report.json's collision keys: min_distance_m, collision_free, the closest pair."""
    result = plan.collisions
    closest = result.closest
    return {
        "collision_free": result.collision_free,
        "min_distance_m": result.min_distance_m if np.isfinite(result.min_distance_m) else None,
        "closest_pair": None
        if closest is None
        else {
            "pair": [closest.a, closest.b],
            "group": closest.group,
            "sigma_m": closest.sigma_m,
            "t_s": closest.t_s,
            "distance_m": closest.distance_m,
        },
        "clearance_m": result.clearance_m,
        "self_clearance_m": result.self_clearance_m,
        "self_collision_pairs_skipped": None
        if result.skipped_self_pairs is None
        else [
            {"pair": [p.a, p.b], "class": p.kind, "reason": p.reason}
            for p in result.skipped_self_pairs
        ],
        # The gripper on the flange link and the part in the gripper: held, not checked.
        "held_contacts_not_checked": [
            {"pair": [a, b], "reason": reason} for a, b, reason in result.held_contacts or []
        ],
        "feasible": plan.feasible,
        "failure": plan.failure,
        "failure_kind": None if plan.failure_kind is None else plan.failure_kind.value,
        "collision_avoidance": plan.avoidance,
    }


def payload_summary(cell, cell_file) -> dict:
    """The payload the programs set, or ``set: false`` and a warning (export.payload);
    the record of scene.payload (masses, centres of mass, inertias, their sources)."""
    record = payload_record(cell, cell_file)
    complete = payload(record) is not None
    warning = None if complete else payload_note(record, np.eye(4)).removeprefix("WARNING: ")
    return {"set": complete, "warning": warning, **record}


def gripper_summary(cell, cell_file) -> list[dict] | None:
    """The gripper's shapes in E for the report's views: name, kind, size_m (as
    ``CellShape.size_m``; a mesh: its bounding box's) and X_OG (4, 4), the shape in E
    [m]; None without a gripper."""
    shapes = gripper_shapes(cell, Path(cell_file).parent)
    if not shapes:
        return None
    out = []
    for shape in shapes:
        size, X_EG = list(shape.size_m), shape.X_OG.GetAsMatrix4()
        if shape.kind == "mesh":  # its bounding box, centred on the box
            low, high = shape.mesh.bounds
            size = (high - low).tolist()
            X_EG[:3, 3] += X_EG[:3, :3] @ ((low + high) / 2)
        out.append({"name": shape.name, "kind": shape.kind, "size_m": size, "X_OG": X_EG.tolist()})
    return out


def cad_summary(points) -> dict | None:
    """A cad: seam's model facts: what was picked, the exact length [m], the reference's
    tolerance [mm] and the corners between its edges (cusps of the path); else None."""
    exact = getattr(points, "exact", None)
    if exact is None:
        return None
    return {
        "model": exact.model,
        "length_m": exact.length_m,
        "reference_tolerance_mm": exact.tolerance_m * 1e3,
        "corners": [
            {"p_P_mm": [round(float(v) * 1e3, 3) for v in p], "turn_deg": round(turn, 3)}
            for p, turn in exact.corners
        ],
    }


def normal_fit_summary(plan: Plan) -> dict:
    """report.json's normal-fit keys: the angle from the given normals to the fitted
    field [deg] (0 for a constant path.normal, None for normals from part.mesh)."""
    fit = plan.normal_fit
    return {
        "normal_source": None if fit is None else fit.source,
        "normal_tolerance_deg": plan.cell.path.normal_tolerance_deg,
        "normal_max_error_deg": None if fit is None else fit.max_error_deg,
        "normal_rms_error_deg": None if fit is None else fit.rms_error_deg,
        "normal_worst_row": None if fit is None else fit.worst_row,
        # cad: seams: the fitted path's distance from the model's exact seam [mm]
        "edge_max_error_mm": None if fit is None else fit.edge_max_error_mm,
        "edge_rms_error_mm": None if fit is None else fit.edge_rms_error_mm,
        "edge_tangent_max_error_deg": None if fit is None else fit.edge_tangent_max_error_deg,
    }


def report(plan: Plan) -> dict:
    """The machine-readable plan summary (SI units unless the key says otherwise)."""
    cell, tr, fitted = plan.cell, plan.trajectory, plan.fitted
    law = tr.law
    sources = ("points", "dxf", "analytic", "cad")
    source = next(k for k in sources if getattr(cell.path, k) is not None)
    smoothing = None
    if hasattr(plan.flange, "max_deviation_m"):
        smoothing = {
            "max_deviation_mm": plan.flange.max_deviation_m * 1e3,
            "n_control_points": plan.flange.n_control_points,
        }
    return {
        "generator": f"offline_prog {__version__}",
        "generated": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "cell": str(plan.cell_file),
        "name": cell.name,
        "robot": cell.robot.model,
        **robot_source(plan.robot),
        "tool": cell.tool.name,
        "part": cell.part.name,
        "payload": payload_summary(cell, plan.cell_file),
        "gripper": gripper_summary(cell, plan.cell_file),
        "path": {
            "source": source,
            "n_points": int(len(plan.points.p_PR)),
            "closed": bool(cell.path.closed),
            "polygon_length_m": fitted.period,
            "length_m": plan.path.length,
            "cad": cad_summary(plan.points),
        },
        "fit": {
            "degree": fitted.degree,
            "n_control_points": fitted.n_control_points,
            "tolerance_mm": cell.path.fit_tolerance_mm,
            "max_error_mm": fitted.max_error_m * 1e3,
            "rms_error_mm": fitted.rms_error_m * 1e3,
            **normal_fit_summary(plan),
        },
        "motion": {
            "speed_reference": tr.reference,
            "limits": {
                "speed_m_s": law.v_max,
                "max_acceleration_m_s2": law.a_max,
                "max_jerk_m_s3": law.j_max,
            },
            "top_speed_m_s": law.v_peak,
            # The path is too short to reach the speed (with no joint limit).
            "top_speed_reduced": not without_joint_limits(law, cell.motion.time_law)[1],
            "sample_rate_hz": cell.motion.sample_rate_hz,
            # flying (lead-in and lead-out at the process speed) or rest, and why rest
            "entry": plan.entry,
        },
        "trajectory": {
            "duration_s": tr.duration,
            "n_samples": int(len(tr.t)),
            "max_flange_speed_m_s": float(np.linalg.norm(tr.v_IE, axis=1).max()),
            "max_flange_acceleration_m_s2": float(np.linalg.norm(tr.a_IE, axis=1).max()),
            "max_angular_speed_rad_s": float(np.linalg.norm(tr.w_IE_I, axis=1).max()),
            **speed_checks(plan),
        },
        "robot_motion": robot_report(plan),
        **collision_summary(plan),
        "cusps": [c.__dict__ for c in plan.cusps],
        "cusp_smoothing": smoothing,
        "timings_s": plan.timings_s,
    }
