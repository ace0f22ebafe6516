"""KUKA KRL for KSS 8: a job as ``name.src`` / ``.dat`` plus one ``name_<k>`` module per
seam, in the external-TCP style.

Frames: ``$IPO_MODE=#TCP``, ``$BASE = BASE_DATA[tool.controller_frame]`` = the fixed
tool T in ``$WORLD`` (KSS keeps a fixed tool as a base), ``$TOOL =
TOOL_DATA[part.controller_frame]`` = the part P in ``$FLANGE`` (the robot-carried
workpiece is the "tool"): the controller's calibrated frames by number
(``export.frames``), so a calibration moves every program with it. Their nominal values
(the cell's) are in ``<name>_frm.src`` only, a routine the technician may run once (it
sets ``BASE_DATA``/``BASE_TYPE`` and ``TOOL_DATA``/``TOOL_TYPE``). Each LIN point is a
pose between P and T, written as ``tcp_pose_convention`` says: "X_TP" (P in T, the
default: flange = ``$BASE:POS:inv($TOOL)``, KSS's rule for every Cartesian position) or
"X_PF" (T in P: flange = ``$BASE:inv(POS):inv($TOOL)``). The controller then moves the
fixed TCP in straight lines across the part, which is what the point selection assumes
(``export.points``, external_tcp). Besides I, B, E, P, F, T: K = KUKA's ``$FLANGE``, the
URDF ``tool0`` (``kuka.X_KE``); B = ``base_link`` = ``$ROBROOT``, taken as ``$WORLD``.

Main program: home (``PTP`` to an ``E6AXIS``), then per seam: the link (``PTP`` through
its ``E6AXIS`` waypoints, fine points), the approach (``LIN`` to the seam's first
point), the seam's module (its LIN points with ``C_DIS``, ``$VEL.CP`` the highest
planned speed on each segment), the retract (``LIN``), and the last link home. With a
``line_limit`` a seam whose module would be longer (``DEF`` to ``END``) runs as modules
``<name>_<k>_<j>`` called in turn (``export.split``): each opens with the ``$VEL.CP`` it
runs at, a ``TRIGGER`` stays with its ``LIN``, the last ``LIN`` of a part keeps its
``C_DIS`` (the advance run approximates across the call), and ``$OUT`` and the flow's
factor are globals that the parts share.

Process I/O on the path (KSS 8 System Software, "TRIGGER WHEN PATH"), from the plan's
I/O events: ``TRIGGER WHEN PATH = −d DELAY = 0 DO $OUT[n] = TRUE`` before a LIN switches
d mm before that motion's end point; every event stands before the LIN that holds it,
in path order (two on one LIN: two TRIGGERs). The flow follows the TCP speed with one
``ANOUT ON $ANOUT[n] = <name>_FK * $VEL_ACT + o DELAY = −lag MINIMUM = lo MAXIMUM = hi``
at the program's start: ``$VEL_ACT`` in m/s and ``$ANOUT`` normalised to ±1 = ±10 V,
so the factor is per_mps / 10 while the process output is on and 0 otherwise (the
idle value o = offset / 10), switched by ``TRIGGER ... DO <name>_FK = f`` where the
plan sets the flow: ``flow.lag_s`` (the dispenser's lag) before the tool reaches the
positions of ``$OUT[n]`` (``IoEvent.set_path_m``), as the ANOUT's own ``DELAY`` leads
the speed; no TRIGGER needs a negative DELAY, which the controller would stop at the
motion's start.

Edge units: X, Y, Z [mm]; A, B, C [deg] with R = Rz(A)·Ry(B)·Rx(C) (KUKA Z-Y′-X″);
E6AXIS A1..A6 = q [deg] (robots/kuka_* URDFs carry KUKA's joint signs and zeros);
``$VEL.CP`` [m/s]; ``$APO.CDIS`` [mm]. Status and Turn: see ``kuka.status_turn``.
"""

from __future__ import annotations

import dataclasses
import textwrap
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.atomic import write_atomic
from offline_prog.export.frames import controller_frames
from offline_prog.export.kuka.kuka import (
    X_KE,
    krl_frame,
    krl_num,
    kuka_abc_deg,
    status_turn,
    vel_cp,
)
from offline_prog.export.payload import Principal
from offline_prog.export.points import PointRule
from offline_prog.export.post import CartesianPost, PointOptions
from offline_prog.export.record import JointMove, LinearMove, Process, ProgramRecord, Switch
from offline_prog.export.split import check_line_limit, split_blocks
from offline_prog.export.text import krl_comment

