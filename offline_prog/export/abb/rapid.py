"""ABB RAPID: the robot carries the part past a stationary tool (remote TCP).

Controller model (RAPID Technical Reference Manual, 3HAC050917: ``tooldata``,
``wobjdata``, ``robtarget``, ``confdata``; MultiMove manual 3HAC021272 §6.3):

- ``tooldata`` with ``robhold := FALSE``: ``tframe`` is the fixed tool T in the world
  frame W; ``tload`` is then the load of the gripper that holds the part.
- ``wobjdata`` with ``robhold := TRUE``, ``ufprog := TRUE``, ``ufmec := ""``:
  ``uframe`` is given in the wrist frame tool0 (E), ``oframe`` in ``uframe``.
- a ``robtarget`` is the TCP in the object frame O, so the controller puts the flange
  at ``X_WE = tframe · robtarget⁻¹ · oframe⁻¹ · uframe⁻¹``.

Here W = B (world = robot base frame), tframe = X_BT, uframe = X_EP, oframe = I and
robtarget_i = X_PF(i), so the composition is the plan's X_BE = X_BT · X_PF⁻¹ · X_EP⁻¹.
E, the URDF ``tool0``, is ABB's tool0 (z out of the flange, x down at the calibration
position). Axis values are the URDF q, except axis 3 = q2 + q3 on robots with a J2/J3
parallel linkage (ROS-I ``abb_driver`` ``linkage_transform``, ``J23_coupled``).
Units at this edge: mm, degrees, quaternions ``[q1, q2, q3, q4] = [w, x, y, z]``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from pydrake.math import RotationMatrix

from offline_prog.atomic import write_atomic
from offline_prog.export.abb.abb import abb_axes_deg, confdata
from offline_prog.export.densify import densify
from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M, select_points
from offline_prog.export.header import header_lines
from offline_prog.export.payload import payload
from offline_prog.export.program import ProgramData
from offline_prog.export.text import identifier, identifier_from, rapid_comment
from offline_prog.robot.model import RobotModel

# Approach / retract along -y of F (y = pressing direction n): none by default, so the
# program moves only as planned (MoveAbsJ to the plan's first joints); a whole job's
# program (rapid_job) has the planned approach and retract.
DEFAULT_APPROACH_M = 0.0
START_SPEED = "v100"  # predefined speeddata (BASE module) for MoveAbsJ
APPROACH_SPEED = "v20"  # predefined speeddata for the linear approach and retract
SPEED_REST = "500,5000,1000"  # v_ori [deg/s], v_leax [mm/s], v_reax [deg/s], as v5..v1000
MIN_SPEED_MMS = 0.1  # smallest v_tcp written
MAX_SPEED_MMS = 7000.0  # largest v_tcp of RAPID's predefined speeddata (v7000)
# PLACEHOLDER gripper load (tload of a stationary tool) when the cell gives no payload:
# 5 kg, 100 mm along tool0's z (the header warns: PAYLOAD NOT SET).
GRIPPER_LOAD = "[5,[0,0,100],[1,0,0,0],0,0,0]"
EXTAX = "[9E9,9E9,9E9,9E9,9E9,9E9]"  # external axes: none
PGF_HEAD = '<?xml version="1.0" encoding="ISO-8859-1" ?>\n'  # program file (.pgf)
MM_DIGITS, QUAT_DIGITS, DEG_DIGITS = 3, 7, 4  # 0.5 µm, ~1e-5 deg, 5e-5 deg
NAME_MAX = 32  # RAPID identifiers: letter first, letters / digits / _, ≤ 32 characters
_PART_OVERHEAD = 6  # MODULE, comment, zone, PROC, ENDPROC, ENDMODULE


@dataclasses.dataclass(frozen=True)
class RapidResult:
    """Files written (modules in load order, then the .pgf program file), the dense
    plan sample behind each process robtarget, and the achieved LIN deviations."""

    files: tuple[Path, ...]
    n_points: int
    indices: np.ndarray
    max_chord_m: float
    max_angle_rad: float


def segment_speeds_mms(data: ProgramData, indices: np.ndarray) -> np.ndarray:
    """(n-1,) planned TCP speed on each LIN segment [mm/s]: the time mean of
    ``data.tcp_speed`` between its end samples (= planned length / duration), so the
    program keeps the planned timing; rounded to 0.1 mm/s, at least 0.1 mm/s."""
    v, t = data.tcp_speed, data.t
    mean = [
        np.trapezoid(v[a : b + 1], t[a : b + 1]) / (t[b] - t[a]) if t[b] > t[a] else v[b]
        for a, b in zip(indices[:-1], indices[1:], strict=True)
    ]
    speeds = np.maximum(np.round(np.asarray(mean) * 1e4) / 10.0, MIN_SPEED_MMS)
    if not np.all(speeds <= MAX_SPEED_MMS):  # NaN too
        raise ValueError(
            f"write_rapid: v_tcp {np.nanmax(speeds):g} mm/s is beyond {MAX_SPEED_MMS:g} mm/s "
            "(the plan's speeds are m/s, not mm/s)"
        )
    return speeds


def approach_and_retract(robot: RobotModel, data: ProgramData, distance_m: float):
    """[(X_PT, q) at the approach, (X_PT, q) at the retract], or None if out of reach:
    the first / last process frame moved distance_m along -y of F (y of F = n, the
    pressing direction) so that the tool is off the surface, with the IK solution (6,)
    [rad] within the plan's limits nearest the plan's first / last joints."""
    poses, X_EP_inv = [], np.linalg.inv(data.X_EP)
    for k in (0, -1):
        X_PT = data.X_PF[k].copy()
        X_PT[:3, 3] -= distance_m * X_PT[:3, 1]
        q = robot.inverse((data.X_BT @ np.linalg.inv(X_PT) @ X_EP_inv)[None])[0]
        q += 2.0 * np.pi * np.round((data.q[k] - q) / (2.0 * np.pi))  # the nearest turn
        ok = np.all(np.isfinite(q) & (q >= data.q_lower) & (q <= data.q_upper), axis=1)
        if not ok.any():
            return None
        poses.append((X_PT, q[ok][np.argmin(np.abs(q[ok] - data.q[k]).max(axis=1))]))
    return poses


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


def _load(mass_kg: float, p_m: np.ndarray) -> str:
    """loaddata ``[mass, cog [mm], [1,0,0,0], 0, 0, 0]`` of a point mass (no inertia);
    RAPID needs mass > 0, so 0 kg is written as 0.001 kg."""
    return f"[{_num(max(mass_kg, 1e-3), 3)},{_list(p_m * 1e3, 1)},[1,0,0,0],0,0,0]"


def _robtarget(name: str, X: np.ndarray, conf: np.ndarray) -> str:
    cf = ",".join(str(int(c)) for c in conf)
    return f"LOCAL CONST robtarget {name} := [{_pose(X)[1:-1]},[{cf}],{EXTAX}];"


def _module_text(name: str, body: list[str], procs: dict[str, list[str]]) -> str:
    lines = [f"MODULE {name}"] + ["  " + line for line in body]
    for proc, statements in procs.items():
        lines += [f"  PROC {proc}()"] + ["    " + s for s in statements] + ["  ENDPROC"]
    return "\n".join(lines + ["ENDMODULE"]) + "\n"


def _parts(speeds: np.ndarray, line_limit: int) -> list[range]:
    """Process points 1..n-1 in order, cut so that each part module fits line_limit."""
    parts, begin, used = [], 1, set()
    for i in range(1, len(speeds) + 1):
        used = used | {speeds[i - 1]}
        if i > begin and _PART_OVERHEAD + len(used) + 2 * (i - begin + 1) > line_limit:
            parts.append(range(begin, i))
            begin, used = i, {speeds[i - 1]}
    return parts + [range(begin, len(speeds) + 1)]


def write_rapid(
    data: ProgramData,
    out_dir: Path,
    *,
    module: str = "OfflineProg",
    chord_tol_m: float = DEFAULT_CHORD_TOL_M,
    angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD,
    line_limit: int = 5000,
    zone_mm: float = 0.3,
    approach_m: float = DEFAULT_APPROACH_M,
    j23_coupled: bool | None = None,
    forced: bool = False,
) -> RapidResult:
    r"""Write ``<module>.mod`` (and ``<module>_<k>.mod`` parts, called in order from
    main, when one module would exceed line_limit) and ``<module>.pgf`` that loads them.

    Program: ConfJ/ConfL on; MoveAbsJ to the approach pose (first process frame backed
    off by approach_m; IK nearest the plan's start); MoveL to the first process point
    (fine); one MoveL per point chosen by ``select_points`` on X_PF, at the segment's
    planned TCP speed (speeddata ``v<mm/s>_<tenth>``), zone ``zPath`` (z0 proportions,
    zone_mm), fine at the end; MoveL to the retract pose. All with ``tool\WObj:=wobj``.

    Args:
        data: the plan, of an OPW robot in robots/.
        out_dir: folder for the files.
        module: RAPID module name (letter first, then letters, digits, _).
        chord_tol_m, angle_tol_rad: LIN deviation allowed from the dense X_PF [m, rad].
        line_limit: most lines in one module file.
        zone_mm: corner zone of the process moves [mm] (0: fine everywhere).
        approach_m: approach / retract distance off the surface [m] (0 or out of reach: none).
        j23_coupled: the controller's axis 3 is q2 + q3 (None: from the robot's record).
        forced: the plan failed and is exported anyway (the header says so).

    Raises:
        ValueError: naming the bad argument.
    """
    identifier(module, max_chars=NAME_MAX - 6, what="module")
    if not (chord_tol_m > 0 and angle_tol_rad > 0 and zone_mm >= 0 and approach_m >= 0):
        raise ValueError("need chord_tol_m > 0, angle_tol_rad > 0, zone_mm >= 0, approach_m >= 0")
    robot = data.load_robot()
    # Controller axis 3 = q2 + q3 where robot.yaml says so (the IRB 2400's J2/J3 linkage).
    j23 = robot.j23_coupled if j23_coupled is None else j23_coupled
    if robot.family != "opw":
        raise ValueError(f"data.robot={data.robot!r}: RAPID export needs an OPW (ABB) robot")
    dense = densify(data, chord_tol_m, angle_tol_rad)
    data = dense.data
    chord_sel, angle_sel = dense.selection_tolerances(chord_tol_m, angle_tol_rad)
    p_PF, R_PF = data.X_PF[:, :3, 3], data.X_PF[:, :3, :3]
    sel = select_points(p_PF, R_PF, chord_tol_m=chord_sel, angle_tol_rad=angle_sel)
    idx, n = sel.indices, len(sel.indices)
    max_chord, max_angle = dense.bound(sel.max_chord_m, sel.max_angle_rad)
    conf, speeds = confdata(robot, data.q[idx]), segment_speeds_mms(data, idx)
    tool = identifier_from("tool", data.tool, max_chars=NAME_MAX)
    wobj = identifier_from("wobj", data.part, max_chars=NAME_MAX)
    tail = f", {tool}\\WObj:={wobj};"
    names = [f"p{i:0{max(4, len(str(n - 1)))}d}" for i in range(n)]
    z = _list((zone_mm,) * 3 + (zone_mm / 10, zone_mm, zone_mm / 10), 5)[1:-1]
    zone_decl = [f"LOCAL CONST zonedata zPath := [FALSE,{z}];"] * (zone_mm > 0)
    vname = {v: f"v{int(round(v * 10)) // 10}_{int(round(v * 10)) % 10}" for v in speeds}

    def part(points: range) -> tuple[list[str], list[str]]:
        """Declarations and moves of process points, each reached from the one before."""
        used = sorted({speeds[i - 1] for i in points})
        decls = [f"LOCAL CONST speeddata {vname[v]} := [{_num(v, 1)},{SPEED_REST}];" for v in used]
        decls += zone_decl + [_robtarget(names[i], data.X_PF[idx[i]], conf[i]) for i in points]
        zone = ["zPath", "fine"]
        return decls, [
            f"MoveL {names[i]}, {vname[speeds[i - 1]]}, {zone[i == n - 1 or zone_mm == 0]}{tail}"
            for i in points
        ]

    # Loads (RAPID TRM loaddata: a stationary tool's tload is the gripper, cog in tool0;
    # GripLoad's cog is in the object frame of the robot-held wobj, here P).
    load = payload(data.payload)
    gripper_load, grip = GRIPPER_LOAD, []
    if load is not None:
        gripper_load = _load(load.gripper_mass_kg, load.p_EG)
        grip = [f"PERS loaddata partLoad := {_load(load.part_mass_kg, load.p_PC)};"]
    # Start (MoveAbsJ, then the linear approach) and retract.
    head = [
        f"PERS tooldata {tool} := [FALSE,{_pose(data.X_BT)},{gripper_load}];",
        f'PERS wobjdata {wobj} := [TRUE,TRUE,"",{_pose(data.X_EP)},[[0,0,0],[1,0,0,0]]];',
        _robtarget(names[0], data.X_PF[idx[0]], conf[0]),
    ]
    off = approach_and_retract(robot, data, approach_m) if approach_m > 0 else None
    (_, q_start), (X_PT_ret, q_ret) = off or [(None, data.q[0]), (None, None)]
    first = ["ConfJ \\On;", "ConfL \\On;"] + ["GripLoad partLoad;"] * bool(grip)
    last = []  # the part stays gripped after the program: its load stays set
    head += grip
    if off:  # else: out of reach or not wanted, so start at the first process point
        head.append(_robtarget("pRetract", X_PT_ret, confdata(robot, q_ret[None])[0]))
        last.append(f"MoveL pRetract, {APPROACH_SPEED}, fine{tail}")
    start = "jApproach" if off else "jStart"
    axes = _list(abb_axes_deg(q_start[None], j23_coupled=j23)[0], DEG_DIGITS)
    head.append(f"LOCAL CONST jointtarget {start} := [{axes},{EXTAX}];")
    first.append(f"MoveAbsJ {start}\\NoEOffs, {START_SPEED}, fine{tail}")
    first += [f"MoveL {names[0]}, {APPROACH_SPEED}, fine{tail}"] * bool(off)
    approach = f"{approach_m * 1e3:g} mm along -y of F" if off else "none"

    conventions = [
        "Units: mm, deg; quaternions [q1,q2,q3,q4] = [w,x,y,z], q1 >= 0. World = robot base.",
        "Stationary tool: tframe = tool in world; robot-held wobj: uframe = part in tool0,",
        "  oframe = I; robtarget = tool on the part; flange = tframe * rt^-1 * uframe^-1.",
        "Axes: URDF joints" + (", axis 3 = q2 + q3 (J2/J3 linkage)" if j23 else "") + "; conf: "
        "cf1/4/6 = floor(axis/90 deg), cfx = RAPID confdata table.",
        f"Points: {n} of {len(data.t)} samples, LIN deviation <= {max_chord * 1e3:.4f} mm, "
        f"{np.rad2deg(max_angle):.4f} deg ({dense.basis}); v_tcp = planned mean on each segment.",
        f"Approach/retract: {approach}"
        + (" (OUT OF REACH)" if approach_m and not off else "")
        + ", not collision-checked. "
        + (
            "tload = gripper, GripLoad partLoad = part (see Payload above)."
            if load
            else "tload: PLACEHOLDER 5 kg gripper, no GripLoad (PAYLOAD NOT SET)."
        ),
    ]
    header = header_lines(data, conventions=conventions, forced=forced)
    head = ["! " + rapid_comment(line) for line in header] + head

    decls, moves = part(range(1, n))
    texts = {module: _module_text(module, head + decls, {"main": first + moves + last})}
    if texts[module].count("\n") > line_limit:
        parts = _parts(speeds, line_limit)
        procs = [f"{module}_seg{k}" for k in range(1, len(parts) + 1)]
        if line_limit < _PART_OVERHEAD + 3 or len(procs[-1]) > NAME_MAX:
            raise ValueError(f"line_limit={line_limit}: too small to split module {module!r}")
        calls = [proc + ";" for proc in procs]
        texts = {module: _module_text(module, head, {"main": first + calls + last})}
        for k, (points, proc) in enumerate(zip(parts, procs, strict=True), start=1):
            decls, moves = part(points)
            note = f"! Part {k} of {module}: process points {points[0]}..{points[-1]}."
            texts[f"{module}_{k}"] = _module_text(f"{module}_{k}", [note] + decls, {proc: moves})
        if (size := texts[module].count("\n")) > line_limit:
            raise ValueError(f"line_limit={line_limit}: the main module alone needs {size} lines")
    assert all(text.count("\n") <= line_limit for text in texts.values())

    files = [Path(out_dir) / f"{name}.mod" for name in texts]
    for file, text in zip(files, texts.values(), strict=True):
        write_atomic(file, text)
    listing = "".join(f"  <Module>{file.name}</Module>\n" for file in files)
    files.append(Path(out_dir) / f"{module}.pgf")
    write_atomic(files[-1], f"{PGF_HEAD}<Program>\n{listing}</Program>\n")
    return RapidResult(tuple(files), n, idx, max_chord, max_angle)
