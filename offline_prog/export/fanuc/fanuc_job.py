"""FANUC TP programs of a whole job (LS text), in the frames and form of
:mod:`offline_prog.export.fanuc.fanuc_ls` (flange-style: UTOOL[1] = the part P in the
faceplate, positions = P in UFRAME[1] = base_link).

``<name>.ls``: ``J`` home; per seam the link (``J`` through its joint-represented
points, FINE: the planned, collision-checked joint moves) and ``CALL <name>_S<k>``: the
approach (``L`` to the seam's first point), the seam's ``L`` moves (the one-seam point
choice on the flange path) and the retract (``L``), in its own program so that no
program grows with the job; home at the end (the last link). Every ``L`` point is a
planned sample.

Process I/O, translated from the plan's I/O events (``io_events``), placed by
:mod:`offline_prog.export.fanuc.fanuc_io`:

- the digital output: FANUC's distance-before motion option on the motion whose end the
  event precedes, ``L P[i] ... DB d mm,DO[n]=ON`` (the output is set when the TCP comes
  within d of the destination: on these straight ``L`` moves, d before the end along the
  path). A motion takes one DB option: where two switches fall on one motion it is
  split at a planned sample between them.
- the flow: plain ``AO[n]=value`` statements before the motion they hold for; the value
  takes effect when the statement runs, as that motion starts (a motion starts at each
  flow edge: the planned sample nearest it is an ``L`` point). While the output is on
  (from the plan's flow-live event to its flow-idle event, both ``lag_s`` ahead of the
  output's switches, since FANUC does not lead by the dispenser's lag itself) each
  motion's value is the plan's flow (offset + per_mps · v, clipped, at the speed the
  tool has ``lag_s`` later) within ``fanuc_io.FLOW_STEP_V`` / 2 (a planned sample
  starts a new motion where the speed changes more); otherwise ``AO[n]`` is the idle
  value (``ProcessIo.idle``), set once at the program's start.
A time-before trigger (``TB t sec,...``) is not used: the events are distances.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.errors import InputError
from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M
from offline_prog.export.fanuc.fanuc import cartesian_pos, config_strings, fanuc_axes_deg, joint_pos
from offline_prog.export.fanuc.fanuc_io import Samples, place_events
from offline_prog.export.fanuc.fanuc_ls import (
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
from offline_prog.export.job_steps import JointMove, Process, job_steps
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

    def add(self, items: list) -> None:
        """Statements: a str as it is, or ((X_BP, config), rest) for ``L P[k] rest``."""
        for item in items:
            if isinstance(item, str):
                self.lines.append(item)
                continue
            (X_BP, config), rest = item
            k = len(self.positions) + 1
            self.positions.append(cartesian_pos(k, X_BP, config, uf=UF, ut=UT))
            self.lines.append(f"L P[{k}] {rest}")

    def text(self) -> str:
        return ls_text(self.name, self.lines, self.positions, "offline_prog")


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

    Raises:
        ValueError: a bad name or line limit, a robot that is not OPW.
        InputError: two process output switches that no planned sample separates
            (``fanuc_io``; names the cell file, the seam and both positions).
    """
    identifier(name, max_chars=NAME_MAX - 8, what="name")
    if line_limit < 8:
        raise ValueError(f"line_limit={line_limit}: need at least 8 lines per program")
    robot = data.load_robot()
    if robot.family != "opw":
        raise ValueError(f"data.robot={data.robot!r}: FANUC export needs an OPW robot")
    io = data.process_io
    flow = io is not None and io.analog_output is not None
    steps = job_steps(data, chord_tol_m, angle_tol_rad, style="flange")
    main, seams, seam_no = _Program(name), [], 0
    main.lines.append("  PAYLOAD[1]")
    if flow:  # the flow rests at its idle value until a seam's output goes on
        main.lines.append(f"  AO[{io.analog_output}]={io.idle:.3f}")
    main.joint(robot, steps[0].targets[0])
    for step in steps:
        if isinstance(step, JointMove):
            for q in step.targets[1:]:
                main.joint(robot, q)
        elif isinstance(step, Process):
            seam_no += 1
            chain = _Chain(data, step, robot)
            lines = chain.approach + chain.process + chain.retract
            parts = _seam_parts(f"{name}_S{seam_no}", lines, line_limit)
            seams += parts
            main.add([f"  CALL {part.name}" for part in parts])
    header = header_lines(data.job, conventions=_conventions(data, robot), forced=forced)
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


