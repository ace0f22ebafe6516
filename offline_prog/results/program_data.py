"""The finished plan as the program writers read it: the job's rows and each seam's
(``export.program.ProgramData``, ``export.job_program.JobProgramData``), poses in the
robot base B, saved as plan.npz + job.npz.

Frames: I inertial, B robot base, E flange, P part, F process frame, T the physical
fixed tool. X_BT = X_BI · X_IT and X_EP = X_PE⁻¹ from the cell; the tool frame in P on
every row is X_PT = (X_BT⁻¹ · X_BE · X_EP)⁻¹ (on a seam: its process frame, turned by
any free rotation about a symmetric tool's axis, since X_BE = X_BT · X_PT⁻¹ · X_EP⁻¹
holds by construction).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from offline_prog.config.cell import transform
from offline_prog.config.process_speed import approach_speed
from offline_prog.constants import TimeLaw
from offline_prog.export.densify import dense_grid
from offline_prog.export.job_program import JobProgramData, JobSegment
from offline_prog.export.program import ProgramData
from offline_prog.job.records import JobPlan, Plan
from offline_prog.robot.dense_joints import dense_joints
from offline_prog.robot.record import robot_record
from offline_prog.scene.payload import payload_record


def time_law_name(motion) -> str:
    """The time law as the program header names it: "sin2", or "time_optimal
    (constant_speed)" / "time_optimal (cycle_time)"."""
    if motion.time_law == TimeLaw.TIME_OPTIMAL:
        return f"time_optimal ({motion.process})"
    return motion.time_law


def program_names(cell, cell_file: Path, robot, summary: dict) -> dict:
    """The ProgramData fields that name the cell, robot, tool and part and carry the
    robot's limits and the payload (the same for a seam and a job)."""
    return {
        "cell_name": cell.name or Path(cell_file).stem,
        "cell_file": str(cell_file),
        "robot": robot.name,
        "tool": cell.tool.name,
        "part": cell.part.name,
        "process_speed_m_s": cell.motion.speed,
        "joint_names": tuple(robot.joint_names),
        "generated": summary["generated"],
        "q_lower": robot.q_lower,
        "q_upper": robot.q_upper,
        "qd_max": robot.qd_max,
        "j23_coupled": robot.j23_coupled,
        "j23_factor": robot.j23_factor,
        "robots_dir": str(robot.urdf_path.parent.parent),
        "language": robot.language,
        "payload": payload_record(cell, cell_file),
        "controller_frames": {
            "tool": cell.tool.controller_frame,
            "part": cell.part.controller_frame,
        },
        "robot_record": robot_record(robot),
        "link_speed_percent": cell.motion.link_speed_percent,
    }


def _header(plan: Plan | JobPlan, cell_file: Path, robot, summary: dict) -> dict:
    """The header fields of a seam's or the job's ProgramData: names, limits, payload,
    time law, and whether the plan passed its checks."""
    cell = plan.cell
    # A seam runs at its own process speed (config.process_speed); the job's rows
    # carry the cell's motion.speed.
    speed = getattr(plan, "process_speed", None)
    return {
        **program_names(cell, cell_file, robot, summary),
        **(
            {}
            if speed is None
            else {
                "process_speed_m_s": speed.v_m_s,
                "approach_speed_m_s": approach_speed(cell, speed).v_m_s,
            }
        ),
        "time_law": time_law_name(cell.motion),
        "feasible": plan.feasible,
        "failure": plan.failure,
    }


def _samples(t, path_m, q, qd, tcp_speed) -> dict:
    """The per-row fields of a ProgramData: t (N,) [s], path_m (N,) [m], q, qd (N, 6)
    [rad, rad/s], tcp_speed (N,) [m/s]."""
    return {"t": t, "path_m": path_m, "q": q, "qd": qd, "tcp_speed": tcp_speed}


def _frames(X_BT: np.ndarray, X_BE: np.ndarray, X_EP: np.ndarray) -> dict:
    """The pose fields of a ProgramData: the flange X_BE (N, 4, 4), the tool in the part
    X_PT (N, 4, 4), the tool X_BT and the part X_EP (4, 4)."""
    return {"X_BE": X_BE, "X_PT": _tool_in_part(X_BT, X_BE, X_EP), "X_BT": X_BT, "X_EP": X_EP}


