"""FANUC TP programs as LS text (``/PROG … /ATTR … /MN … /POS … /END``) for one seam.

Form: **flange-style, dense point list** (KRL's ``flange`` style, ``export.kuka.krl_points``).
FANUC sells a Remote TCP option for a robot that carries the part past a fixed tool, but
this writer has no FANUC document at hand to cite for its instructions, so it does not
use it (the issue's rule: cite the source or write the flange form and say so). The
tool frame is the part: UTOOL[1] = X_EP (P in the faceplate = URDF tool0, z out of the
flange), and every position is the part frame X_BP = X_BE · X_EP in a user frame equal
to the URDF base_link (UFRAME[1] = 0, 0, -c1, 0, 0, 0 in FANUC's world, see
export.fanuc.fanuc). The controller interpolates P linearly between the points while the
tool stays fixed, so the points are split until the tool's curve on the part also stays
within the chord and angle tolerances (``process_points(style="flange")`` after
``densify``). Speeds are each segment's planned mean speed of P's origin [mm/sec];
CNT100 between process points, FINE at the ends. By default the program moves only as
planned: ``J`` (joint represented) to the plan's first joints, then the ``L`` points.
With ``approach_m`` > 0, as the RAPID writer's option: ``J`` to the approach pose,
``approach_m`` off the surface along -y of F, ``L`` onto the first point and ``L`` back
off after the last (moves the plan did not check). This writer serves one-seam plan
folders written before every cell became a job (``fanuc_job`` writes every new plan).
Each program holds at most
``line_limit`` /MN lines; longer ones call sub-programs ``NAME_2 …``.
"""

from __future__ import annotations

import dataclasses
import datetime
from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.export.abb.rapid import approach_and_retract
from offline_prog.export.densify import densify
from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M
from offline_prog.export.fanuc.fanuc import (
    cartesian_pos,
    config_strings,
    fanuc_axes_deg,
    joint_pos,
    wpr_deg,
)
from offline_prog.export.header import header_lines
from offline_prog.export.kuka.krl_points import process_points
from offline_prog.export.payload import payload
from offline_prog.export.program import ProgramData
from offline_prog.export.text import fanuc_comments, identifier

NAME_MAX = 36  # program names: letters, digits, _; this writer keeps 36 characters at most
DEFAULT_LINE_LIMIT = 2000  # /MN lines per program (splits into called sub-programs)
JOINT_SPEED_PCT = 20  # J moves to the start
APPROACH_SPEED_MMS = 20  # L moves onto and off the surface
MAX_SPEED_MMS = 2000  # FANUC L moves take at most 2000 mm/sec
UF, UT = 1, 1


@dataclasses.dataclass(frozen=True)
class FanucResult:
    """Files written (main program first), the (densified) plan rows behind each process
    point, and the bounds on the tool's deviation on the part [m, rad]."""

    files: tuple[Path, ...]
    indices: np.ndarray
    max_chord_m: float
    max_angle_rad: float


def _attr(name: str, lines: int, comment: str) -> str:
    now = datetime.datetime.now(datetime.UTC)
    stamp = f"DATE {now:%y-%m-%d}  TIME {now:%H:%M:%S}"
    return (
        f'/PROG  {name}\n/ATTR\nOWNER\t\t= MNEDITOR;\nCOMMENT\t\t= "{comment[:16]}";\n'
        f"PROG_SIZE\t= 0;\nCREATE\t\t= {stamp};\nMODIFIED\t= {stamp};\nFILE_NAME\t= ;\n"
        f"VERSION\t\t= 0;\nLINE_COUNT\t= {lines};\nMEMORY_SIZE\t= 0;\nPROTECT\t\t= READ_WRITE;\n"
        "TCD:  STACK_SIZE\t= 0,\n      TASK_PRIORITY\t= 50,\n      TIME_SLICE\t= 0,\n"
        "      BUSY_LAMP_OFF\t= 0,\n      ABORT_REQUEST\t= 0,\n      PAUSE_REQUEST\t= 0;\n"
        "DEFAULT_GROUP\t= 1,*,*,*,*;\nCONTROL_CODE\t= 00000000 00000000;\n"
    )


