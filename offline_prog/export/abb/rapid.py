"""ABB RAPID: a job as one module ``<module>.mod`` (+ ``.pgf``); the robot carries the
part past a stationary tool (remote TCP).

Controller model (RAPID Technical Reference Manual, 3HAC050917: ``tooldata``,
``wobjdata``, ``robtarget``, ``confdata``; MultiMove manual 3HAC021272 §6.3):

- ``tooldata`` with ``robhold := FALSE``: ``tframe`` is the fixed tool T in the world
  frame W; ``tload`` is then the load of the gripper that holds the part.
- ``wobjdata`` with ``robhold := TRUE``, ``ufprog := TRUE``, ``ufmec := ""``:
  ``uframe`` is given in the wrist frame tool0 (E), ``oframe`` in ``uframe``.
- a ``robtarget`` is the TCP in the object frame O, so the controller puts the flange
  at ``X_WE = tframe · robtarget⁻¹ · oframe⁻¹ · uframe⁻¹``.

Here W = B (world = robot base frame), tframe = X_BT, uframe = X_EP, oframe = I and
robtarget_i = X_PT(i) (the process frame on the seam), so the composition is the plan's
X_BE = X_BT · X_PT⁻¹ · X_EP⁻¹. E, the URDF ``tool0``, is ABB's tool0 (z out of the
flange, x down at the calibration position). Axis values: ``abb.abb_axes_deg``. Units
at this edge: mm, degrees, quaternions ``[q1, q2, q3, q4] = [w, x, y, z]``.

``main``: ``MoveAbsJ`` home; per seam the link (``MoveAbsJ`` through its jointtargets,
fine points: the planned, collision-checked joint moves), the approach (``TriggL`` to
the seam's first point), the seam (``PROC seam_<k>``: ``MoveL`` / ``TriggL`` through its
points at each segment's planned mean TCP speed, zone ``zPath``), the retract
(``MoveL``/``TriggL``); home at the end. With a ``line_limit`` a seam's routine that would
be longer (``PROC`` to ``ENDPROC``) runs as routines ``seam_<k>_p<j>`` called in turn
(``export.split``): a move stays with its ``TriggIO`` / ``TriggSpeed``, each move
names its own speeddata, the last move of a part keeps its zone, and the outputs (the
``TriggSpeed`` flow with them) hold across the calls.

Process I/O on the path from the plan's I/O events (RAPID Instructions, 3HAC050917:
``TriggIO``, ``TriggL``, ``TriggSpeed``): ``TriggIO t, d \\DOp:=do<n>, 1`` then
``TriggL p, v, t, z, tool`` sets the output d mm before the move's end point (distance
from the end, no ``\\Start``); a move holds every event that falls on it (``\\T2``,
``\\T3``, ...). The flow follows the TCP speed only while the output is on:
``TriggSpeed tFlowOn, d, lag, ao<n>, k`` at the on switch's position with k = per_mps /
1000 (the logical value of ``ao<n>`` = k · v_TCP [mm/s], i.e. volts per mm/s) and
``TriggSpeed tFlowOff, d, lag, ao<n>, 0`` at the off switch's; ScaleLag = the cell's
``flow.lag_s`` (the dispenser's lag). The offset and limits belong to the signal's
scaling in the I/O configuration (the header says which): logical 0 is the idle value,
the offset. Signals are named ``do<n>`` / ``ao<n>``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from pydrake.math import RotationMatrix

from offline_prog.atomic import write_atomic
from offline_prog.export.abb.abb import abb_axes_deg, confdata
from offline_prog.export.payload import principal
from offline_prog.export.points import PointRule
from offline_prog.export.post import CartesianPost, PointOptions
from offline_prog.export.program import ProgramData
from offline_prog.export.record import JointMove, LinearMove, Process, ProgramRecord, Switch
from offline_prog.export.split import check_line_limit, split_blocks
from offline_prog.export.text import identifier_from, rapid_comment
from offline_prog.io_events import Signal

LINK_SPEED = "v1000"  # predefined speeddata of the MoveAbsJ links (timing: the controller's)
SPEED_REST = "500,5000,1000"  # v_ori [deg/s], v_leax [mm/s], v_reax [deg/s], as v5..v1000
MIN_SPEED_MMS = 0.1  # smallest v_tcp written
MAX_SPEED_MMS = 7000.0  # largest v_tcp of RAPID's predefined speeddata (v7000)
# The tooldata's tload in the frames module when the program states no load: RAPID's
# smallest (mass > 0), with a remark to set the gripper's load there; no program uses it
# as a load statement.
NO_LOAD = "[0.001,[0,0,0],[1,0,0,0],0,0,0]"
EXTAX = "[9E9,9E9,9E9,9E9,9E9,9E9]"  # external axes: none
PGF_HEAD = '<?xml version="1.0" encoding="ISO-8859-1" ?>\n'  # program file (.pgf)
MM_DIGITS, QUAT_DIGITS, DEG_DIGITS = 3, 7, 4  # 0.5 µm, ~1e-5 deg, 5e-5 deg
NAME_MAX = 32  # RAPID identifiers: letter first, letters / digits / _, ≤ 32 characters
MODULE_NAME_MAX = NAME_MAX - 6  # the module's name (room for a suffix)
FRAMES_SUFFIX = "Frames"  # <module>Frames.mod: the nominal PERS tooldata and wobjdata
# The triggdata of each kind of event; a second one of a kind on the same move gets a
# number (tOn2): a TriggL holds up to 8 triggers, each its own triggdata.
TRIGGERS = {
    (Signal.DIGITAL, True): "tOn",
    (Signal.DIGITAL, False): "tOff",
    (Signal.ANALOG, True): "tFlowOn",
    (Signal.ANALOG, False): "tFlowOff",
}


@dataclasses.dataclass(frozen=True)
class RapidOptions(PointOptions):
    """module: the module's name; zone_mm: the corner zone of the seams' moves [mm];
    line_limit: most lines (``PROC`` to ``ENDPROC``) of a seam's routine, or None (no
    split)."""

    module: str = "OfflineProg"
    zone_mm: float = 0.3
    line_limit: int | None = None


class RapidPost(CartesianPost):
    """The RAPID module of a job (see the module docstring)."""

    FORMAT = "rapid"
    Options = RapidOptions
    NAME_OPTION = "module"
    NAME_MAX = MODULE_NAME_MAX

    def __init__(self, job, options: RapidOptions, **flags):
        super().__init__(job, options, **flags)
        if not options.zone_mm >= 0:
            raise ValueError(f"zone_mm={options.zone_mm}: need a zone >= 0 mm")
        check_line_limit(options.line_limit)
        rows = job.job
        tool = identifier_from("tool", rows.tool, max_chars=NAME_MAX)
        wobj = identifier_from("wobj", rows.part, max_chars=NAME_MAX)
        self.tool, self.wobj, self.tail = tool, wobj, f", {tool}\\WObj:={wobj};"
        self.decls: list[str] = []
        self.main: list[str] = []
        self.procs: dict[str, list[str]] = {}
        self.speeds: set[str] = set()  # speeddata declared
        self.triggdata: set[str] = set()  # declared once the moves are written
        self.on_move: list[str] = []  # the triggers of the move being written

    def point_rule(self) -> PointRule:
        o = self.options
        return PointRule("external_tcp", "X_PF", o.chord_tol_m, o.angle_tol_rad)

    def conventions(self, record: ProgramRecord) -> list[str]:
        io, names = record.job.process_io, record.job.seam_names
        lines = [
            f"Job: {len(names)} seams in this order: {', '.join(names)}.",
            f"Frames: tool T = PERS tooldata {self.tool}, part P = PERS wobjdata {self.wobj} "
            "(named after tool.name and part.name: RAPID names its frames, the cell's "
            "controller_frame numbers are not used), as calibrated on the controller; their "
            f"nominal values: {self.options.module}{FRAMES_SUFFIX}.mod (load it once, it is "
            "not part of the .pgf).",
            "Units: mm, deg; quaternions [w,x,y,z]. World = robot base. Stationary tool: "
            "tframe = tool in world; robot-held wobj: uframe = part in tool0; robtarget = tool "
            "on the part.",
            "Axes: URDF joints"
            + (
                f", axis 3 = q3 + {self.robot.j23_factor:g} x q2 (J2/J3 linkage)"
                if self.robot.j23_coupled
                else ""
            )
            + ".",
            f"Links: MoveAbsJ to fine points ({LINK_SPEED}); approach, seams, retract: MoveL / "
            "TriggL at the planned speeds.",
        ]
        if io is not None and io.digital_output is not None:
            lines.append(
                f"Process output do{io.digital_output}: TriggIO at the plan's switch positions "
                f"(on {io.on_lead_m * 1e3:g} mm before each seam's start, off "
                f"{io.off_lead_m * 1e3:g} mm before its end)."
            )
        if io is not None and io.analog_output is not None:
            lines.append(
                f"Flow ao{io.analog_output}: TriggSpeed while the process output is on, logical "
                f"value = {io.per_mps / 1000:g} V per mm/s x TCP speed, 0 otherwise (ScaleLag "
                f"{io.lag_s:g} s: the dispenser's lag); set the signal's I/O configuration to "
                f"add {io.offset:g} V and limit it to [{io.min:g}, {io.max:g}] V (idle "
                f"{io.idle:g} V)."
            )
        return lines

    def header(self, lines: list[str]) -> None:
        self.head = ["! " + rapid_comment(line) for line in lines]

    def frames(self) -> None:
        """The part's load (GripLoad) and the seams' zone. The stationary tool and the
        robot-held work object are the controller's PERS data (``_nominal_frames``)."""
        load = self.load
        if load is not None:
            self.decls.append(
                f"PERS loaddata partLoad := {_load(load.part_mass_kg, load.p_PC, load.I_C_P)};"
            )
        zone = self.options.zone_mm
        z = _list((zone,) * 3 + (zone / 10, zone, zone / 10), 5)[1:-1]
        self.decls.append(f"LOCAL CONST zonedata zPath := [FALSE,{z}];")
        self.main += ["ConfJ \\On;", "ConfL \\On;"] + ["GripLoad partLoad;"] * (load is not None)

    def move_joint(self, move: JointMove) -> None:
        n = move.number
        names = ["jHome"] if n == 0 else [f"jL{n}_{w}" for w in range(1, len(move.targets) + 1)]
        for name, q in zip(names, move.targets, strict=True):
            axes = abb_axes_deg(self.robot, q[None])[0]
            self.decls.append(
                f"LOCAL CONST jointtarget {name} := [{_list(axes, DEG_DIGITS)},{EXTAX}];"
            )
            self.main.append(f"MoveAbsJ {name}\\NoEOffs, {LINK_SPEED}, fine{self.tail}")

    def move_linear(self, move: LinearMove) -> None:
        name = f"p{move.kind[0].upper()}{move.number}"
        self.decls.append(_robtarget(name, move.X_PT, confdata(self.robot, move.q[None])[0]))
        speed = self._speed(move.speed_m_s * 1e3)
        triggers = self._triggers(move.switches, self.main)
        self.main.append(_move(name, speed, triggers, "fine", self.tail))

    def set_output(self, switch: Switch) -> str:
        event = switch.event
        name, distance = self._trigger_name(switch), _num(switch.before_end_m * 1e3, 3)
        return f"TriggIO {name}, {distance}\\DOp:=do{event.output}, {int(event.state)};"

    def follow_speed(self, switch: Switch) -> str:
        io, event = self.job.process_io, switch.event
        name, distance = self._trigger_name(switch), _num(switch.before_end_m * 1e3, 3)
        k = _num(io.per_mps / 1000.0, 6) if event.state else "0"
        return f"TriggSpeed {name}, {distance}, {_num(io.lag_s, 3)}, ao{event.output}, {k};"

    def call_part(self, process: Process) -> None:
        """``PROC seam_<k>``: the seam's moves; its first point is the approach's end.
        At the line limit: its parts ``seam_<k>_p<j>``, called in turn."""
        proc, data, idx = f"seam_{process.number}", process.data, process.indices
        conf, speeds = confdata(self.robot, data.q[idx]), segment_speeds_mms(data, idx)
        moves = range(1, len(idx))
        sizes = [len(process.switches_before(m)) + 1 for m in moves]
        parts = split_blocks(sizes, self.options.line_limit, frame=2)
        names = [proc] if len(parts) == 1 else [f"{proc}_p{j + 1}" for j in range(len(parts))]
        for routine, part in zip(names, parts, strict=True):
            lines = self.procs.setdefault(routine, [])
            for m in (moves[k] for k in part):
                name = f"{proc}_{m}"
                self.decls.append(_robtarget(name, data.X_PT[idx[m]], conf[m]))
                zone = "fine" if m == len(idx) - 1 or self.options.zone_mm == 0 else "zPath"
                triggers = self._triggers(process.switches_before(m), lines)
                lines.append(_move(name, self._speed(speeds[m - 1]), triggers, zone, self.tail))
            self.main.append(f"{routine};  ! seam {process.seam}")

    def footer(self, out_dir: Path) -> list[Path]:
        module, limit = self.options.module, self.options.line_limit
        statements = 2 + sum(not line.startswith("!") for line in self.main)
        if limit is not None and statements > limit:
            raise ValueError(f"line_limit={limit}: the main routine alone needs {statements} lines")
        decls = self.decls + [f"VAR triggdata {name};" for name in sorted(self.triggdata)]
        text = _module_text(module, self.head + decls, {"main": self.main, **self.procs})
        files = [out_dir / f"{module}.mod", out_dir / f"{module}.pgf"]
        write_atomic(files[0], text)
        listing = f"<Program>\n  <Module>{files[0].name}</Module>\n</Program>\n"
        write_atomic(files[1], PGF_HEAD + listing)
        return files + [self._nominal_frames(out_dir)]

    def _nominal_frames(self, folder: Path) -> Path:
        """``<module>Frames.mod``: the PERS tooldata (the stationary tool T in the world
        W = B; its tload the gripper's) and wobjdata (the part P: uframe in tool0 = E)
        with the cell's nominal values, a module to load once (not in the .pgf): the
        controller's calibration then updates them, and every program uses them."""
        rows, load = self.job.job, self.load
        gripper = NO_LOAD if load is None else _load(load.gripper_mass_kg, load.p_EG, load.I_G_E)
        name = f"{self.options.module}{FRAMES_SUFFIX}"
        body = self.head + [
            "! NOMINAL FRAMES of the cell (its CAD values): load this module once, then",
            "! calibrate these data on the controller; the program only names them.",
            *(
                ["! tload: the cell gives no gripper load; set it here (0.001 kg: none given)."]
                if load is None
                else []
            ),
            f"PERS tooldata {self.tool} := [FALSE,{_pose(rows.X_BT)},{gripper}];",
            f'PERS wobjdata {self.wobj} := [TRUE,TRUE,"",{_pose(rows.X_EP)},[[0,0,0],[1,0,0,0]]];',
        ]
        file = folder / f"{name}.mod"
        write_atomic(file, _module_text(name, body, {}))
        return file

    def _speed(self, v_mms: float) -> str:
        """The speeddata of v_tcp [mm/s] (``v<mm/s>_<tenth>``), declared at first use."""
        name = f"v{int(round(v_mms * 10)) // 10}_{int(round(v_mms * 10)) % 10}"
        if name not in self.speeds:
            self.speeds.add(name)
            self.decls.append(f"LOCAL CONST speeddata {name} := [{_num(v_mms, 1)},{SPEED_REST}];")
        return name

    def _triggers(self, switches, lines: list[str]) -> list[str]:
        """Define the triggers of one move's I/O events in ``lines``; their names in
        path order."""
        self.on_move = []
        lines += [self.switch(s) for s in switches]
        self.triggdata.update(self.on_move)
        return self.on_move

    def _trigger_name(self, switch: Switch) -> str:
        """The triggdata of an event on the move being written: ``tOn``, or ``tOn2`` for
        the second of its kind on the move, ..."""
        base = TRIGGERS[switch.event.signal, switch.event.state]
        count = sum(name.rstrip("0123456789") == base for name in self.on_move)
        self.on_move.append(base + (str(count + 1) if count else ""))
        return self.on_move[-1]


