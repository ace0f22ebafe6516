"""KUKA KRL for KSS 8: the plan as ``name.src`` + ``name.dat`` (numbered parts if long).

Styles. ``external_tcp``: ``$IPO_MODE=#TCP``, ``$BASE`` = the fixed tool T in ``$WORLD``
(KSS keeps a fixed tool as a base), ``$TOOL`` = the part P in ``$FLANGE`` (the
robot-carried workpiece is the "tool"); each LIN point is a pose between P and T, written
as ``tcp_pose_convention`` says. The controller then moves the fixed TCP in straight lines
across the part, which is what ``select_points`` assumes for the process frames X_PF.
``flange``: ``$IPO_MODE=#BASE``, ``$BASE=$NULLFRAME``, the same ``$TOOL``; the points are
X_BP, refined until the part, interpolated linearly in B, carries the path under the
nozzle within the tolerances.

Frames besides I, B, E, P, F, T: K = KUKA's ``$FLANGE``, z out of the flange. It is the
URDF ``tool0`` E (kuka_experimental marks ``tool0`` as "the $FLANGE coordinate system in
KUKA KRC controllers"; KUKA tool data put straight tools along flange z); ``X_KE`` keeps
that assumption in one place. B = ``base_link`` = ``$ROBROOT`` (kuka_experimental
``base``), taken as ``$WORLD`` (the robot at the world origin, KSS's default).

Edge units: X, Y, Z [mm]; A, B, C [deg] with R = Rz(A)·Ry(B)·Rx(C) (KUKA Z-Y′-X″);
E6AXIS A1..A6 = q [deg] (robots/kuka_* URDFs carry KUKA's joint signs and zeros);
``$VEL.CP`` [m/s]; ``$APO.CDIS`` [mm]. Status and Turn: see ``status_turn``.
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.atomic import write_atomic
from offline_prog.export.densify import densify
from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M
from offline_prog.export.header import header_lines
from offline_prog.export.kuka.krl_header import krl_comments, krl_conventions
from offline_prog.export.kuka.krl_points import process_points
from offline_prog.export.kuka.kuka import (
    X_KE,
    joints_near,
    krl_frame,
    krl_num,
    status_turn,
    vel_cp,
)
from offline_prog.export.payload import payload
from offline_prog.export.program import ProgramData

STYLES = ("external_tcp", "flange")
# "X_TP": the point is P in T, flange = $BASE:POS:inv($TOOL), KSS's rule for every
# Cartesian position (POS = $TOOL in $BASE). "X_PF": the point is T in P (the process
# frame), flange = $BASE:inv(POS):inv($TOOL).
TCP_POSE_CONVENTIONS = ("X_TP", "X_PF")
MAX_NAME_CHARS = 24  # KRL names (KSS 8 KRL quick guide)
MAX_LINE_CHARS = 255  # no published KRL limit; our lines stay far below
ORI_SPEED_MARGIN, ORI_SPEED_MIN_DEG_S = 1.2, 100.0  # $VEL.ORI1/2 vs the planned peak
PTP_VEL_PERCENT, PTP_ACC_PERCENT = 20, 50  # the joint move to the approach pose [%]
_ZEROS = ",E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0"
_MAIN = """DEF {name}( )
{ext};FOLD INI
BAS(#INITMOV,0)
;ENDFOLD (INI)
{load}$BASE={base}
$TOOL=PART_ON_FLANGE
$IPO_MODE={ipo}
$ORI_TYPE=#VAR
$ADVANCE=3
BAS(#VEL_PTP,{ptp_vel})
BAS(#ACC_PTP,{ptp_acc})
$VEL.ORI1={ori:.0f}
$VEL.ORI2={ori:.0f}
$APO.CDIS={cdis:.3f}
; Start: PTP (joints) to {start}, then LIN onto the path
PTP {start_name}
$VEL.CP={v:.4f}
LIN XP1
; Process start
{process}
; Process end{retract}
END"""


@dataclasses.dataclass(frozen=True)
class KrlResult:
    """Files written (main .src/.dat, then name_1.src/.dat, ...), the process LIN points
    (``indices`` (n_points,) into the plan's samples, first and last included), and the
    largest deviation [m, rad] of any plan sample from the controller's interpolation."""

    files: list[Path]
    n_points: int
    indices: np.ndarray
    max_chord_m: float
    max_angle_rad: float


def _process_lines(names, idx, speed, line_limit: int) -> list[list[str]]:
    """``$VEL.CP`` and ``LIN`` lines to XP2..XPn, in parts of at most line_limit lines.

    $VEL.CP of a segment is the highest planned speed [m/s] on it, floored to 0.1 mm/s
    (written when it changes and at the start of every part); the last LIN stops exactly.
    """
    parts, v_now = [[]], None
    for m in range(1, len(idx)):
        v = vel_cp(speed[idx[m - 1] : idx[m] + 1].max())
        lin = f"LIN {names[m]}" + (" C_DIS" if m < len(idx) - 1 else "")
        block = [f"$VEL.CP={v:.4f}", lin] if v != v_now else [lin]
        if parts[-1] and len(parts[-1]) + len(block) > line_limit:
            parts.append([])
            block = [f"$VEL.CP={v:.4f}", lin]
        parts[-1] += block
        v_now = v
    return parts


def _check(name: str, style: str, convention: str, line_limit: int, tolerances) -> None:
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name) or len(name) > MAX_NAME_CHARS - 4:
        raise ValueError(f"write_krl: name {name!r} is not a KRL name of <= 20 characters")
    if style not in STYLES or convention not in TCP_POSE_CONVENTIONS:
        raise ValueError(
            f"write_krl: style {style!r} / tcp_pose_convention {convention!r} "
            f"not in {STYLES} / {TCP_POSE_CONVENTIONS}"
        )
    if line_limit < 2 or min(tolerances) <= 0:
        raise ValueError("write_krl: expected line_limit >= 2 and tolerances > 0")


def write_krl(
    data: ProgramData,
    out_dir: Path,
    *,
    name: str = "offline_prog",
    style: str = "external_tcp",
    chord_tol_m: float = DEFAULT_CHORD_TOL_M,
    angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD,
    line_limit: int = 1400,
    tcp_pose_convention: str = "X_TP",
    approach_m: float = 0.0,
    blend_m: float = 0.001,
    forced: bool = False,
) -> KrlResult:
    """Write the KRL program for a plan (see the module docstring for the frames).

    The main program sets the frames, moves PTP (E6AXIS) to the plan's first joints
    (or, with ``approach_m`` > 0, to the joint solution nearest them at the pose
    ``approach_m`` off the path start against the process normal, y of F: a move the
    plan does not hold), goes LIN onto the path, runs the process LIN points (``C_DIS``
    with ``$APO.CDIS`` = blend_m; ``$VEL.CP`` see ``_process_lines``: the TCP speed, or
    the part-origin speed in the flange style) and, with ``approach_m`` > 0, retracts
    LIN by ``approach_m``. A whole job's program (``krl_job``) moves only as planned.
    Process lines beyond ``line_limit`` go to ``name_1``, ``name_2``, ...
    (own .src/.dat each), called in order from the main program.

    Args:
        data: the plan; its robot must be an OPW arm with KUKA joint conventions.
        out_dir: folder for the files (created).
        name: KRL program name (<= 20 characters, leaving room for ``_<k>``).
        style: "external_tcp" ($IPO_MODE #TCP) or "flange" (#BASE, dense X_BP points).
        chord_tol_m, angle_tol_rad: allowed deviation of the plan from the LIN path [m, rad].
        line_limit: most process lines in one .src before splitting.
        tcp_pose_convention: "X_TP" (default, P in T) or "X_PF" (T in P), external_tcp only.
        approach_m, blend_m: approach/retract distance (0: none, the default) and C_DIS
            blend distance [m].
        forced: the plan failed and is exported anyway (the header says so).

    Raises:
        ValueError: a bad argument, a non-OPW robot, or an unreachable approach/retract.
    """
    _check(name, style, tcp_pose_convention, line_limit, (chord_tol_m, angle_tol_rad))
    robot = data.load_robot()
    if robot.family != "opw":
        raise ValueError(f"write_krl: robot {data.robot} is not an OPW arm (family {robot.family})")
    dense = densify(data, chord_tol_m, angle_tol_rad)
    data = dense.data
    tolerances = dense.selection_tolerances(chord_tol_m, angle_tol_rad)
    idx, max_chord, max_angle = process_points(data, style, *tolerances, tcp_pose_convention)
    max_chord, max_angle = dense.bound(max_chord, max_angle)
    off = np.eye(4)
    off[1, 3] = -approach_m  # the tool frame backed off against the normal n = y of F
    X_PF_off = data.X_PF[[0, -1]] @ off  # approach, retract
    X_BE_off = data.X_BT @ np.linalg.inv(X_PF_off) @ np.linalg.inv(data.X_EP)
    retract = approach_m > 0
    q_start, q_retract = data.q[0], data.q[-1]
    if retract:
        q_start = joints_near(robot, X_BE_off[0], data.q[0], data, "approach")
        q_retract = joints_near(robot, X_BE_off[1], data.q[-1], data, "retract")
    X_PF = np.concatenate([data.X_PF[idx], X_PF_off[1:]])  # the process points, retract
    X_BE = np.concatenate([data.X_BE[idx], X_BE_off[1:]])
    if style == "flange":
        poses, base, ipo = X_BE @ data.X_EP, "$NULLFRAME", "#BASE"
        speed = np.linalg.norm(
            np.gradient((data.X_BE @ data.X_EP)[:, :3, 3], data.t, axis=0), axis=1
        )
    else:
        poses = np.linalg.inv(X_PF) if tcp_pose_convention == "X_TP" else X_PF
        base, ipo, speed = "FIXED_TOOL", "#TCP", data.tcp_speed
    status, turn = status_turn(robot.params, np.vstack([data.q[idx], q_retract]))
    names = [f"XP{k + 1}" for k in range(len(idx))] + ["XRETRACT"]
    decl = {
        n: f"DECL E6POS {n}={{{krl_frame(X)},S {s},T {t}{_ZEROS}}}"
        for n, X, s, t in zip(names, poses, status, turn, strict=True)
    }
    R = data.X_BE[:, :3, :3]
    omega = Rotation.from_matrix(np.swapaxes(R[:-1], 1, 2) @ R[1:]).magnitude() / np.diff(data.t)
    parts = _process_lines(names, idx, speed, line_limit)
    subs = [f"{name}_{k + 1}" for k in range(len(parts))] if len(parts) > 1 else []
    conventions = krl_conventions(style, tcp_pose_convention, len(idx), chord_tol_m, angle_tol_rad)
    conventions[-2] += (
        f" (achieved {max_chord * 1e3:.4f} mm, {np.rad2deg(max_angle):.4f} deg, {dense.basis})."
    )
    head = krl_comments(header_lines(data, conventions=conventions, forced=forced))
    src = _MAIN.format(
        name=name,
        load=_load(data),
        ext="".join(f"EXT {sub}( )\n" for sub in subs),
        base=base,
        ipo=ipo,
        ptp_vel=PTP_VEL_PERCENT,
        ptp_acc=PTP_ACC_PERCENT,
        ori=max(np.ceil(ORI_SPEED_MARGIN * np.rad2deg(omega.max())), ORI_SPEED_MIN_DEG_S),
        cdis=blend_m * 1e3,
        start=f"{approach_m * 1e3:g} mm off the path start" if retract else "the plan's start",
        start_name="XAPPROACH" if retract else "XSTART",
        retract=(
            f". Retract {approach_m * 1e3:g} mm\n$VEL.CP={vel_cp(data.process_speed_m_s):.4f}"
            "\nLIN XRETRACT"
            if retract
            else ""
        ),
        v=vel_cp(data.process_speed_m_s),
        process="\n".join([f"{sub}( )" for sub in subs] or parts[0]),
    )
    axes = ",".join(f"A{i + 1} {krl_num(v, 5)}" for i, v in enumerate(np.rad2deg(q_start)))
    dat = [
        f"DEFDAT {name}",
        "EXT BAS (BAS_COMMAND :IN,REAL :IN )",
        f"DECL FRAME PART_ON_FLANGE={{{krl_frame(X_KE @ data.X_EP)}}}",
        *([f"DECL FRAME FIXED_TOOL={{{krl_frame(data.X_BT)}}}"] if style != "flange" else []),
        f"DECL E6AXIS {'XAPPROACH' if retract else 'XSTART'}={{{axes}{_ZEROS}}}",
        decl["XP1"],
        *([decl["XRETRACT"]] if retract else []),
    ]
    dat += [] if subs else [decl[n] for n in names[1:-1]]
    files = _write(Path(out_dir), name, head + src.splitlines(), head + dat + ["ENDDAT"])
    for k, (sub, lines) in enumerate(zip(subs, parts if subs else [], strict=True)):
        part_head = head + [f"; Part {k + 1} of {len(subs)} of program {name}"]
        points = [decl[line.split()[1]] for line in lines if line.startswith("LIN")]
        files += _write(
            Path(out_dir),
            sub,
            [*part_head, f"DEF {sub}( )", *lines, "END"],
            [*part_head, f"DEFDAT {sub}", *points, "ENDDAT"],
        )
    return KrlResult(files, len(idx), idx, max_chord, max_angle)


def _load(data: ProgramData) -> str:
    """``$LOAD`` (gripper + part on $FLANGE = E, point mass) when the cell gives both."""
    load = payload(data.payload)
    if load is None:
        return ""  # the header warns: PAYLOAD NOT SET
    mass, p_EC = load.total(data.X_EP)
    x, y, z = (krl_num(v, 1) for v in (X_KE[:3, :3] @ p_EC + X_KE[:3, 3]) * 1e3)
    return (
        f"$LOAD={{M {krl_num(mass, 3)},CM {{X {x},Y {y},Z {z},A 0,B 0,C 0}},J {{X 0,Y 0,Z 0}}}}\n"
    )


def _write(folder: Path, name: str, src: list[str], dat: list[str]) -> list[Path]:
    """Write name.src and name.dat with CRLF line ends (as KSS writes them)."""
    files = []
    for ext, lines in (("src", src), ("dat", dat)):
        assert max(len(line) for line in lines) <= MAX_LINE_CHARS
        files.append(folder / f"{name}.{ext}")
        write_atomic(files[-1], "\r\n".join(lines) + "\r\n")
    return files