ANALOG_FULL_SCALE_V = 10.0  # $ANOUT = ±1 is ±10 V
# Links: the planned joint moves at full acceleration; their speed override is the
# plan's motion.link_speed_percent (ProgramData.link_speed_percent).
PTP_ACC_PERCENT = 100
ORI_SPEED_MARGIN, ORI_SPEED_MIN_DEG_S = 1.2, 100.0  # $VEL.ORI1/2 vs the planned peak
FRAMES_SUFFIX = "_frm"  # <name>_frm: the nominal frames (KRL names: ≤ 24 characters)
MAX_LINE_CHARS = 255  # no published KRL limit; our lines stay far below
NAME_CHARS = 24  # KRL module names: at most 24 characters
_ZEROS = ",E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0"


@dataclasses.dataclass(frozen=True)
class KrlOptions(PointOptions):
    """name: the main program (KRL names ≤ 24 characters, 4 kept for ``_<k>``);
    blend_m: ``C_DIS`` blend distance [m]; tcp_pose_convention: "X_TP" or "X_PF";
    line_limit: most lines (``DEF`` to ``END``) of a seam's module, or None (no split)."""

    name: str = "offline_prog"
    blend_m: float = 0.001
    tcp_pose_convention: str = "X_TP"
    line_limit: int | None = None


