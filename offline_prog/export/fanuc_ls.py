"""FANUC TP programs as LS text (``/PROG … /ATTR … /MN … /POS … /END``) for one seam.

Form: **flange-style, dense point list**. FANUC sells a Remote TCP option for a robot
that carries the part past a fixed tool, but this writer has no FANUC document at hand
to cite for its instructions, so it does not use it (the issue's rule: cite the source or
write the flange form and say so). The tool frame is therefore the faceplate
(UTOOL[1] = 0, 0, 0, 0, 0, 0: URDF tool0, z out of the flange) and every position is the
flange pose X_BE in a user frame equal to the URDF base_link
(UFRAME[1] = 0, 0, -c1, 0, 0, 0 in FANUC's world, see export.fanuc). The points are
chosen on the flange path so that linear moves between them keep the fixed tool's point
on the part within the chord tolerance: chord ≤ tol/2 of the flange and angle ≤
tol / (2 · lever), lever = the largest distance from the flange to the tool point
(``select_points`` on X_BE, after ``densify``). Speeds are each segment's planned mean
flange speed [mm/sec]; CNT100 between process points, FINE at the ends. Each program
holds at most ``line_limit`` /MN lines; longer ones call sub-programs ``NAME_2 …``.
"""

from __future__ import annotations

import dataclasses
import datetime
from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.export.densify import densify
from offline_prog.export.density import DEFAULT_CHORD_TOL_M, select_points
from offline_prog.export.fanuc import cartesian_pos, config_strings, fanuc_axes_deg, joint_pos
from offline_prog.export.header import header_lines
from offline_prog.export.payload import payload
from offline_prog.export.program import ProgramData
from offline_prog.export.text import fanuc_comments, identifier

NAME_MAX = 36  # program names: letters, digits, _; this writer keeps 36 characters at most
DEFAULT_LINE_LIMIT = 2000  # /MN lines per program (splits into called sub-programs)
JOINT_SPEED_PCT = 20  # J moves to the start
MAX_SPEED_MMS = 2000  # FANUC L moves take at most 2000 mm/sec
UF, UT = 1, 1


@dataclasses.dataclass(frozen=True)
class FanucResult:
    """Files written (main program first), the plan rows behind each process point,
    and the bound on the tool point's deviation [m]."""

    files: tuple[Path, ...]
    indices: np.ndarray
    max_deviation_m: float


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
    """A whole LS file: numbered /MN lines and the /POS entries."""
    mn = "".join(f"{k:4d}:{s}\n" for k, s in enumerate(statements, start=1))
    pos = "\n".join(positions)
    return _attr(name, len(statements), comment) + f"/MN\n{mn}/POS\n{pos}\n/END\n"


def segment_speeds_mms(data: ProgramData, idx: np.ndarray) -> np.ndarray:
    """(n-1,) mean flange speed of each segment [mm/sec], whole numbers in [1, 2000]."""
    p = data.X_BE[idx, :3, 3]
    dt = np.maximum(np.diff(data.t[idx]), 1e-9)
    speeds = np.linalg.norm(np.diff(p, axis=0), axis=1) / dt * 1e3
    return np.clip(np.round(speeds), 1, MAX_SPEED_MMS).astype(int)


