"""FANUC TP programs of a whole job (LS text), in the frames and form of
:mod:`offline_prog.export.fanuc_ls` (flange-style: UTOOL[1] = the part P in the
faceplate, positions = P in UFRAME[1] = base_link).

``<name>.ls``: ``J`` home; per seam the link (``J`` through its joint-represented
points, FINE: the planned, collision-checked joint moves), the approach (``L`` to the
seam's first point), ``CALL <name>_S<k>`` (the seam's ``L`` moves, the one-seam point
choice on the flange path, in its own program so that no program grows with the job),
the retract (``L``); home at the end (the last link).

Process I/O (the job writers' switch events, ``export.job_steps``): a switch ``d`` mm
before the end of a move is FANUC's distance-before motion option on that move,
``L P[i] ... DB d mm,DO[n]=ON`` (the output is set when the TCP comes within d of the
destination; on the straight ``L`` moves here that is d before the end along the path).
The flow output ``AO[n]`` follows the planned speed of the tool on the part: before each
process move an ``AO[n]=value`` statement sets offset + per_mps · v (clipped to the
cell's [min, max]) for the segment that move starts; ``AO[n]=0`` after the seam's last
move. A time-before trigger (``TB t sec,...``) is not used: the events are distances.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M
from offline_prog.export.fanuc import cartesian_pos, config_strings, fanuc_axes_deg, joint_pos
from offline_prog.export.fanuc_ls import (
    DEFAULT_LINE_LIMIT,
    JOINT_SPEED_PCT,
    NAME_MAX,
    UF,
    UT,
    frame_conventions,
    ls_text,
    payload_conventions,
    remarks,
    segment_speeds_mms,
)
from offline_prog.export.header import header_lines
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.job_steps import JointMove, LinearMove, Process, job_steps
from offline_prog.export.text import identifier


class _Program:
    """One LS program being written: statements and its own /POS entries."""

    def __init__(self, name: str):
        self.name, self.lines, self.positions = (
            name,
            [f"  UFRAME_NUM={UF}", f"  UTOOL_NUM={UT}"],
            [],
        )

    def joint(self, robot, q: np.ndarray) -> None:
        k = len(self.positions) + 1
        self.positions.append(joint_pos(k, fanuc_axes_deg(robot, q[None])[0], uf=UF, ut=UT))
        self.lines.append(f"J P[{k}] {JOINT_SPEED_PCT}% FINE")

    def linear(self, X_BP, config: str, speed_mms: int, term: str, option: str = "") -> None:
        k = len(self.positions) + 1
        self.positions.append(cartesian_pos(k, X_BP, config, uf=UF, ut=UT))
        self.lines.append(f"L P[{k}] {speed_mms}mm/sec {term}{option}")

    def text(self) -> str:
        return ls_text(self.name, self.lines, self.positions, "offline_prog")


def _db(switch) -> str:
    state = "ON" if switch.state else "OFF"
    return f" DB {switch.before_end_m * 1e3:.1f}mm,DO[{switch.output}]={state}"


def write_fanuc_job(
    data: JobProgramData,
    out_dir: Path,
    *,
    name: str = "OFFLINE_PROG",
    chord_tol_m: float = DEFAULT_CHORD_TOL_M,
    angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD,
    line_limit: int = DEFAULT_LINE_LIMIT,
    forced: bool = False,
) -> list[Path]:
    """Write ``<name>.ls`` and one ``<name>_S<k>.ls`` per seam (``<name>_S<k>_<j>.ls``,
    called in turn, where a seam's moves exceed ``line_limit`` lines); returns the files.
    """
    identifier(name, max_chars=NAME_MAX - 8, what="name")
    if line_limit < 8:
        raise ValueError(f"line_limit={line_limit}: need at least 8 lines per program")
    robot = data.load_robot()
    if robot.family != "opw":
        raise ValueError(f"data.robot={data.robot!r}: FANUC export needs an OPW robot")
    job, io = data.job, data.process_io
    flow = io is not None and io.analog_output is not None
    steps = job_steps(data, chord_tol_m, angle_tol_rad, style="flange")
    main, seams, seam_no = _Program(name), [], 0
    main.lines.append("  PAYLOAD[1]")
    main.joint(robot, steps[0].targets[0])
    for step in steps:
        if isinstance(step, JointMove):
            for q in step.targets[1:]:
                main.joint(robot, q)
        elif isinstance(step, LinearMove):
            seam_no += step.kind == "approach"
            X_BP = robot.forward(step.q[None])[0] @ job.X_EP
            option = "".join(_db(s) for s in step.switches[:1])
            speed = max(1, int(round(step.speed_m_s * 1e3)))
            main.linear(X_BP, config_strings(robot, step.q[None])[0], speed, "FINE", option)
        else:
            parts = _seam(f"{name}_S{seam_no}", step, robot, io if flow else None, line_limit)
            seams += parts
            main.lines += [f"  CALL {part.name}" for part in parts]
    header = header_lines(job, conventions=_conventions(data, robot), forced=forced)
    main.lines[2:2] = remarks(header)
    if len(main.lines) > line_limit:
        raise ValueError(
            f"line_limit={line_limit}: the main program alone needs {len(main.lines)} lines"
        )
    files = []
    for program in [main, *seams]:
        files.append(Path(out_dir) / f"{program.name}.ls")
        write_atomic(files[-1], program.text())
    return files


def _seam(name: str, step: Process, robot, io, line_limit: int) -> list[_Program]:
    """The seam's L moves from its first point (the approach's end) on, in programs of
    at most line_limit lines (``name``, or ``name_1``, ``name_2`` ... called in turn)."""
    parts = [_Program(name)]
    data, idx = step.data, step.indices
    X_BP = data.X_BE @ data.X_EP
    configs = config_strings(robot, data.q[idx])
    speeds = segment_speeds_mms(data.t, X_BP, idx)
    by_move = {s.move: s for s in step.switches}
    for m in range(1, len(idx)):
        if len(parts[-1].lines) + 3 > line_limit:  # AO, the move, and a closing AO
            parts.append(_Program(f"{name}_{len(parts) + 1}"))
        sub = parts[-1]
        if io is not None:
            a, b = idx[m - 1], idx[m]
            v = np.trapezoid(data.tcp_speed[a : b + 1], data.t[a : b + 1]) / max(
                data.t[b] - data.t[a], 1e-9
            )
            value = float(np.clip(io.offset + io.per_mps * v, io.min, io.max))
            sub.lines.append(f"  AO[{io.analog_output}]={value:.3f}")
        term = "FINE" if m == len(idx) - 1 else "CNT100"
        option = _db(by_move[m]) if m in by_move else ""
        sub.linear(X_BP[idx[m]], configs[m], int(speeds[m - 1]), term, option)
    if io is not None:
        parts[-1].lines.append(f"  AO[{io.analog_output}]=0")
    if len(parts) > 1:
        parts[0].name = f"{name}_1"
    return parts


def _conventions(data: JobProgramData, robot) -> list[str]:
    io = data.process_io
    lines = [
        f"Job: {len(data.seam_names)} seams in this order: {', '.join(data.seam_names)}.",
        *frame_conventions(robot, data.job.X_EP),
        f"Links: J to joint positions, {JOINT_SPEED_PCT}%, FINE; approach, seams, retract: "
        "L at the planned speeds of P.",
    ]
    if io is not None and io.digital_output is not None:
        lines.append(
            f"Process output DO[{io.digital_output}]: DB (distance before) on "
            f"{io.on_lead_m * 1e3:g} mm before each seam's start, off {io.off_lead_m * 1e3:g} mm "
            "before its end."
        )
    if io is not None and io.analog_output is not None:
        lines.append(
            f"Flow AO[{io.analog_output}] = {io.offset:g} + {io.per_mps:g} x TCP speed [m/s], "
            f"in [{io.min:g}, {io.max:g}], set before each process move; 0 after each seam."
        )
    return lines + payload_conventions(data.job)