class _Chain:
    """A seam's ``L`` motions (approach, seam, retract) with its I/O events on them, as
    ``_Program.add`` items in ``approach``, ``process`` and ``retract``."""

    def __init__(self, data: JobProgramData, step: Process, robot):
        io, seam = data.process_io, step.seam
        samples, points, (n_a, n_p) = _samples(data, step)
        events = [e for e in data.events if e.seam == seam]
        try:
            motions = place_events(
                samples, points, events, seam=seam, io=io, flow_at=_flow_at(data)
            )
        except ValueError as error:  # the cell's switch positions: one line, exit 2
            raise InputError(data.job.cell_file, "tool.process_io", str(error)) from None
        configs = config_strings(robot, samples.q)
        speed = data.seams[data.seam_names.index(seam)].process_speed_m_s  # approach, retract
        process = [m.end for m in motions if n_a < m.end <= n_p]
        speeds = dict(
            zip(
                process,
                segment_speeds_mms(samples.t, samples.X_BP, np.array([n_a, *process])),
                strict=True,
            )
        )
        self.approach, self.process, self.retract = [], [], []
        current = None if io is None else io.idle
        for m in motions:
            part = self.approach if m.end <= n_a else self.process if m.end <= n_p else self.retract
            if m.flow is not None and f"{m.flow:.3f}" != f"{current:.3f}":
                part.append(f"  AO[{io.analog_output}]={m.flow:.3f}")
                current = m.flow
            last = m.end in (n_a, n_p, len(samples.sigma) - 1)
            mms = speeds.get(m.end, max(1, int(round(speed * 1e3))))
            option = "" if m.event is None else _db(m)
            entry = (samples.X_BP[m.end], configs[m.end])
            part.append((entry, f"{mms}mm/sec {'FINE' if last else 'CNT100'}{option}"))
        if current is not None and f"{current:.3f}" != f"{io.idle:.3f}":
            self.retract.append(f"  AO[{io.analog_output}]={io.idle:.3f}")


def _db(motion) -> str:
    """FANUC's distance-before option switching the digital output."""
    state = "ON" if motion.event.state else "OFF"
    return f" DB {motion.before_end_m * 1e3:.1f}mm,DO[{motion.event.output}]={state}"


def _samples(data: JobProgramData, step: Process):
    """The seam's planned samples from its approach's start (the link's end) to its
    retract's end: the job's approach rows, the seam's densified samples, the job's
    retract rows; the L points before splitting; the indices of the seam's first and
    last sample."""
    segments = {s.kind: s for s in data.segments if s.seam == step.seam}
    rows, dense = data.job, step.data
    a_rows = np.arange(segments["approach"].start, segments["approach"].stop)
    retract = segments["retract"]
    r_rows = np.arange(retract.start + 1, min(retract.stop, len(rows.t) - 1) + 1)
    t0 = rows.t[segments["process"].start] - dense.t[0]
    sigma_r = rows.sigma[r_rows].copy()
    if np.isnan(sigma_r[-1]):  # the retract's end is the next link's first row
        gap = np.linalg.norm(rows.X_PF[r_rows[-1], :3, 3] - rows.X_PF[r_rows[-2], :3, 3])
        sigma_r[-1] = sigma_r[-2] + gap
    samples = Samples(
        sigma=np.concatenate([rows.sigma[a_rows], dense.sigma, sigma_r]),
        t=np.concatenate([rows.t[a_rows], dense.t + t0, rows.t[r_rows]]),
        q=np.concatenate([rows.q[a_rows], dense.q, rows.q[r_rows]]),
        X_BP=np.concatenate([rows.X_BE[a_rows], dense.X_BE, rows.X_BE[r_rows]]) @ rows.X_EP,
    )
    n_a = len(a_rows) + int(step.indices[0])
    n_p = len(a_rows) + int(step.indices[-1])
    points = [0, *(len(a_rows) + step.indices), len(samples.sigma) - 1]
    return samples, points, (n_a, n_p)


def _flow_at(data: JobProgramData):
    """The live flow [V] at job times (n,) [s]: the plan's flow at the speed the tool
    has ``lag_s`` later, as the plan's ``ao`` column holds it while live."""
    io, t, v = data.process_io, data.job.t, data.job.tcp_speed
    if io is None or io.analog_output is None:
        return None
    return lambda times: io.flow(np.interp(np.asarray(times) + io.lag_s, t, v))


def _seam_parts(name: str, lines: list, line_limit: int) -> list[_Program]:
    """The seam's statements in programs of at most line_limit lines (``name``, or
    ``name_1``, ``name_2`` ... called in turn)."""
    parts = [_Program(name)]
    for line in lines:
        if len(parts[-1].lines) + 2 > line_limit:  # an AO and its move stay together
            parts.append(_Program(f"{name}_{len(parts) + 1}"))
        parts[-1].add([line])
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
            f"Process output DO[{io.digital_output}]: DB (distance before), on "
            f"{io.on_lead_m * 1e3:g} mm before each seam's start, off {io.off_lead_m * 1e3:g} mm "
            "before its end; one DB per motion (split at planned samples)."
        )
    if io is not None and io.analog_output is not None:
        lines.append(
            f"Flow AO[{io.analog_output}] = {io.offset:g} + {io.per_mps:g} x TCP speed [m/s], "
            f"in [{io.min:g}, {io.max:g}] while DO is on, {io.idle:g} otherwise; AO "
            f"statements take effect as the next motion starts, {io.lag_s:g} s ahead."
        )
    return lines + payload_conventions(data.job)