def _tool_and_part(cell) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(X_BI, X_BT, X_EP) (4, 4) from the cell: the inertial frame and the physical tool
    in the robot base, the part in the flange."""
    X_BI = transform(cell.robot.X_IB).inverse().GetAsMatrix4()
    X_BT = X_BI @ transform(cell.tool.X_IT).GetAsMatrix4()
    X_EP = transform(cell.part.X_PE).inverse().GetAsMatrix4()
    return X_BI, X_BT, X_EP


def _tool_in_part(X_BT: np.ndarray, X_BE: np.ndarray, X_EP: np.ndarray) -> np.ndarray:
    """(N, 4, 4) X_PT of flange poses X_BE (N, 4, 4) (see the module docstring)."""
    return np.linalg.inv(np.linalg.inv(X_BT) @ X_BE @ X_EP)


def _poses(p: np.ndarray, R: np.ndarray) -> np.ndarray:
    X = np.zeros((len(p), 4, 4))
    X[:, :3, :3], X[:, :3, 3], X[:, 3, 3] = R, p, 1.0
    return X


def seam_rows(plan: Plan) -> tuple[np.ndarray, ...]:
    """(t (N,) [s] from the first row, σ (N,) [m], q, qd (N, 6), tcp_speed (N,) [m/s]) of
    a seam as the programs run it between its straight approach and retract: a flying
    seam's lead-in, its own rows and its lead-out (``job.lead_rows``: σ from −lead-in to
    L + lead-out; the shared rows once)."""
    joints, traj = plan.joints, plan.trajectory
    rows = (traj.s, joints.q, joints.qd, traj.tcp_speed)
    start = 0.0 if plan.lead_in is None else float(plan.lead_in.t[-1])  # the seam's σ = 0
    times, parts = [traj.t + start], [rows]
    if plan.lead_in is not None:
        lead = plan.lead_in
        times.insert(0, lead.t[:-1])
        parts.insert(0, tuple(x[:-1] for x in (lead.s, lead.q, lead.qd, lead.tcp_speed)))
    if plan.lead_out is not None:
        lead = plan.lead_out
        times.append(lead.t[1:] + start + traj.t[-1])
        parts.append(tuple(x[1:] for x in (lead.s, lead.q, lead.qd, lead.tcp_speed)))
    return (np.concatenate(times), *(np.concatenate([p[k] for p in parts]) for k in range(4)))


def seam_program_data(plan: Plan, summary: dict) -> ProgramData:
    """A seam as the writers read it: its samples (:func:`seam_rows`: a flying seam's
    leads included), and its continuous path on the dense grid (``export.densify``) with
    the joints planned there (no writer runs IK)."""
    cell = plan.cell
    t, s, q, qd, tcp_speed = seam_rows(plan)
    X_BI, X_BT, _ = _tool_and_part(cell)
    rows = plan.flange(s)  # the samples' own flange poses (a lead's too)
    X_BE = X_BI @ _poses(rows.p_IE, rows.R_IE)
    X_EP = plan.flange.X_PE.inverse().GetAsMatrix4()
    path_dense_m = s[0] + dense_grid(s[-1] - s[0])
    dense = plan.flange(path_dense_m)
    X_BE_dense = X_BI @ _poses(dense.p_IE, dense.R_IE)
    X_PT_dense = _tool_in_part(X_BT, X_BE_dense, X_EP)
    # The writers' inserted points: X_BE as export.densify computes it from X_PT_dense.
    X_BE_grid = X_BT @ np.linalg.inv(X_PT_dense) @ np.linalg.inv(X_EP)
    q_dense = dense_joints(plan.robot, s, t, q, qd, X_BE, path_dense_m, X_BE_grid)
    return ProgramData(
        **_header(plan, plan.cell_file, plan.robot, summary),
        speed_reference=plan.trajectory.reference,
        cycle_time_s=float(t[-1]),
        **_samples(t, s, q, qd, tcp_speed),
        **_frames(X_BT, X_BE, X_EP),
        path_dense_m=path_dense_m,
        X_PT_dense=X_PT_dense,
        q_dense=q_dense,
    )


def job_program_data(job: JobPlan, summary: dict) -> JobProgramData:
    """The job as the writers read it: every row (the flange poses the plan computed,
    the tool frame in P, the signed path position), its segments, link waypoints,
    process I/O, and each seam's data."""
    cell, s = job.cell, job.samples
    _, X_BT, X_EP = _tool_and_part(cell)
    rows = ProgramData(
        **_header(job, job.cell_file, job.robot, summary),
        speed_reference=cell.motion.speed_reference,
        cycle_time_s=float(s.t[-1]),
        **_samples(s.t, s.path_m, s.q, s.qd, job.tcp_speed),
        **_frames(X_BT, job.X_BE, X_EP),
        whole_job=True,
    )
    return JobProgramData(
        job=rows,
        segments=tuple(JobSegment(g.kind, g.seam, g.start, g.stop) for g in s.segments),
        seams=tuple(seam_program_data(o.plan, summary) for o in job.chosen),
        seam_names=tuple(o.name for o in job.chosen),
        seam_lengths_m=tuple(o.plan.path.length for o in job.chosen),
        link_waypoints=tuple(np.asarray(link.waypoints, dtype=float) for link in job.links),
        process_io=job.io.settings,
        digital=job.io.digital,
        analog=job.io.analog,
        events=tuple(job.io.events),
    )