def ls_text(name: str, statements: list[str], positions: list[str], comment: str) -> str:
    """A whole LS file: numbered /MN lines (statements without the closing `` ;``) and
    the /POS entries."""
    mn = "".join(f"{k:4d}:{s} ;\n" for k, s in enumerate(statements, start=1))
    pos = "\n".join(positions)
    return _attr(name, len(statements), comment) + f"/MN\n{mn}/POS\n{pos}\n/END\n"


def segment_speeds_mms(t: np.ndarray, X_BU: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """(n-1,) planned mean speed of the TCP U (origin of X_BU (N, 4, 4) [m]; times t
    (N,) [s]) on each segment between rows idx [mm/sec], whole numbers in [1, 2000]."""
    p = X_BU[idx, :3, 3]
    dt = np.maximum(np.diff(t[idx]), 1e-9)
    speeds = np.linalg.norm(np.diff(p, axis=0), axis=1) / dt * 1e3
    return np.clip(np.round(speeds), 1, MAX_SPEED_MMS).astype(int)


def write_fanuc(
    data: ProgramData,
    out_dir: Path,
    *,
    name: str = "OFFLINE_PROG",
    chord_tol_m: float = DEFAULT_CHORD_TOL_M,
    angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD,
    line_limit: int = DEFAULT_LINE_LIMIT,
    approach_m: float = 0.0,
    forced: bool = False,
) -> FanucResult:
    """Write ``<name>.ls`` (and ``<name>_<k>.ls`` sub-programs) for a one-seam plan.

    Args:
        data: the plan, of an OPW robot.
        chord_tol_m, angle_tol_rad: the tool's largest deviation on the part [m, rad].
        line_limit: most /MN lines in one program.
        approach_m: approach / retract distance off the surface [m] (0, the default, or
            out of reach: none), as the RAPID writer's: J to the approach, L to the first
            point, and L back off after the last.

    Raises:
        ValueError: naming the bad argument.
    """
    identifier(name, max_chars=NAME_MAX - 4, what="name")
    if not (chord_tol_m > 0 and angle_tol_rad > 0 and approach_m >= 0) or line_limit < 8:
        raise ValueError(
            "need chord_tol_m > 0, angle_tol_rad > 0, approach_m >= 0 and line_limit >= 8"
        )
    robot = data.load_robot()
    if robot.family != "opw":
        raise ValueError(f"data.robot={data.robot!r}: FANUC export needs an OPW robot")
    dense = densify(data, chord_tol_m, angle_tol_rad)
    data = dense.data
    tolerances = dense.selection_tolerances(chord_tol_m, angle_tol_rad)
    idx, chord, angle = process_points(data, "flange", *tolerances)
    max_chord, max_angle = dense.bound(chord, angle)
    X_BP = data.X_BE @ data.X_EP
    configs = config_strings(robot, data.q[idx])
    speeds = segment_speeds_mms(data.t, X_BP, idx)
    conventions = frame_conventions(robot, data.X_EP) + [
        f"Points: {len(idx)} of {len(data.t)} samples; the tool on the part within "
        f"{max_chord * 1e3:.4f} mm, {np.rad2deg(max_angle):.4f} deg of the plan ({dense.basis});",
        "speeds = the planned mean speed of P per segment. CNT100 between points, FINE at",
        "the ends: the rounding stays between neighbouring points, which FANUC does not",
        "bound in mm; lower --chord-tol-mm for denser points.",
    ]
    off = approach_and_retract(robot, data, approach_m) if approach_m > 0 else None
    approach = f"{approach_m * 1e3:g} mm along -y of F" if off else "none"
    conventions.append(
        f"Approach/retract: {approach}"
        + (" (OUT OF REACH)" if approach_m and not off else "")
        + f", L at {APPROACH_SPEED_MMS} mm/sec, not collision-checked."
    )
    conventions += payload_conventions(data)
    header = header_lines(data, conventions=conventions, forced=forced)
    start = [
        f"  UFRAME_NUM={UF}",
        f"  UTOOL_NUM={UT}",
        "  PAYLOAD[1]",
        f"J P[1] {JOINT_SPEED_PCT}% FINE",
    ]
    q_start, targets = data.q[idx[0]], []  # (X_BP, config, statement tail) per L move
    if off is not None:
        q_start = off[0][1]
        targets.append((X_BP[idx[0]], configs[0], f"{APPROACH_SPEED_MMS}mm/sec FINE"))
    for i in range(1, len(idx)):
        term = "FINE" if i == len(idx) - 1 else "CNT100"
        targets.append((X_BP[idx[i]], configs[i], f"{speeds[i - 1]}mm/sec {term}"))
    if off is not None:
        q_ret = off[1][1]
        X_BP_ret = robot.forward(q_ret[None])[0] @ data.X_EP
        targets.append(
            (X_BP_ret, config_strings(robot, q_ret[None])[0], f"{APPROACH_SPEED_MMS}mm/sec FINE")
        )
    positions = {1: joint_pos(1, fanuc_axes_deg(robot, q_start[None])[0], uf=UF, ut=UT)}
    moves = []
    for k, (X, config, tail) in enumerate(targets, start=2):
        moves.append((k, f"L P[{k}] {tail}"))
        positions[k] = cartesian_pos(k, X, config, uf=UF, ut=UT)
    texts = _split(name, remarks(header) + start, moves, positions, line_limit)
    files = []
    for program, text in texts.items():
        files.append(Path(out_dir) / f"{program}.ls")
        write_atomic(files[-1], text)
    return FanucResult(tuple(files), idx, max_chord, max_angle)


def frame_conventions(robot, X_EP: np.ndarray) -> list[str]:
    """Header lines: the program's form, frames, configuration and axis conventions."""
    return [
        "FLANGE-STYLE PROGRAM, DENSE POINT LIST: not FANUC Remote TCP (no FANUC document",
        "cited for it). UTOOL[1] = the part frame P in the faceplate (URDF tool0):",
        f"({_frame(X_EP)}).",
        f"UFRAME[1] = URDF base_link = (0,0,{-robot.params.c1 * 1e3:.3f},0,0,0) in FANUC world.",
        "Positions: P in UFRAME[1]; frames (X,Y,Z mm, W,P,R deg about fixed x, y, z).",
        "CONFIG: N/F = J5 <= 0 / > 0, U/D elbow, T/B wrist centre front/back of J1;",
        "turns of J1, J4, J6. Joint positions: FANUC axes, J3 from the horizontal",
        f"(J3 = q3 {'+' if robot.j23_factor > 0 else '-'} q2 of the URDF, "
        "ROS-I fanuc_driver J23_factor)."
        if robot.j23_coupled
        else "(J1..J6 = the URDF joints).",
    ]


def payload_conventions(data: ProgramData) -> list[str]:
    """The PAYLOAD[1] header line, when the cell gives the masses."""
    load = payload(data.payload)
    if load is None:
        return []
    mass, p_EC = load.total(data.X_EP)
    return [
        f"PAYLOAD[1]: {mass:.3f} kg at ({', '.join(f'{v * 100:.2f}' for v in p_EC)}) cm "
        "in the faceplate frame: set it in the payload schedule before running."
    ]


def remarks(lines: list[str]) -> list[str]:
    """TP remark statements (``! text``, at most 32 characters each) for header lines."""
    return [f"  ! {piece}" for line in lines for piece in fanuc_comments(line)]


def _frame(X: np.ndarray) -> str:
    """``x, y, z, w, p, r`` [mm, deg] of a 4x4 transform [m]."""
    values = [*(X[:3, 3] * 1e3), *wpr_deg(X[:3, :3])]
    return ", ".join(f"{v:.3f}" for v in values)


def _split(name, head, moves, positions, line_limit) -> dict[str, str]:
    """Programs: main (head + moves, or head + CALLs) and its sub-programs."""
    comment = "offline_prog"
    if len(head) + len(moves) <= line_limit:
        used = [1] + [k for k, _ in moves]
        return {
            name: ls_text(name, head + [s for _, s in moves], [positions[k] for k in used], comment)
        }
    size = line_limit - 2
    chunks = [moves[k : k + size] for k in range(0, len(moves), size)]
    subs = [f"{name}_{k}" for k in range(2, len(chunks) + 2)]
    main_lines = head + [f"  CALL {sub}" for sub in subs]
    if len(main_lines) > line_limit:
        raise ValueError(
            f"line_limit={line_limit}: the main program alone needs {len(main_lines)} lines"
        )
    texts = {name: ls_text(name, main_lines, [positions[1]], comment)}
    for sub, chunk in zip(subs, chunks, strict=True):
        lines = [f"  UFRAME_NUM={UF}", f"  UTOOL_NUM={UT}"] + [s for _, s in chunk]
        texts[sub] = ls_text(sub, lines, [positions[k] for k, _ in chunk], comment)
    return texts
