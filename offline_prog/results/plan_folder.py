"""The plan folder: trajectory.csv, report.json, collisions, programs, preview, report.html.

The whole folder is written as a temporary sibling and swapped in at the end
(``atomic.staged_folder``): a crash or Ctrl-C leaves the previous complete folder, and a
re-plan leaves no file of an older run. The folder's manifest lists what we wrote; a
folder holding anything else is not replaced (we delete only our own files).
"""

from __future__ import annotations

import io
import json
import os
from pathlib import Path

import numpy as np

from offline_prog.atomic import (
    MANIFEST,
    TEMP_PREFIX,
    read_manifest,
    staged_folder,
    write_atomic,
    write_manifest,
)
from offline_prog.collision.check import write_collisions_json
from offline_prog.config.cell import transform
from offline_prog.constants import TimeLaw
from offline_prog.errors import InputError
from offline_prog.export.densify import dense_grid
from offline_prog.export.formats import PROGRAMS_DIR, default_formats, export
from offline_prog.export.program import ProgramData
from offline_prog.job.records import Plan
from offline_prog.results.report import report
from offline_prog.robot.dense_joints import dense_joints
from offline_prog.robot.record import robot_record
from offline_prog.scene.payload import payload_record
from offline_prog.timing.trajectory import CSV_COLUMNS
from offline_prog.viz.preview import write_preview_html
from offline_prog.viz.report_html import write_report_html


def csv_columns(n_joints: int) -> list[str]:
    """CSV_COLUMNS then q1..qN [rad] and qd1..qdN [rad/s] in the URDF's joint order."""
    return [
        *CSV_COLUMNS,
        *(f"q{i + 1}" for i in range(n_joints)),
        *(f"qd{i + 1}" for i in range(n_joints)),
    ]


def trajectory_csv(plan: Plan) -> str:
    """CSV text: header csv_columns, one row per sample, SI units (s, m, rad)."""
    buffer = io.StringIO()
    joints = plan.joints
    np.savetxt(
        buffer,
        np.hstack([plan.trajectory.table(), joints.q, joints.qd]),
        delimiter=",",
        fmt="%.10g",
        header=",".join(csv_columns(joints.q.shape[1])),
        comments="",
    )
    return buffer.getvalue()


def clearance_csv(t: np.ndarray, profile: dict[str, np.ndarray]) -> str:
    """``t_s,<group>_m,...``: the smallest distance per pair group over time [m]."""
    buffer = io.StringIO()
    groups = list(profile)
    table = np.column_stack(
        [t, *(np.where(np.isfinite(profile[g]), profile[g], np.nan) for g in groups)]
    )
    np.savetxt(
        buffer,
        table,
        delimiter=",",
        fmt="%.9g",
        header=",".join(["t_s", *(f"{g}_m" for g in groups)]),
        comments="",
    )
    return buffer.getvalue()


def _poses(p: np.ndarray, R: np.ndarray) -> np.ndarray:
    X = np.zeros((len(p), 4, 4))
    X[:, :3, :3], X[:, :3, 3], X[:, 3, 3] = R, p, 1.0
    return X


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
        "robot_record": robot_record(robot),
    }


def program_data(plan: Plan, summary: dict) -> ProgramData:
    """The plan as the program writers need it (poses in the robot base B)."""
    cell, joints, traj = plan.cell, plan.joints, plan.trajectory
    X_IB = transform(cell.robot.X_IB)
    X_BI = X_IB.inverse().GetAsMatrix4()
    X_BE = X_BI @ _poses(traj.flange.p_IE, traj.flange.R_IE)
    # The physical tool T, and the part frames that sit on it: X_BE = X_BT X_PF⁻¹ X_EP⁻¹
    # holds by construction, whatever rotation about a symmetric tool's axis was used.
    X_BT = X_BI @ transform(cell.tool.X_IT).GetAsMatrix4()
    X_EP = plan.flange.X_PE.inverse().GetAsMatrix4()
    X_PF = np.linalg.inv(np.linalg.inv(X_BT) @ X_BE @ X_EP)
    s_dense = dense_grid(plan.path.length)
    dense = plan.flange(s_dense)
    X_BE_dense = X_BI @ _poses(dense.p_IE, dense.R_IE)
    X_PF_dense = np.linalg.inv(np.linalg.inv(X_BT) @ X_BE_dense @ X_EP)
    # The writers' inserted points: X_BE as export.densify computes it from X_PF_dense.
    X_BE_grid = X_BT @ np.linalg.inv(X_PF_dense) @ np.linalg.inv(X_EP)
    q_dense = dense_joints(
        plan.robot, traj.s, traj.t, joints.q, joints.qd, X_BE, s_dense, X_BE_grid
    )
    return ProgramData(
        **program_names(cell, plan.cell_file, plan.robot, summary),
        speed_reference=traj.reference,
        cycle_time_s=traj.duration,
        time_law=time_law_name(cell.motion),
        feasible=plan.feasible,
        failure=plan.failure,
        t=traj.t,
        sigma=traj.s,
        q=joints.q,
        qd=joints.qd,
        X_BE=X_BE,
        X_PF=X_PF,
        X_BT=X_BT,
        X_EP=X_EP,
        tcp_speed=traj.tcp_speed,
        sigma_dense=s_dense,
        X_PF_dense=X_PF_dense,
        q_dense=q_dense,
    )


