"""ABB RAPID: a whole job as one module ``<module>.mod`` (+ ``.pgf``), in the frames of
:mod:`offline_prog.export.abb.rapid` (stationary ``tooldata`` = the fixed tool T,
robot-held ``wobjdata`` = the part P, robtarget = the process frame X_PF).

``main``: ``MoveAbsJ`` home; per seam the link (``MoveAbsJ`` through its jointtargets,
fine points: the planned, collision-checked joint moves), the approach (``TriggL`` to
the seam's first point), the seam (``PROC seam_<k>``: ``MoveL`` / ``TriggL`` through the
one-seam writer's points and speeds), the retract (``MoveL``/``TriggL``); home at the end.

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

from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.export.abb.abb import abb_axes_deg, confdata
from offline_prog.export.abb.rapid import (
    DEG_DIGITS,
    EXTAX,
    GRIPPER_LOAD,
    NAME_MAX,
    PGF_HEAD,
    SPEED_REST,
    _list,
    _load,
    _module_text,
    _num,
    _pose,
    _robtarget,
    segment_speeds_mms,
)
from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M
from offline_prog.export.header import header_lines
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.job_steps import JointMove, LinearMove, Process, job_steps
from offline_prog.export.payload import payload
from offline_prog.export.text import identifier, identifier_from, rapid_comment
from offline_prog.io_events import Signal

LINK_SPEED = "v1000"  # predefined speeddata of the MoveAbsJ links (timing: the controller's)
# The triggdata of each kind of event; a second one of a kind on the same move gets a
# number (tOn2): a TriggL holds up to 8 triggers, each its own triggdata.
TRIGGERS = {
    (Signal.DIGITAL, True): "tOn",
    (Signal.DIGITAL, False): "tOff",
    (Signal.ANALOG, True): "tFlowOn",
    (Signal.ANALOG, False): "tFlowOff",
}


def write_rapid_job(
    data: JobProgramData,
    out_dir: Path,
    *,
    module: str = "OfflineProg",
    chord_tol_m: float = DEFAULT_CHORD_TOL_M,
    angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD,
    zone_mm: float = 0.3,
    forced: bool = False,
) -> list[Path]:
    """Write ``<module>.mod`` and ``<module>.pgf`` into out_dir; returns the files."""
    identifier(module, max_chars=NAME_MAX - 6, what="module")
    robot = data.load_robot()
    if robot.family != "opw":
        raise ValueError(f"data.robot={data.robot!r}: RAPID export needs an OPW (ABB) robot")
    job, io = data.job, data.process_io
    tool = identifier_from("tool", job.tool, max_chars=NAME_MAX)
    wobj = identifier_from("wobj", job.part, max_chars=NAME_MAX)
    tail = f", {tool}\\WObj:={wobj};"
    load = payload(job.payload)
    decls = [
        f"PERS tooldata {tool} := [FALSE,{_pose(job.X_BT)},"
        f"{GRIPPER_LOAD if load is None else _load(load.gripper_mass_kg, load.p_EG)}];",
        f'PERS wobjdata {wobj} := [TRUE,TRUE,"",{_pose(job.X_EP)},[[0,0,0],[1,0,0,0]]];',
    ]
    if load is not None:
        decls.append(f"PERS loaddata partLoad := {_load(load.part_mass_kg, load.p_PC)};")
    triggdata: set[str] = set()  # declared once the moves are written
    z = _list((zone_mm,) * 3 + (zone_mm / 10, zone_mm, zone_mm / 10), 5)[1:-1]
    decls.append(f"LOCAL CONST zonedata zPath := [FALSE,{z}];")
    main = ["ConfJ \\On;", "ConfL \\On;"] + ["GripLoad partLoad;"] * (load is not None)
    procs, speeds_declared, seam_no, link_no = {}, set(), 0, 0
    steps = job_steps(data, chord_tol_m, angle_tol_rad, convention="X_PF")

    def speed_name(v_mms: float) -> str:
        name = f"v{int(round(v_mms * 10)) // 10}_{int(round(v_mms * 10)) % 10}"
        if name not in speeds_declared:
            speeds_declared.add(name)
            decls.append(f"LOCAL CONST speeddata {name} := [{_num(v_mms, 1)},{SPEED_REST}];")
        return name

    def jointtarget(name: str, q: np.ndarray) -> None:
        axes = _list(abb_axes_deg(q[None], j23_coupled=robot.j23_coupled)[0], DEG_DIGITS)
        decls.append(f"LOCAL CONST jointtarget {name} := [{axes},{EXTAX}];")

    jointtarget("jHome", steps[0].targets[0])
    main.append(f"MoveAbsJ jHome\\NoEOffs, {LINK_SPEED}, fine{tail}")
    for step in steps:
        if isinstance(step, JointMove):
            link_no += 1
            for w, q in enumerate(step.targets[1:], start=1):
                jointtarget(f"jL{link_no}_{w}", q)
                main.append(f"MoveAbsJ jL{link_no}_{w}\\NoEOffs, {LINK_SPEED}, fine{tail}")
        elif isinstance(step, LinearMove):
            seam_no += step.kind == "approach"
            name = f"p{step.kind[0].upper()}{seam_no}"
            conf = confdata(robot, step.q[None])[0]
            decls.append(_robtarget(name, step.X_PT, conf))
            speed = speed_name(step.speed_m_s * 1e3)
            triggers = _triggers(step.switches, io, main, triggdata)
            main.append(_move(name, speed, triggers, "fine", tail))
        else:
            proc = f"seam_{seam_no}"
            procs[proc] = _seam_moves(
                step, robot, decls, speed_name, tail, zone_mm, proc, io, triggdata
            )
            main.append(f"{proc};  ! seam {step.seam}")
    decls += [f"VAR triggdata {name};" for name in sorted(triggdata)]
    header = _header(data, robot, forced)
    body = ["! " + rapid_comment(line) for line in header] + decls
    text = _module_text(module, body, {"main": main, **procs})
    files = [Path(out_dir) / f"{module}.mod", Path(out_dir) / f"{module}.pgf"]
    write_atomic(files[0], text)
    write_atomic(files[1], f"{PGF_HEAD}<Program>\n  <Module>{files[0].name}</Module>\n</Program>\n")
    return files


def _triggers(switches, io, lines: list[str], declared: set[str]) -> list[str]:
    """Define the triggers of one move's I/O events in ``lines`` (each its own
    triggdata, added to ``declared``); returns their names in path order."""
    names: list[str] = []
    for switch in switches:
        base = TRIGGERS[switch.signal, switch.state]
        count = sum(name.rstrip("0123456789") == base for name in names)
        names.append(_trigger(switch, io, lines, base + (str(count + 1) if count else "")))
    declared.update(names)
    return names


def _trigger(switch, io, lines: list[str], name: str) -> str:
    """Define the trigger ``name`` of one I/O event in ``lines``; returns its name."""
    distance = _num(switch.before_end_m * 1e3, 3)
    if switch.signal is Signal.DIGITAL:
        lines.append(f"TriggIO {name}, {distance}\\DOp:=do{switch.output}, {int(switch.state)};")
    else:
        k = _num(io.per_mps / 1000.0, 6) if switch.state else "0"
        lines.append(f"TriggSpeed {name}, {distance}, {_num(io.lag_s, 3)}, ao{switch.output}, {k};")
    return name


def _move(target: str, speed: str, triggers: list[str], zone: str, tail: str) -> str:
    if not triggers:
        return f"MoveL {target}, {speed}, {zone}{tail}"
    extra = "".join(f" \\T{k + 2}:={t}" for k, t in enumerate(triggers[1:]))
    return f"TriggL {target}, {speed}, {triggers[0]}{extra}, {zone}{tail}"


def _seam_moves(
    step: Process, robot, decls, speed_name, tail, zone_mm, proc, io, triggdata: set[str]
) -> list[str]:
    """The seam's moves; its first point is the approach's end (declared there)."""
    data, idx = step.data, step.indices
    conf = confdata(robot, data.q[idx])
    speeds = segment_speeds_mms(data, idx)
    lines = []
    for m in range(1, len(idx)):
        name = f"{proc}_{m}"
        decls.append(_robtarget(name, data.X_PF[idx[m]], conf[m]))
        zone = "fine" if m == len(idx) - 1 or zone_mm == 0 else "zPath"
        triggers = _triggers(step.switches_before(m), io, lines, triggdata)
        lines.append(_move(name, speed_name(speeds[m - 1]), triggers, zone, tail))
    return lines


def _header(data: JobProgramData, robot, forced: bool) -> list[str]:
    io = data.process_io
    lines = [
        f"Job: {len(data.seam_names)} seams in this order: {', '.join(data.seam_names)}.",
        "Units: mm, deg; quaternions [w,x,y,z]. World = robot base. Stationary tool: "
        "tframe = tool in world; robot-held wobj: uframe = part in tool0; robtarget = tool "
        "on the part.",
        "Axes: URDF joints"
        + (", axis 3 = q2 + q3 (J2/J3 linkage)" if robot.j23_coupled else "")
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
    return header_lines(data.job, conventions=lines, forced=forced)