def segment_speeds_mms(data: ProgramData, indices: np.ndarray) -> np.ndarray:
    """(n-1,) planned TCP speed on each LIN segment [mm/s]: the time mean of
    ``data.tcp_speed`` between its end samples (= planned length / duration), so the
    program keeps the planned timing; rounded to 0.1 mm/s, at least 0.1 mm/s.

    Raises:
        ValueError: a speed beyond MAX_SPEED_MMS (a unit slip: the plan's speeds are m/s).
    """
    v, t = data.tcp_speed, data.t
    mean = [
        np.trapezoid(v[a : b + 1], t[a : b + 1]) / (t[b] - t[a]) if t[b] > t[a] else v[b]
        for a, b in zip(indices[:-1], indices[1:], strict=True)
    ]
    speeds = np.maximum(np.round(np.asarray(mean) * 1e4) / 10.0, MIN_SPEED_MMS)
    if not np.all(speeds <= MAX_SPEED_MMS):  # NaN too
        raise ValueError(
            f"rapid: v_tcp {np.nanmax(speeds):g} mm/s is beyond {MAX_SPEED_MMS:g} mm/s "
            "(the plan's speeds are m/s, not mm/s)"
        )
    return speeds


def _move(target: str, speed: str, triggers: list[str], zone: str, tail: str) -> str:
    if not triggers:
        return f"MoveL {target}, {speed}, {zone}{tail}"
    extra = "".join(f" \\T{k + 2}:={t}" for k, t in enumerate(triggers[1:]))
    return f"TriggL {target}, {speed}, {triggers[0]}{extra}, {zone}{tail}"