def write_fanuc(
    data: ProgramData,
    out_dir: Path,
    *,
    name: str = "OFFLINE_PROG",
    chord_tol_m: float = DEFAULT_CHORD_TOL_M,
    angle_tol_rad: float | None = None,
    line_limit: int = DEFAULT_LINE_LIMIT,
    forced: bool = False,
) -> FanucResult:
    """Write ``<name>.ls`` (and ``<name>_<k>.ls`` sub-programs) for a one-seam plan.

    Args:
        data: the plan, of an OPW robot.
        chord_tol_m: the tool point's largest deviation from the planned path [m].
        angle_tol_rad: a tighter bound on the flange's rotation between points (None:
            from chord_tol_m and the lever, see the module docstring).
        line_limit: most /MN lines in one program.

    Raises:
        ValueError: naming the bad argument.
    """
    identifier(name, max_chars=NAME_MAX - 4, what="name")
    if not chord_tol_m > 0 or line_limit < 8:
        raise ValueError("need chord_tol_m > 0 and line_limit >= 8")
    robot = data.load_robot()
    if robot.family != "opw":
        raise ValueError(f"data.robot={data.robot!r}: FANUC export needs an OPW robot")
    p_BT = data.X_BT[:3, 3]
    lever = float(np.max(np.linalg.norm(
        np.einsum("nji,nj->ni", data.X_BE[:, :3, :3], p_BT - data.X_BE[:, :3, 3]), axis=1
    )))  # fmt: skip
    angle = chord_tol_m / (2.0 * max(lever, 1e-3))
    angle = angle if angle_tol_rad is None else min(angle, angle_tol_rad)
    dense = densify(data, chord_tol_m / 2.0, angle)
    data = dense.data
    chord_sel, angle_sel = dense.selection_tolerances(chord_tol_m / 2.0, angle)
    sel = select_points(data.X_BE[:, :3, 3], data.X_BE[:, :3, :3],
                        chord_tol_m=chord_sel, angle_tol_rad=angle_sel)  # fmt: skip
    idx = sel.indices
    max_chord, max_angle = dense.bound(sel.max_chord_m, sel.max_angle_rad)
    deviation = max_chord + lever * max_angle
    configs = config_strings(robot, data.q[idx])
    speeds = segment_speeds_mms(data, idx)
    conventions = [
        "FLANGE-STYLE PROGRAM, DENSE POINT LIST: not FANUC Remote TCP (no FANUC document",
        "cited for it). UTOOL[1] = faceplate (0,0,0,0,0,0): URDF tool0.",
        f"UFRAME[1] = URDF base_link = (0,0,{-robot.params.c1 * 1e3:.3f},0,0,0) mm in FANUC world.",
        "Positions: flange in UFRAME[1], mm and W,P,R deg (fixed axes x, y, z).",
        "CONFIG: N/F = J5 <= 0 / > 0, U/D elbow, T/B wrist centre front/back of J1;",
        "turns of J1, J4, J6. Joint positions: FANUC axes, J3 from the horizontal",
        f"(J3 = q3 {'+' if robot.j23_factor > 0 else '-'} q2 of the URDF, "
        "ROS-I fanuc_driver J23_factor)."
        if robot.j23_coupled
        else "(J1..J6 = the URDF joints).",
        f"Points: {len(idx)} of {len(data.t)} samples; tool point within {deviation * 1e3:.4f} mm "
        f"of the plan ({dense.basis}); speeds = planned mean flange speed per segment.",
    ]
    load = payload(data.payload)
    if load is not None:
        mass, p_EC = load.total(data.X_EP)
        conventions.append(
            f"PAYLOAD[1]: {mass:.3f} kg at ({', '.join(f'{v * 100:.2f}' for v in p_EC)}) cm "
            "in the faceplate frame: set it in the payload schedule before running."
        )
    header = header_lines(data, conventions=conventions, forced=forced)
    remarks = [f"  ! {piece} ;" for line in header for piece in fanuc_comments(line)]
    start = [
        f"  UFRAME_NUM={UF} ;",
        f"  UTOOL_NUM={UT} ;",
        "  PAYLOAD[1] ;",
        f"J P[1] {JOINT_SPEED_PCT}% FINE ;",
    ]
    positions = {1: joint_pos(1, fanuc_axes_deg(robot, data.q[idx[:1]])[0], uf=UF, ut=UT)}
    moves = []
    for i in range(1, len(idx)):
        term = "FINE" if i == len(idx) - 1 else "CNT100"
        moves.append((i + 1, f"L P[{i + 1}] {speeds[i - 1]}mm/sec {term} ;"))
        positions[i + 1] = cartesian_pos(i + 1, data.X_BE[idx[i]], configs[i], uf=UF, ut=UT)
    texts = _split(name, remarks + start, moves, positions, line_limit)
    files = []
    for program, text in texts.items():
        files.append(Path(out_dir) / f"{program}.ls")
        write_atomic(files[-1], text)
    return FanucResult(tuple(files), idx, deviation)


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
    main_lines = head + [f"  CALL {sub} ;" for sub in subs]
    if len(main_lines) > line_limit:
        raise ValueError(
            f"line_limit={line_limit}: the main program alone needs {len(main_lines)} lines"
        )
    texts = {name: ls_text(name, main_lines, [positions[1]], comment)}
    for sub, chunk in zip(subs, chunks, strict=True):
        lines = [f"  UFRAME_NUM={UF} ;", f"  UTOOL_NUM={UT} ;"] + [s for _, s in chunk]
        texts[sub] = ls_text(sub, lines, [positions[k] for k, _ in chunk], comment)
    return texts