class KrlPost(CartesianPost):
    """KRL programs of a job (see the module docstring)."""

    FORMAT = "krl"
    Options = KrlOptions
    NAME_MAX = 20
    FLOW_WHERE_SET = True  # TRIGGERs set the flow's factor where the plan sets the flow

    def __init__(self, job, options: KrlOptions, **flags):
        super().__init__(job, options, **flags)
        check_line_limit(options.line_limit)
        self.rule = PointRule(
            "external_tcp", options.tcp_pose_convention, options.chord_tol_m, options.angle_tol_rad
        )
        self.src: list[str] = []  # main program statements after the settings
        self.decl: list[str] = []  # main .dat declarations
        # the seams' modules: name, process, its LIN moves m (1 .. n of the process)
        self.modules: list[tuple[str, Process, range]] = []
        io = job.process_io
        self.flow = io is not None and io.analog_output is not None
        self.factor = f"{options.name.upper()}_FK"  # the flow's factor: live while $OUT is on
        self.numbers = controller_frames(job.job)

    def point_rule(self) -> PointRule:
        return self.rule

    def conventions(self, record: ProgramRecord) -> list[str]:
        io, names = record.job.process_io, record.job.seam_names
        base, tool = self.numbers.tool, self.numbers.part
        lines = [
            f"Job: {len(names)} seams in this order: {', '.join(names)}.",
            self.numbers.note(f"BASE_DATA[{base}]", f"TOOL_DATA[{tool}]"),
            f"Style external_tcp: $BASE = BASE_DATA[{base}] = fixed tool T in $WORLD (= "
            f"base_link), $TOOL = TOOL_DATA[{tool}] = part P in $FLANGE, $IPO_MODE = #TCP, as "
            f"calibrated on the controller; their nominal values: {self.options.name}"
            f"{FRAMES_SUFFIX}.src (run once, or calibrate instead). E6POS = "
            + ("T in P (X_PF)" if self.rule.convention == "X_PF" else "P in T (X_TP)")
            + "; E6AXIS = q [deg].",
            "Links: PTP to E6AXIS fine points (the planned, collision-checked joint moves); "
            "approach and retract: LIN; seams: LIN with C_DIS, $VEL.CP = planned speed.",
        ]
        if io is not None and io.digital_output is not None:
            lines.append(
                f"Process output $OUT[{io.digital_output}]: TRIGGER WHEN PATH at the plan's "
                f"switch positions (on {io.on_lead_m * 1e3:g} mm before each seam's start, off "
                f"{io.off_lead_m * 1e3:g} mm before its end)."
            )
        if self.flow:
            lines.append(
                f"Flow $ANOUT[{io.analog_output}] = ({io.per_mps:g} V per m/s * $VEL_ACT + "
                f"{io.offset:g} V) / 10 V within [{io.min:g}, {io.max:g}] V while the process "
                f"output is on, {io.idle:g} V otherwise; leads by the dispenser's lag "
                f"{io.lag_s:g} s."
            )
        return lines

    def header(self, lines: list[str]) -> None:
        """KRL comment lines: each text line sanitized (export.text), wrapped at 100."""
        safe = [krl_comment(line) for line in lines]
        self.head = ["; " + part for line in safe for part in textwrap.wrap(line, 100) or [""]]

    def frames(self) -> None:
        """$LOAD, $BASE, $TOOL and the motion settings (in the main program's head, see
        footer); the flow's cyclic output, idle (factor 0) until a TRIGGER makes it live."""
        if not self.flow:
            return
        io = self.job.process_io
        self.decl.append(f"DECL GLOBAL REAL {self.factor}=0.0")
        o = io.offset / ANALOG_FULL_SCALE_V
        lo, hi = io.min / ANALOG_FULL_SCALE_V, io.max / ANALOG_FULL_SCALE_V
        delay = f" DELAY={krl_num(-io.lag_s, 3)}" if io.lag_s > 0 else ""
        self.src += [
            f"; Flow: $ANOUT[{io.analog_output}] follows $VEL_ACT while $OUT is on, idle otherwise",
            f"{self.factor}=0.0",
            f"ANOUT ON $ANOUT[{io.analog_output}]={self.factor}*$VEL_ACT+{krl_num(o, 6)}{delay} "
            f"MINIMUM={krl_num(lo, 4)} MAXIMUM={krl_num(hi, 4)}",
        ]

    def move_joint(self, move: JointMove) -> None:
        if move.number == 0:  # home: the .dat's first point
            self.decl.insert(0, f"DECL E6AXIS XHOME={{{_axes(move.targets[0])}{_ZEROS}}}")
            self.src += ["; Home", "PTP XHOME"]
            return
        n = move.number
        self.src.append(f"; Link {n}: PTP through {len(move.targets)} joint target(s)")
        for w, q in enumerate(move.targets, start=1):
            self.decl.append(f"DECL E6AXIS XL{n}_{w}={{{_axes(q)}{_ZEROS}}}")
            self.src.append(f"PTP XL{n}_{w}")

    def move_linear(self, move: LinearMove) -> None:
        label = f"X{move.kind[0].upper()}{move.number}"  # XA<k> approach end, XR<k> retract end
        what = "Approach" if move.kind == "approach" else "Retract"
        self.src.append(f"; {what} of seam {move.seam}: LIN {move.length_m * 1e3:.1f} mm")
        self.src.append(f"$VEL.CP={vel_cp(move.speed_m_s):.4f}")
        self.src += [self.switch(s) for s in move.switches]
        status, turn = status_turn(self.robot.params, move.q[None])
        pose = krl_frame(self._point(move.X_PT))
        self.decl.append(f"DECL E6POS {label}={{{pose},S {status[0]},T {turn[0]}{_ZEROS}}}")
        self.src.append(f"LIN {label}")

    def set_output(self, switch: Switch) -> str:
        state, output = "TRUE" if switch.event.state else "FALSE", switch.event.output
        return f"TRIGGER WHEN PATH={_path(switch)} DELAY=0 DO $OUT[{output}]={state} PRIO=-1"

    def follow_speed(self, switch: Switch) -> str:
        io = self.job.process_io
        f = io.per_mps / ANALOG_FULL_SCALE_V if switch.event.state else 0.0
        return f"TRIGGER WHEN PATH={_path(switch)} DELAY=0 DO {self.factor}={krl_num(f, 6)} PRIO=-1"

    def call_part(self, process: Process) -> None:
        """The seam's module, or its parts at the line limit, called in turn."""
        module = f"{self.options.name}_{process.number}"
        speeds = self._lin_speeds(process)
        n = len(speeds) - 1
        sizes = [
            len(process.switches_before(m)) + 1 + (speeds[m] != speeds[m - 1])
            for m in range(1, n + 1)
        ]
        opening = [int(speeds[m] == speeds[m - 1]) for m in range(1, n + 1)]
        parts = split_blocks(sizes, self.options.line_limit, frame=2, opening=opening)
        moves = [range(part.start + 1, part.stop + 1) for part in parts]
        names = [module] if len(parts) == 1 else [f"{module}_{j}" for j in range(1, len(parts) + 1)]
        if len(names[-1]) > NAME_CHARS:
            raise ValueError(
                f"line_limit={self.options.line_limit}: part {names[-1]} is longer than KRL's "
                f"{NAME_CHARS} characters (shorten name)"
            )
        self.src.append(f"; Seam {process.seam}: {n} LIN points in {', '.join(names)}")
        self.src += [f"{name}( )" for name in names]
        self.modules += [(name, process, m) for name, m in zip(names, moves, strict=True)]

    def footer(self, out_dir: Path) -> list[Path]:
        name, io, rows = self.options.name, self.job.process_io, self.job.job
        ori = _ori_speed(rows)
        main_src = [
            f"DEF {name}( )",
            *(f"EXT {m}( )" for m, _, _ in self.modules),
            ";FOLD INI",
            "BAS(#INITMOV,0)",
            ";ENDFOLD (INI)",
            *_load(self.load, rows.X_EP),
            f"$BASE=BASE_DATA[{self.numbers.tool}]",
            f"$TOOL=TOOL_DATA[{self.numbers.part}]",
            "$IPO_MODE=#TCP",
            "$ORI_TYPE=#VAR",
            "$ADVANCE=3",
            f"BAS(#VEL_PTP,{rows.link_speed_percent:g})",
            f"BAS(#ACC_PTP,{PTP_ACC_PERCENT})",
            f"$VEL.ORI1={ori:.0f}",
            f"$VEL.ORI2={ori:.0f}",
            f"$APO.CDIS={self.options.blend_m * 1e3:.3f}",
            *self.src,
            *([f"ANOUT OFF $ANOUT[{io.analog_output}]"] if self.flow else []),
            "END",
        ]
        main_dat = [
            f"DEFDAT {name}" + (" PUBLIC" if self.flow else ""),
            "EXT BAS (BAS_COMMAND :IN,REAL :IN )",
            *self.decl,
            "ENDDAT",
        ]
        limit = self.options.line_limit
        statements = sum(not line.startswith(";") for line in main_src)
        if limit is not None and statements > limit:
            raise ValueError(f"line_limit={limit}: the main program alone needs {statements} lines")
        files = _write(out_dir, name, self.head + main_src, self.head + main_dat)
        for module, process, moves in self.modules:
            files += self._seam_module(out_dir, module, process, moves)
        return files + self._nominal_frames(out_dir)

    def _nominal_frames(self, folder: Path) -> list[Path]:
        """``<name>_frm.src`` / ``.dat``: the cell's nominal frames written into the
        numbered ``BASE_DATA`` (the fixed tool T in $WORLD = B, external TCP: BASE_TYPE
        #TCP) and ``TOOL_DATA`` (the part P in $FLANGE, TOOL_TYPE #BASE), to run once."""
        rows, module = self.job.job, f"{self.options.name}{FRAMES_SUFFIX}"
        base, tool = self.numbers.tool, self.numbers.part
        src = [
            f"DEF {module}( )",
            "; NOMINAL FRAMES of the cell (its CAD values): run once to load them into the",
            "; controller, or calibrate these frames on the controller instead.",
            f"BASE_DATA[{base}]={{{krl_frame(rows.X_BT)}}}",
            f"BASE_TYPE[{base}]=#TCP",
            f"TOOL_DATA[{tool}]={{{krl_frame(X_KE @ rows.X_EP)}}}",
            f"TOOL_TYPE[{tool}]=#BASE",
            "END",
        ]
        dat = [f"DEFDAT {module}", "ENDDAT"]
        return _write(folder, module, self.head + src, self.head + dat)

    def _point(self, X_PT: np.ndarray) -> np.ndarray:
        """(…, 4, 4) the E6POS of the tool frame T in P: P in T (X_TP) or T in P."""
        return X_PT if self.rule.convention == "X_PF" else np.linalg.inv(X_PT)

    @staticmethod
    def _lin_speeds(process: Process) -> list[float | None]:
        """``$VEL.CP`` [m/s] of each LIN m = 1 .. n of the seam (the highest planned
        speed on its segment, floored to 0.1 mm/s); entry 0 None (no LIN)."""
        data, idx = process.data, process.indices
        return [None] + [
            vel_cp(data.tcp_speed[idx[m - 1] : idx[m] + 1].max()) for m in range(1, len(idx))
        ]

    def _seam_module(self, folder: Path, module: str, process: Process, moves: range) -> list[Path]:
        """``module.src`` / ``.dat``: the seam's LIN moves ``moves`` to its points (the
        seam's first point is where the approach ended: the main .dat's XA<k>), with the
        switches before the LIN whose motion holds them; ``$VEL.CP`` where it changes
        and at the module's start."""
        data, idx = process.data, process.indices
        names = [f"XP{k + 1}" for k in range(len(idx))]
        status, turn = status_turn(self.robot.params, data.q[idx])
        decls = [
            f"DECL E6POS {n}={{{krl_frame(X)},S {s},T {t}{_ZEROS}}}"
            for n, X, s, t in zip(names, self._point(data.X_PT[idx]), status, turn, strict=True)
        ]
        speeds = self._lin_speeds(process)
        body, v_now = [], None
        for m in moves:
            # the last LIN of the seam stops exactly
            body += [f"$VEL.CP={speeds[m]:.4f}"] if speeds[m] != v_now else []
            body += [self.switch(s) for s in process.switches_before(m)]
            body.append(f"LIN {names[m]}" + (" C_DIS" if m < len(idx) - 1 else ""))
            v_now = speeds[m]
        note = [
            f"; Seam {process.seam}: deviation <= {process.max_chord_m * 1e3:.4f} mm, "
            f"{np.rad2deg(process.max_angle_rad):.4f} deg from the plan"
        ]
        src = [f"DEF {module}( )", *body, "END"]
        dat = [
            f"DEFDAT {module}",
            "EXT BAS (BAS_COMMAND :IN,REAL :IN )",
            *(decls[m] for m in moves),
            "ENDDAT",
        ]
        return _write(folder, module, self.head + note + src, self.head + note + dat)


