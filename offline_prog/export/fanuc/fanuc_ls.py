"""FANUC TP programs of a job as LS text (``/PROG … /ATTR … /MN … /POS … /END``).

Form: **flange-style, dense point list**. FANUC sells a Remote TCP option for a robot
that carries the part past a fixed tool, but this writer has no FANUC document at hand
to cite for its instructions, so it does not use it (the issue's rule: cite the source
or write the flange form and say so). The frames are the controller's, by number
(``export.fanuc.fanuc_frames``): ``UFRAME_NUM`` = ``tool.controller_frame`` (the fixed
tool T as the user frame), ``UTOOL_NUM`` = ``part.controller_frame`` (the part P in the
faceplate as the tool frame), and every position is the part frame's pose in the user
frame, X_TP = X_BT⁻¹ · X_BE · X_EP; the nominal values of the two frames are in
``<name>_FRAMES.ls`` only. The controller interpolates P linearly between the points
while the tool stays fixed, so the points are split until the tool's curve on the part
also stays within the chord and angle tolerances (``PointRule("flange")``). Speeds are
each segment's planned mean speed of P's origin [mm/sec] (approach and retract too);
CNT100 between points, FINE at
the ends of each move.

``<name>.ls``: ``J`` home; per seam the link (``J`` through its joint-represented
points, FINE: the planned, collision-checked joint moves) and ``CALL <name>_S<k>``: the
approach (``L`` to the seam's first point), the seam's ``L`` moves and the retract
(``L``), in its own program so that no program grows with the job; home at the end (the
last link). Every ``L`` point is a planned sample. With a ``line_limit``, a seam's moves
beyond that many lines go to ``<name>_S<k>_<j>``, called in turn (no FANUC document we
found states a limit, so there is no default: the user sets the controller's).

Process I/O, translated from the plan's I/O events (``io_events``), placed by
:mod:`offline_prog.export.fanuc.fanuc_io`:

- the digital output: FANUC's distance-before motion option on the motion whose end the
  event precedes, ``L P[i] ... DB d mm,DO[n]=ON`` (the output is set when the TCP comes
  within d of the destination). The TCP is UTOOL's point, P's origin, not the tool's
  point on the part, so d is the TCP's distance to the destination where the tool is at
  the event's position on the seam (``fanuc_io.tcp_before_end``): where the part turns,
  that differs from the distance along the seam. A motion takes one DB option: where two
  switches fall on one motion it is split at a planned sample between them.
- the flow: plain ``AO[n]=value`` statements before the motion they hold for; the value
  takes effect when the statement runs, as that motion starts (a motion starts at each
  flow edge: the planned sample nearest it is an ``L`` point). While the output is on
  (from the plan's flow-live event to its flow-idle event, both ``lag_s`` ahead of the
  output's switches, since FANUC does not lead by the dispenser's lag itself) each
  motion's value is the plan's flow (offset + per_mps · v, clipped, at the speed the
  tool has ``lag_s`` later) within ``fanuc_io.FLOW_STEP_V`` / 2 (a planned sample
  starts a new motion where the speed changes more, but no motion shorter than 0.5 mm:
  near rest the steps are coarser and ``fanuc_flow`` picks values the dispenser's lag
  smooths into the plan's flow); otherwise ``AO[n]`` is the idle value
  (``ProcessIo.idle``), set once at the program's start.
A time-before trigger (``TB t sec,...``) is not used: the events are distances.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.errors import InputError
from offline_prog.export.fanuc.fanuc import (
    cartesian_pos,
    config_strings,
    fanuc_axes_deg,
    joint_pos,
    ls_text,
    remarks,
)
from offline_prog.export.fanuc.fanuc_frames import (
    FRAMES_SUFFIX,
    X_WB,
    frame_conventions,
    frames_program,
)
from offline_prog.export.fanuc.fanuc_io import Samples, place_events
from offline_prog.export.frames import ControllerFrames, controller_frames
from offline_prog.export.merge import PathCheck
from offline_prog.export.points import PointRule
from offline_prog.export.post import ControllerPost, PointOptions
from offline_prog.export.record import JointMove, ProgramRecord, SeamRun, Switch
from offline_prog.export.run_samples import run_samples
from offline_prog.export.split import check_line_limit

NAME_MAX = 36  # program names: letters, digits, _; this writer keeps 36 characters at most
JOINT_SPEED_PCT = 20  # J moves of the links
MIN_SPEED_MMS, MAX_SPEED_MMS = 1, 2000  # FANUC L moves take 1 to 2000 mm/sec


@dataclasses.dataclass(frozen=True)
class FanucOptions(PointOptions):
    """name: the main program; line_limit: most /MN lines of one program, or None (no
    split)."""

    name: str = "OFFLINE_PROG"
    line_limit: int | None = None


class _Program:
    """One LS program being written: statements and its own /POS entries, in the user
    frame and tool frame numbered ``frames`` (``export.fanuc.fanuc_frames``)."""

    def __init__(self, name: str, frames: ControllerFrames):
        self.name, self.uf, self.ut = name, frames.tool, frames.part
        self.lines = [f"  UFRAME_NUM={self.uf}", f"  UTOOL_NUM={self.ut}"]
        self.positions = []

    def joint(self, robot, q: np.ndarray) -> None:
        k = len(self.positions) + 1
        self.positions.append(
            joint_pos(k, fanuc_axes_deg(robot, q[None])[0], uf=self.uf, ut=self.ut)
        )
        self.lines.append(f"J P[{k}] {JOINT_SPEED_PCT}% FINE")

    def add(self, items: list) -> None:
        """Statements: a str as it is, or ((X_TP, config), rest) for ``L P[k] rest``."""
        for item in items:
            if isinstance(item, str):
                self.lines.append(item)
                continue
            (X_TP, config), rest = item
            k = len(self.positions) + 1
            self.positions.append(cartesian_pos(k, X_TP, config, uf=self.uf, ut=self.ut))
            self.lines.append(f"L P[{k}] {rest}")

    def text(self) -> str:
        return ls_text(self.name, self.lines, self.positions, "offline_prog")


class FanucPost(ControllerPost):
    """The LS programs of a job (see the module docstring)."""

    FORMAT = "fanuc"
    Options = FanucOptions
    NAME_MAX = NAME_MAX - 8

    def __init__(self, job, options: FanucOptions, **flags):
        super().__init__(job, options, **flags)
        check_line_limit(options.line_limit)
        self.numbers = controller_frames(job.job)
        self.main, self.seams = _Program(options.name, self.numbers), []

    def point_rule(self) -> PointRule:
        return PointRule("flange", "X_TP", self.options.chord_tol_m, self.options.angle_tol_rad)

    def conventions(self, record: ProgramRecord) -> list[str]:
        io, rows, names = record.job.process_io, record.job.job, record.job.seam_names
        lines = [
            f"Job: {len(names)} seams in this order: {', '.join(names)}.",
            *frame_conventions(
                self.robot, self.numbers, frames_program_name=self._frames_name() + ".ls"
            ),
            f"Links: J to joint positions, {JOINT_SPEED_PCT}%, FINE; approach, seams, retract: "
            "L at the planned speeds of P.",
        ]
        if io is not None and io.digital_output is not None:
            lines.append(
                f"Process output DO[{io.digital_output}]: DB (distance before), on "
                f"{io.on_lead_m * 1e3:g} mm before each seam's start, off "
                f"{io.off_lead_m * 1e3:g} mm before its end; DB is the TCP's (P origin's) "
                "distance to the motion's end there; one DB per motion (split at planned "
                "samples)."
            )
        if io is not None and io.analog_output is not None:
            lines.append(
                f"Flow AO[{io.analog_output}] = {io.offset:g} + {io.per_mps:g} x TCP speed "
                f"[m/s], in [{io.min:g}, {io.max:g}] while DO is on, {io.idle:g} otherwise; AO "
                f"statements take effect as the next motion starts, {io.lag_s:g} s ahead."
            )
            lines.append(
                f"AO[{io.analog_output}] values in counts: {io.counts_per_volt:g} counts per V "
                "(tool.process_io.flow.ao_unit)."
                if io.ao_unit == "counts"
                else f"AO[{io.analog_output}] values in volts (tool.process_io.flow.ao_unit)."
            )
        return lines + payload_conventions(self.load, rows.X_EP)

    def header(self, lines: list[str]) -> None:
        self.head = lines
        self.main.lines += remarks(lines)

    def frames(self) -> None:
        """UFRAME/UTOOL (in every program's head), the payload schedule, the flow idle."""
        io = self.job.process_io
        if self.load is not None:
            self.main.lines.append("  PAYLOAD[1]")
        if io is not None and io.analog_output is not None:  # idle until a seam's output
            self.main.lines.append(self.ao_statement(io.idle))

    def move_joint(self, move: JointMove) -> None:
        for q in move.targets:
            self.main.joint(self.robot, q)

    def seam(self, run: SeamRun) -> None:
        """``CALL`` the seam's program(s): its approach, points and retract as ``L``
        motions with the I/O on them (``fanuc_io``)."""
        chain = _Chain(self, run)
        parts = self._parts(f"{self.options.name}_S{run.number}", chain.lines)
        self.seams += parts
        self.main.add([f"  CALL {part.name}" for part in parts])

    def set_output(self, switch: Switch) -> str:
        """FANUC's distance-before option on the motion the switch is on."""
        state = "ON" if switch.event.state else "OFF"
        return f" DB {switch.before_end_m * 1e3:.1f}mm,DO[{switch.event.output}]={state}"

    def follow_speed(self, switch: Switch) -> str:
        """The flow's value from the motion the statement precedes on (FANUC has no
        speed-following output: the plan's flow values are written as the tool moves)."""
        return self.ao_statement(switch.event.value)

    def footer(self, out_dir: Path) -> list[Path]:
        limit = self.options.line_limit
        if limit is not None and len(self.main.lines) > limit:
            raise ValueError(
                f"line_limit={limit}: the main program alone needs {len(self.main.lines)} lines"
            )
        files = []
        for program in [self.main, *self.seams]:
            files.append(out_dir / f"{program.name}.ls")
            write_atomic(files[-1], program.text())
        rows = self.job.job
        files.append(out_dir / f"{self._frames_name()}.ls")
        text = frames_program(
            self._frames_name(),
            self.head,
            X_WT=X_WB(self.robot) @ rows.X_BT,
            X_EP=rows.X_EP,
            numbers=self.numbers,
        )
        write_atomic(files[-1], text)
        return files

    def _frames_name(self) -> str:
        """The nominal frames' program: ``<NAME>_FRAMES``."""
        return f"{self.options.name}{FRAMES_SUFFIX}"

    def ao_statement(self, value_v: float) -> str:
        """``AO[n]=value`` of the flow output at value_v [V], in the cell's
        ``flow.ao_unit``: volts, or whole counts (counts_per_volt per V)."""
        io = self.job.process_io
        if io.ao_unit == "counts":
            return f"  AO[{io.analog_output}]={round(value_v * io.counts_per_volt):d}"
        return f"  AO[{io.analog_output}]={value_v:.3f}"

    def _parts(self, name: str, lines: list) -> list[_Program]:
        """The seam's statements in programs of at most line_limit lines (``name``, or
        ``name_1``, ``name_2`` ... called in turn)."""
        parts, limit = [_Program(name, self.numbers)], self.options.line_limit
        for line in lines:
            if limit is not None and len(parts[-1].lines) + 2 > limit:  # an AO and its move
                parts.append(_Program(f"{name}_{len(parts) + 1}", self.numbers))
            parts[-1].add([line])
        if len(parts) > 1:
            parts[0].name = f"{name}_1"
        return parts


class _Chain:
    """A seam's ``L`` motions (approach, seam, retract) with its I/O events on them, as
    ``_Program.add`` items in ``lines``."""

    def __init__(self, post: FanucPost, run: SeamRun):
        job, io, seam = post.job, post.job.process_io, run.seam
        samples, points, (n_a, n_p) = _samples(job.job, run)
        check = PathCheck(samples.X_BP, job.job.X_BT, *run.process.selection_tol)

        def merge(points: list[int], pinned: set[int], flow_fits) -> list[int]:
            # A merged motion holds the path tolerance and the plan's flow steps (the
            # bead's accuracy), except that a motion the plan runs slower than FANUC's
            # slowest L speed merges into its neighbour: the program cannot time it.
            def fits(a: int, k: int, b: int) -> bool:
                at = np.array([a, k, b])
                speeds = segment_speeds_mms(samples.t, samples.X_BP, at, clip=False)
                return speeds.min() < MIN_SPEED_MMS or flow_fits(a, b)

            return check.merge(points, pinned | {n_a, n_p}, fits)  # the FINE points stay

        try:
            motions = place_events(
                samples,
                points,
                list(run.events),
                seam=seam,
                io=io,
                flow_at=_flow_at(job),
                merge=merge,
                fixed={n_a, n_p},
            )
        except ValueError as error:  # the cell's switch positions: one line, exit 2
            raise InputError(job.job.cell_file, "tool.process_io", str(error)) from None
        configs = config_strings(post.robot, samples.q)
        # Every motion at its planned mean speed: the seam's, and the approach's and
        # retract's (motion.approach_speed where they cruise, slower on their ramps).
        ends = np.array([motions[0].start, *(m.end for m in motions)]) if motions else []
        speeds = segment_speeds_mms(samples.t, samples.X_BP, ends) if motions else []
        # The seam program's first lines: its deviation from the plan, re-checked.
        self.lines: list = _deviation_remarks(check, motions, (n_a, n_p), run.process.residual)
        X_TB = np.linalg.inv(job.job.X_BT)
        current = None if io is None else io.idle
        for m, mms in zip(motions, speeds, strict=True):
            if m.flow is not None and post.ao_statement(m.flow) != post.ao_statement(current):
                if m.flow_event is None:
                    self.lines.append(post.ao_statement(m.flow))
                else:  # the flow's event, at the value the plan's flow has on the motion
                    event = dataclasses.replace(m.flow_event, value=m.flow)
                    self.lines.append(post.follow_speed(Switch(0, 0.0, event)))
                current = m.flow
            last = m.end in (n_a, n_p, len(samples.path_m) - 1)
            switch = "" if m.event is None else post.set_output(Switch(0, m.before_end_m, m.event))
            entry = (X_TB @ samples.X_BP[m.end], configs[m.end])  # P in the user frame T
            self.lines.append((entry, f"{mms}mm/sec {'FINE' if last else 'CNT100'}{switch}"))
        if current is not None and post.ao_statement(current) != post.ao_statement(io.idle):
            self.lines.append(post.ao_statement(io.idle))


def _deviation_remarks(check: PathCheck, motions, seam_ends, residual) -> list[str]:
    """The seam program's statement of its deviation from the plan: the seam's motions
    re-checked against the planned samples, plus the densified plan's residual."""
    n_a, n_p = seam_ends
    on_seam = [m for m in motions if n_a <= m.start and m.end <= n_p]
    i, j = np.array([m.start for m in on_seam], int), np.array([m.end for m in on_seam], int)
    d, a = check.deviations(i, j)
    p = check.X_BP[:, :3, 3]
    shortest = np.linalg.norm(p[j] - p[i], axis=1).min(initial=np.inf)
    return remarks(
        [
            f"Seam: {len(on_seam)} L motions, shortest {shortest * 1e3:.3f} mm; deviation <= "
            f"{(d.max(initial=0.0) + residual[0]) * 1e3:.4f} mm, "
            f"{np.rad2deg(a.max(initial=0.0) + residual[1]):.4f} deg from the plan"
        ]
    )


def _samples(rows, run: SeamRun):
    """The seam's planned samples (``export.run_samples``) with the fixed tool's origin;
    the L points before splitting; the indices of the seam's first and last sample."""
    run_rows = run_samples(rows, run)
    samples = Samples(
        path_m=run_rows.path_m,
        t=run_rows.t,
        q=run_rows.q,
        X_BP=run_rows.X_BP,
        p_BT=rows.X_BT[:3, 3],
    )
    points = [0, *run_rows.seam_points, len(samples.path_m) - 1]
    return samples, points, (run_rows.first, run_rows.last)


def _flow_at(job):
    """The live flow [V] at job times (n,) [s]: the plan's flow at the speed the tool
    has ``lag_s`` later, as the plan's ``ao`` column holds it while live."""
    io, t, v = job.process_io, job.job.t, job.job.tcp_speed
    if io is None or io.analog_output is None:
        return None
    return lambda times: io.flow(np.interp(np.asarray(times) + io.lag_s, t, v))


def segment_speeds_mms(t: np.ndarray, X_BU: np.ndarray, idx: np.ndarray, *, clip: bool = True):
    """(n-1,) planned mean speed of the TCP U (origin of X_BU (N, 4, 4) [m]; times t
    (N,) [s]) on each segment between rows idx [mm/sec]: whole numbers in
    [MIN_SPEED_MMS, MAX_SPEED_MMS] as an L statement takes them, or (clip False) as planned."""
    p = X_BU[idx, :3, 3]
    dt = np.maximum(np.diff(t[idx]), 1e-9)
    speeds = np.linalg.norm(np.diff(p, axis=0), axis=1) / dt * 1e3
    if not clip:
        return speeds
    return np.clip(np.round(speeds), MIN_SPEED_MMS, MAX_SPEED_MMS).astype(int)


def payload_conventions(load, X_EP: np.ndarray) -> list[str]:
    """The PAYLOAD[1] header line of the program's load (None: no line)."""
    if load is None:
        return []
    mass, p_EC = load.total(X_EP)
    return [
        f"PAYLOAD[1]: {mass:.3f} kg at ({', '.join(f'{v * 100:.2f}' for v in p_EC)}) cm "
        "in the faceplate frame: set it in the payload schedule before running."
    ]
