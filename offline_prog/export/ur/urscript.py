"""Universal Robots URScript: a job as one ``.script``.

Two forms (``mode``): ``servoj`` (the default), the planned joint trajectory streamed as
below, and ``movel`` / ``movep``, a program a UR programmer can edit: the seam runs as
linear moves with blend radii within the path tolerance, in the tool's feature, the flow
set per point (``export.ur.ur_moves``). The links are ``movej`` in both.

The servoj form: plain URScript has no remote TCP, so the program runs the planned
joints; it names no frame and holds no frame value (no TCP or feature of the
installation moves a joint target: the header says to re-plan after a calibration).
Links: ``movej`` through the link's joint waypoints (the planned, collision-checked straight
joint moves; the controller's own timing at the joints' common limits). Each seam with
its approach and retract: the planned joint trajectory resampled to the controller
period (0.002 s on e-Series) on the plan's straight joint steps and streamed with one
``servoj`` per period. URScript units: metres, radians, seconds.

Process I/O from the plan's I/O events: an output is set (``set_standard_digital_out``,
``set_standard_analog_out``) just before the first ``servoj`` whose sample has reached
the event's time, so the tool is at most v_TCP · period past its position (0.2 mm at
100 mm/s and 2 ms). The flow, ``set_standard_analog_out(n, value / 10 V)`` (URScript
takes the output as a fraction of its 0–10 V range), follows the plan's ``ao`` column
while it is live, interpolated between live samples only (an edge is a step, not a
ramp), written at each event and whenever it has changed by ``ANALOG_STEP_V`` or by
``ANALOG_STEP_SHARE`` of its value, and holds the idle value otherwise.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.atomic import write_atomic
from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M
from offline_prog.export.points import PointRule
from offline_prog.export.post import ControllerPost
from offline_prog.export.record import JointMove, ProgramRecord, SeamRun, Switch
from offline_prog.export.text import identifier_from, urscript_comment
from offline_prog.export.ur.ur_moves import MOVE_MODES, ur_moves
from offline_prog.io_events import Signal

E_SERIES_PERIOD_S = 0.002
SERVOJ_LOOKAHEAD_S = 0.1
SERVOJ_GAIN = 300
ANALOG_RANGE_V = 10.0  # standard analog outputs: 0..10 V as 0..1
ANALOG_STEP_V = 0.02  # write the flow when it changed by this much
# ... or by this share of its value (a process model's quality follows the output's
# value relative to the speed: a bead or a tape at a slow ramp needs fine steps)
ANALOG_STEP_SHARE = 0.002
MODES = ("servoj", *MOVE_MODES)
FRAMES_SUFFIX = "_frames"  # <name>_frames.script: the nominal frames of the move forms
VARIABLE_MAX = 31  # the frames' pose variables: at most this many characters (our bound)


@dataclasses.dataclass(frozen=True)
class UrScriptOptions:
    """name: the program's function (≤ 63 characters, our bound); period_s: the servoj
    period [s] (the controller's); mode: ``servoj`` (the planned joints streamed) or
    ``movel`` / ``movep`` (linear moves with blends); chord_tol_m, angle_tol_rad: the
    move forms' path tolerance [m, rad] (None: the writers' defaults; servoj takes none)."""

    name: str = "offline_prog"
    period_s: float = E_SERIES_PERIOD_S
    mode: str = "servoj"
    chord_tol_m: float | None = None
    angle_tol_rad: float | None = None


class UrScriptPost(ControllerPost):
    """The URScript program of a job (see the module docstring)."""

    FORMAT = "urscript"
    Options = UrScriptOptions
    NAME_MAX = 63
    OPW_ONLY = False

    def __init__(self, job, options: UrScriptOptions, **flags):
        super().__init__(job, options, **flags)
        if not options.period_s > 0:
            raise ValueError(f"period_s={options.period_s}: need a period > 0 s")
        if options.mode not in MODES:
            raise ValueError(f"mode={options.mode!r}: use one of {', '.join(MODES)}")
        tolerances = (options.chord_tol_m, options.angle_tol_rad)
        if options.mode == "servoj" and tolerances != (None, None):
            raise ValueError(
                "urscript: the path tolerances apply to mode movel or movep (servoj streams "
                "the planned joints)"
            )
        self.moves = options.mode != "servoj"
        given = options.chord_tol_m, options.angle_tol_rad
        self.chord_tol_m = DEFAULT_CHORD_TOL_M if given[0] is None else given[0]
        self.angle_tol_rad = DEFAULT_ANGLE_TOL_RAD if given[1] is None else given[1]
        # the move forms' points: half the tolerance (checked > 0 here)
        self.rule = PointRule("flange", "X_TP", 0.5 * self.chord_tol_m, 0.5 * self.angle_tol_rad)
        rows = self.job.job
        # The move forms' pose variables: the fixed tool T in B and the part P on E.
        self.feature = identifier_from("tool", rows.tool, max_chars=VARIABLE_MAX)
        self.tcp = identifier_from("tcp", rows.part, max_chars=VARIABLE_MAX)
        # movej: the joints' common limits, at the plan's motion.link_speed_percent
        share = self.job.job.link_speed_percent / 100.0
        self.v_link = float(self.robot.qd_max.min()) * share
        self.a_link = float(self.robot.qdd_max.min())
        self.lines: list[str] = []

    def point_rule(self) -> PointRule | None:
        """The move forms: the controller interpolates the TCP P in B with the tool fixed
        (flange style), the seam's points at half the tolerance (the blends take the
        other half); servoj: every sample."""
        return self.rule if self.moves else None

    def conventions(self, record: ProgramRecord) -> list[str]:
        if self.moves:
            return self._move_conventions(record)
        io, rows, names = record.job.process_io, record.job.job, record.job.seam_names
        lines = [
            "Units: m, rad, s. Joint order: " + ", ".join(rows.joint_names) + ".",
            f"Job: {len(names)} seams in this order: {', '.join(names)}.",
            "Frames: none. This program streams joint positions, which no installation TCP "
            "or feature moves: after calibrating the tool or the grasp, plan again with the "
            "calibrated cell (offline-prog calibrate) and export again.",
            f"Links: movej through joint waypoints (a={self.a_link:.3f}, v={self.v_link:.3f}); "
            f"seams with approach and retract: servoj every {self.options.period_s} s "
            "(resampled from the plan).",
        ]
        if io is not None and io.digital_output is not None:
            lines.append(
                f"Process output: standard digital out {io.digital_output}, on "
                f"{io.on_lead_m * 1e3:g} mm before each seam's start, off "
                f"{io.off_lead_m * 1e3:g} mm before its end (at the servoj sample that "
                "reaches it)."
            )
        if io is not None and io.analog_output is not None:
            lines.append(
                f"Flow: standard analog out {io.analog_output} = ({io.offset:g} V + "
                f"{io.per_mps:g} V per m/s x v_TCP) / 10 V, within [{io.min:g}, {io.max:g}] V."
            )
        return lines

    def header(self, lines: list[str]) -> None:
        self.lines += [f"# {urscript_comment(line)}" for line in lines]
        self.lines.append(f"def {self.options.name}():")

    def frames(self) -> None:
        """The payload (gripper + part, centre of mass in the flange) when the cell
        gives it; the program moves the flange's joints, so it sets no TCP."""
        rows = self.job.job
        if (load := self.load) is not None:
            mass, p_EC = load.total(rows.X_EP)
            self.lines.append(f"  set_payload({mass:.3f}, {_list(p_EC, 4)})")
        if self.moves:
            self.lines.append(f"  set_tcp({self.tcp})")

    def move_joint(self, move: JointMove) -> None:
        for q in move.targets:
            self.lines.append(f"  movej({_list(q)}, a={self.a_link:.3f}, v={self.v_link:.3f})")

    def seam(self, run: SeamRun) -> None:
        """The seam with its approach and retract, streamed or as moves (see the module
        docstring)."""
        if self.moves:
            self._seam_moves(run)
            return
        rows, period = self.job.job, self.options.period_s
        t = rows.t[run.rows]
        grid = np.arange(0.0, t[-1] - t[0], period)
        grid = np.append(grid, t[-1] - t[0]) if t[-1] - t[0] - grid[-1] > 1e-9 else grid
        grid = grid + t[0]  # the job's clock
        q = joints_on_steps(t, rows.q[run.rows], grid)
        # An event is set before the first command whose sample is at or past its time.
        sets: dict[int, list] = {}
        for event in run.events:
            i = int(np.searchsorted(grid, event.t_s - 1e-12))
            sets.setdefault(min(max(i, 1), len(grid) - 1), []).append(event)
        flow, last = self._flow(run, grid), None
        for i in range(1, len(grid)):
            last = self._io_here(sets.get(i, []), None if flow is None else flow[i], last)
            self.lines.append(
                f"  servoj({_list(q[i])}, t={period}, lookahead_time={SERVOJ_LOOKAHEAD_S}, "
                f"gain={SERVOJ_GAIN})"
            )

    def set_output(self, switch: Switch) -> str:
        state = "True" if switch.event.state else "False"
        return f"  set_standard_digital_out({switch.event.output}, {state})"

    def follow_speed(self, switch: Switch) -> str:
        """The flow output at the event's value: the plan's flow, which follows the TCP
        speed while live (the stream writes its further values)."""
        return self._analog_out(switch.event.value)

    def footer(self, out_dir: Path) -> list[Path]:
        name = self.options.name
        file = out_dir / f"{name}.script"
        write_atomic(file, "\n".join([*self.lines, "  stopj(2.0)", "end", f"{name}()"]) + "\n")
        if not self.moves:
            return [file]
        frames = out_dir / f"{name}{FRAMES_SUFFIX}.script"
        rows = self.job.job
        write_atomic(
            frames,
            "\n".join(
                [
                    f"# {urscript_comment(line)}"
                    for line in (
                        f"Nominal frames of {rows.cell_name} for {name}.script (m, rad): "
                        "run once before it (a Script node), or name the installation's "
                        "calibrated feature and TCP so instead.",
                        f"{self.feature}: the fixed tool {rows.tool} in the base.",
                        f"{self.tcp}: the part {rows.part} on the tool flange.",
                    )
                ]
                + [
                    f"global {self.feature} = {_pose(rows.X_BT)}",
                    f"global {self.tcp} = {_pose(rows.X_EP)}",
                ]
            )
            + "\n",
        )
        return [file, frames]

    def _move_conventions(self, record: ProgramRecord) -> list[str]:
        io, rows, names = record.job.process_io, record.job.job, record.job.seam_names
        name, mode = self.options.name, self.options.mode
        lines = [
            "Units: m, rad, s. Joint order: " + ", ".join(rows.joint_names) + ".",
            f"Job: {len(names)} seams in this order: {', '.join(names)}.",
            f"Frames: TCP {self.tcp} = the part {rows.part} on the flange; targets "
            f"pose_trans({self.feature}, part in the tool) with {self.feature} = the fixed "
            f"tool {rows.tool} in the base. Both are pose variables of the installation "
            f"or of {name}{FRAMES_SUFFIX}.script (nominal values, run once before): a "
            "calibration of the two moves every target with it.",
            f"Links: movej through joint waypoints (a={self.a_link:.3f}, v={self.v_link:.3f}); "
            f"seams with approach and retract: {mode} through planned points at the planned "
            f"speeds, blends within {self.chord_tol_m * 1e3:g} mm and "
            f"{np.rad2deg(self.angle_tol_rad):g} deg of the plan.",
        ]
        if io is not None and io.digital_output is not None:
            lines.append(
                f"Process output: standard digital out {io.digital_output}, set at the point "
                "where the plan sets it (as the move to it blends)."
            )
        if io is not None and io.analog_output is not None:
            lines.append(
                f"Flow: standard analog out {io.analog_output} = ({io.offset:g} V + "
                f"{io.per_mps:g} V per m/s x v_TCP) / 10 V, within [{io.min:g}, {io.max:g}] V, "
                "set per point."
            )
        return lines

    def _seam_moves(self, run: SeamRun) -> None:
        """The run as moves through planned points (``ur_moves``), the I/O statements
        at the points where the plan sets them, the flow per point."""
        moves = ur_moves(
            self.job, run, chord_tol_m=self.chord_tol_m, angle_tol_rad=self.angle_tol_rad
        )
        points, t = moves.points, moves.t
        X_TB = np.linalg.inv(self.job.job.X_BT)
        at_point: dict[int, list] = {}
        for event, m in zip(run.events, moves.event_points, strict=True):
            at_point.setdefault(int(m), []).append(event)
        flow, last = self._flow(run, t[points]), None
        self.lines.append(
            f"  # {run.seam}: {len(points) - 1} moves, deviation <= "
            f"{moves.deviation_m * 1e3:.4f} mm from the plan without blends"
        )
        for m, k in enumerate(points):
            if m > 0:
                self.lines.append(
                    f"  {self.options.mode}(pose_trans({self.feature}, "
                    f"{_pose(X_TB @ moves.X_BP[k])}), a={moves.accel_m_s2[m]:.3f}, "
                    f"v={moves.speed_m_s[m]:.5f}, r={moves.radius_m[m]:.6f})"
                )
            if m == len(points) - 1:
                break
            last = self._io_here(at_point.get(m, []), None if flow is None else flow[m], last)

    def _io_here(self, events: list, flow_v: float | None, last: float | None) -> float | None:
        """The statements of the I/O events set here, and of the flow at its value here
        flow_v [V] (None: no flow output) at an analog event or when it has changed from
        the ``last`` value written by ANALOG_STEP_V or ANALOG_STEP_SHARE of it; returns
        the flow value last written."""
        self.lines += [
            self.set_output(Switch(0, 0.0, e)) for e in events if e.signal is Signal.DIGITAL
        ]
        analog = [e for e in events if e.signal is Signal.ANALOG]
        if flow_v is None or not (
            last is None
            or abs(flow_v - last) >= min(ANALOG_STEP_V, ANALOG_STEP_SHARE * abs(last))
            or analog
        ):
            return last
        if analog:  # the event, at the value the plan's flow has here
            event = dataclasses.replace(analog[0], value=float(flow_v))
            self.lines.append(self.follow_speed(Switch(0, 0.0, event)))
        else:
            self.lines.append(self._analog_out(flow_v))
        return flow_v

    def _analog_out(self, value_v: float) -> str:
        output = self.job.process_io.analog_output
        fraction = np.clip(value_v / ANALOG_RANGE_V, 0.0, 1.0)
        return f"  set_standard_analog_out({output}, {fraction:.4f})"

    def _flow(self, run: SeamRun, grid: np.ndarray) -> np.ndarray | None:
        """(len(grid),) the flow command at the grid times [V]: the plan's ``ao`` column
        between its live samples while the flow is live (its analog events), else idle."""
        io = self.job.process_io
        if io is None or io.analog_output is None or self.job.analog is None:
            return None
        t, value = self.job.job.t[run.rows], self.job.analog[run.rows]
        events = [e for e in run.events if e.signal is Signal.ANALOG]
        out = np.full(len(grid), io.idle)
        for on, off in zip(events[::2], events[1::2], strict=True):
            live = (t >= on.t_s) & (t < off.t_s)
            here = (grid >= on.t_s) & (grid < off.t_s)
            if live.any():
                out[here] = np.interp(grid[here], t[live], value[live])
            else:  # a window shorter than a sample: the event's own value
                out[here] = on.value
        return out


def joints_on_steps(t: np.ndarray, q: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """(M, 6) the joints at times ``grid`` (M,) [s], linear between the plan's samples
    t (N,), q (N, 6) [rad]: the straight joint step between two samples is what the
    collision check certified (collision.check), so a servoj target never leaves it."""
    return np.column_stack([np.interp(grid, t, q[:, j]) for j in range(q.shape[1])])


def _pose(X: np.ndarray) -> str:
    """A URScript pose ``p[x, y, z, rx, ry, rz]`` of a 4×4 pose [m, rotation vector rad]."""
    rotvec = Rotation.from_matrix(X[:3, :3]).as_rotvec()
    return "p" + _list(np.concatenate([X[:3, 3], rotvec]))


def _list(values: np.ndarray, digits: int = 7) -> str:
    return "[" + ", ".join(f"{v:.{digits}f}" for v in values) + "]"