def _axes(q: np.ndarray) -> str:
    return ",".join(f"A{i + 1} {krl_num(v, 5)}" for i, v in enumerate(np.rad2deg(q)))


def _path(switch: Switch) -> str:
    """``PATH`` of a TRIGGER: the switch's distance before its motion's end [mm], < 0."""
    return krl_num(-switch.before_end_m * 1e3, 3)


def _load(load, X_EP: np.ndarray) -> list[str]:
    """``$LOAD`` (gripper + part on $FLANGE = E, point mass) of the program's load
    (``export.payload.Payload`` or None: no statement, the header says why)."""
    if load is None:
        return []
    mass, p_EC = load.total(X_EP)
    x, y, z = (krl_num(v, 1) for v in (X_KE[:3, :3] @ p_EC + X_KE[:3, 3]) * 1e3)
    # CM's A, B, C: the principal axes of inertia in $FLANGE; J: the moments about them.
    inertia = load.total_inertia or Principal(np.zeros(3), np.eye(3))
    a, b, c = (krl_num(v, 4) for v in kuka_abc_deg((X_KE[:3, :3] @ inertia.R)[None])[0])
    jx, jy, jz = (krl_num(v, 5) for v in inertia.moments)
    return [
        f"$LOAD={{M {krl_num(mass, 3)},CM {{X {x},Y {y},Z {z},A {a},B {b},C {c}}},"
        f"J {{X {jx},Y {jy},Z {jz}}}}}"
    ]


def _ori_speed(rows) -> float:
    """``$VEL.ORI1/2`` [deg/s]: the planned peak of the flange's turn rate with a margin."""
    R = rows.X_BE[:, :3, :3]
    omega = Rotation.from_matrix(np.swapaxes(R[:-1], 1, 2) @ R[1:]).magnitude() / np.diff(rows.t)
    return max(np.ceil(ORI_SPEED_MARGIN * np.rad2deg(omega.max())), ORI_SPEED_MIN_DEG_S)


def _write(folder: Path, name: str, src: list[str], dat: list[str]) -> list[Path]:
    """Write name.src and name.dat with CRLF line ends (as KSS writes them)."""
    files = []
    for ext, lines in (("src", src), ("dat", dat)):
        assert max(len(line) for line in lines) <= MAX_LINE_CHARS
        files.append(folder / f"{name}.{ext}")
        write_atomic(files[-1], "\r\n".join(lines) + "\r\n")
    return files