def check_out_dir(out_dir: Path) -> None:
    """Refuse an --out that is a file, or a folder with files we did not write.

    Raises:
        InputError: naming the folder and what is in the way.
    """
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(out_dir, "--out", "exists and is not a folder")
    parent = out_dir.absolute().parent  # the folder is swapped in there
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(out_dir, "--out", f"cannot write into {parent} (permission denied)")
    if not out_dir.is_dir():
        return
    entries = {e.name for e in out_dir.iterdir() if not e.name.startswith(TEMP_PREFIX)}
    manifest = read_manifest(out_dir)
    owned = set((manifest or {}).get("files", {}).get("plan", [])) | {MANIFEST}
    foreign = sorted(entries - owned)
    if foreign:
        raise InputError(
            out_dir,
            "--out",
            f"holds files offline_prog did not write ({', '.join(foreign[:3])}"
            f"{', ...' if len(foreign) > 3 else ''}); choose an empty or new folder",
        )


def write_outputs(plan: Plan, out_dir: Path) -> tuple[dict[str, Path], dict]:
    """Write the plan folder ``out_dir`` (replacing an earlier plan folder there).

    Returns:
        The written files by name (paths in out_dir), and the report in report.json.

    Raises:
        InputError: out_dir is a file, or a folder with files we did not write.
    """
    out_dir = Path(out_dir)
    check_out_dir(out_dir)
    with staged_folder(out_dir) as folder:
        files, summary = _write_all(plan, folder, folder_name=out_dir.name)
        names = sorted({path.relative_to(folder).parts[0] for path in files.values()})
        write_manifest(folder, {"plan": names})
    return {key: out_dir / path.relative_to(folder) for key, path in files.items()}, summary


def _write_all(plan: Plan, out_dir: Path, *, folder_name: str) -> tuple[dict[str, Path], dict]:
    """Every output of the plan, into the (fresh, staged) folder out_dir, which the
    user will see as ``folder_name``."""
    files = {
        "trajectory": out_dir / "trajectory.csv",
        "report": out_dir / "report.json",
        "collisions": out_dir / "collisions.json",
    }
    # preview.html needs nothing the other outputs write: the second core draws it.
    files["preview"] = out_dir / "preview.html"
    # An error or Ctrl-C in the block stops the child before the folder goes.
    with InParallel(lambda: write_preview_html(plan, files["preview"])) as preview:
        summary = _write_rest(plan, out_dir, files, folder_name=folder_name)
        preview.wait()
    return files, summary


def _write_rest(plan: Plan, out_dir: Path, files: dict[str, Path], *, folder_name: str) -> dict:
    """Everything but preview.html, into ``files``; returns the report."""
    summary = report(plan)
    write_atomic(files["trajectory"], trajectory_csv(plan))
    write_collisions_json(plan.collisions, files["collisions"])
    if plan.clearance_profile is not None:
        files["clearance"] = out_dir / "clearance.csv"
        write_atomic(files["clearance"], clearance_csv(*plan.clearance_profile))
    write_atomic(files["report"], json.dumps(summary, indent=2) + "\n")
    data = program_data(plan, summary)
    files["plan"] = data.save(out_dir)
    if data.feasible:  # no program from a failed plan (offline-prog export --force can)
        for fmt in default_formats(data.language):
            for file in export(data, fmt, out_dir / PROGRAMS_DIR):
                files[f"{fmt}:{file.name}"] = file
    # After the programs: it lists them.
    files["report_html"] = write_report_html(out_dir, folder_name=folder_name)
    return summary


class InParallel:
    """``function()`` running in a forked child process (the plan is shared
    copy-on-write: nothing is pickled); where fork is not available it runs at once.

    ``wait()`` blocks until it is done and raises the child's error here, as it was (an
    OSError keeps its path; RuntimeError if it cannot travel). ``cancel()`` stops it:
    a folder is never removed while the child still writes into it. Used as a context
    manager, leaving the block by any error or Ctrl-C cancels it.
    """

    def __init__(self, function):
        import multiprocessing

        self.process = None
        if "fork" not in multiprocessing.get_all_start_methods():
            function()
            return
        context = multiprocessing.get_context("fork")
        self.receive, send = context.Pipe(duplex=False)

        def child() -> None:
            try:
                function()
                send.send("")
            except BaseException as error:  # raised by wait(), in the parent
                try:
                    send.send(error)
                except Exception:  # not picklable: its text
                    send.send(f"{type(error).__name__}: {error}")

        self.process = context.Process(target=child, daemon=True)
        self.process.start()
        send.close()

    def wait(self) -> None:
        if self.process is None:
            return
        try:
            message = self.receive.recv()
        except EOFError:
            message = "the writer process ended without a word"
        self.process.join()
        self.process = None
        if isinstance(message, BaseException):
            raise message
        if message:
            raise RuntimeError(message)

    def cancel(self) -> None:
        if self.process is not None:
            self.process.terminate()
            self.process.join()
            self.process = None

    def __enter__(self) -> InParallel:
        return self

    def __exit__(self, *exc_info) -> None:
        self.cancel()