def _num(x: float, digits: int) -> str:
    text = f"{x:.{digits}f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def _list(values, digits: int) -> str:
    return "[" + ",".join(_num(v, digits) for v in values) + "]"


def _pose(X: np.ndarray) -> str:
    """RAPID pose ``[[x,y,z],[q1,q2,q3,q4]]`` [mm] of a 4×4 transform [m], q1 >= 0."""
    q = RotationMatrix(X[:3, :3]).ToQuaternion().wxyz()
    q *= np.sign(q[0] + (q[0] == 0.0)) / np.linalg.norm(q)
    return f"[{_list(X[:3, 3] * 1e3, MM_DIGITS)},{_list(q, QUAT_DIGITS)}]"


def _load(mass_kg: float, p_m: np.ndarray, inertia: np.ndarray) -> str:
    """loaddata ``[mass, cog [mm], aom, ix, iy, iz]``: aom the principal axes of the
    inertia (3, 3) [kg m²] about cog, ix..iz the moments about them [kg m²]; RAPID needs
    mass > 0, so 0 kg is written as 0.001 kg."""
    axes = principal(inertia)
    X = np.eye(4)
    X[:3, :3] = axes.R
    aom = _pose(X).split("],[")[1].rstrip("]")
    moments = ",".join(_num(v, 5) for v in axes.moments)
    return f"[{_num(max(mass_kg, 1e-3), 3)},{_list(p_m * 1e3, 1)},[{aom}],{moments}]"


def _robtarget(name: str, X: np.ndarray, conf: np.ndarray) -> str:
    cf = ",".join(str(int(c)) for c in conf)
    return f"LOCAL CONST robtarget {name} := [{_pose(X)[1:-1]},[{cf}],{EXTAX}];"


def _module_text(name: str, body: list[str], procs: dict[str, list[str]]) -> str:
    lines = [f"MODULE {name}"] + ["  " + line for line in body]
    for proc, statements in procs.items():
        lines += [f"  PROC {proc}()"] + ["    " + s for s in statements] + ["  ENDPROC"]
    return "\n".join(lines + ["ENDMODULE"]) + "\n"
