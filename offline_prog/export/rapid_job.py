"""ABB RAPID: a whole job as one module ``<module>.mod`` (+ ``.pgf``), in the frames of
:mod:`offline_prog.export.rapid` (stationary ``tooldata`` = the fixed tool T,
robot-held ``wobjdata`` = the part P, robtarget = the process frame X_PF).

``main``: ``MoveAbsJ`` home; per seam the link (``MoveAbsJ`` through its jointtargets,
fine points: the planned, collision-checked joint moves), the approach (``TriggL`` to
the seam's first point), the seam (``PROC seam_<k>``: ``MoveL`` / ``TriggL`` through the
one-seam writer's points and speeds), the retract (``MoveL``/``TriggL``); home at the end.

Process I/O on the path (RAPID Instructions, 3HAC050917: ``TriggIO``, ``TriggL``,
``TriggSpeed``): ``TriggIO t, d \\DOp:=do<n>, 1`` then ``TriggL p, v, t, z, tool`` sets
the output d mm before the move's end point (distance from the end, no ``\\Start``). The
output goes on d = lead mm before the approach's end (the seam's start) and off on the
seam's move that holds L − lead. The flow follows the TCP speed: ``TriggSpeed tFlow, 0
\\Start, 0.05, ao<n>, k`` on the approach with k = per_mps / 1000 (the logical value of
``ao<n>`` = k · v_TCP [mm/s], i.e. volts per mm/s); the cell's offset and limits belong
to the signal's scaling in the I/O configuration (the header says which); a
``TriggSpeed`` with k = 0 on the retract ends it. Signals are named ``do<n>`` / ``ao<n>``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.export.abb import abb_axes_deg, confdata
from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M
from offline_prog.export.header import header_lines
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.job_steps import JointMove, LinearMove, Process, job_steps
from offline_prog.export.payload import payload
from offline_prog.export.rapid import (
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
from offline_prog.export.text import identifier, identifier_from, rapid_comment

LINK_SPEED = "v1000"  # predefined speeddata of the MoveAbsJ links (timing: the controller's)
FLOW_LAG_S = 0.05  # TriggSpeed ScaleLag: the flow equipment's delay [s]


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
    flow = io is not None and io.analog_output is not None
    digital = io is not None and io.digital_output is not None
    decls += ["VAR triggdata tOn;", "VAR triggdata tOff;"] * digital
    decls += ["VAR triggdata tFlow;", "VAR triggdata tFlowEnd;"] * flow
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
            triggers = [_trigg_io(s, main) for s in step.switches]
            if flow and step.kind == "approach":
                main.append(f"TriggSpeed tFlow, 0\\Start, {FLOW_LAG_S}, ao{io.analog_output}, "
                            f"{_num(io.per_mps / 1000.0, 6)};")  # fmt: skip
                triggers.append("tFlow")
            if flow and step.kind == "retract":
                main.append(f"TriggSpeed tFlowEnd, 0, 0, ao{io.analog_output}, 0;")
                triggers.append("tFlowEnd")
            main.append(_move(name, speed, triggers, "fine", tail))
        else:
            proc = f"seam_{seam_no}"
            procs[proc] = _seam_moves(step, robot, decls, speed_name, tail, zone_mm, proc)
            main.append(f"{proc};  ! seam {step.seam}")
    header = _header(data, robot, forced)
    body = ["! " + rapid_comment(line) for line in header] + decls
    text = _module_text(module, body, {"main": main, **procs})
    files = [Path(out_dir) / f"{module}.mod", Path(out_dir) / f"{module}.pgf"]
    write_atomic(files[0], text)
    write_atomic(files[1], f"{PGF_HEAD}<Program>\n  <Module>{files[0].name}</Module>\n</Program>\n")
    return files


def _trigg_io(switch, lines: list[str]) -> str:
    name = "tOn" if switch.state else "tOff"
    lines.append(
        f"TriggIO {name}, {_num(switch.before_end_m * 1e3, 3)}\\DOp:=do{switch.output}, "
        f"{int(switch.state)};"
    )
    return name


def _move(target: str, speed: str, triggers: list[str], zone: str, tail: str) -> str:
    if not triggers:
        return f"MoveL {target}, {speed}, {zone}{tail}"
    extra = "".join(f" \\T{k + 2}:={t}" for k, t in enumerate(triggers[1:]))
    return f"TriggL {target}, {speed}, {triggers[0]}{extra}, {zone}{tail}"


def _seam_moves(step: Process, robot, decls, speed_name, tail, zone_mm, proc) -> list[str]:
    """The seam's moves; its first point is the approach's end (declared there)."""
    data, idx = step.data, step.indices
    conf = confdata(robot, data.q[idx])
    speeds = segment_speeds_mms(data, idx)
    by_move = {s.move: s for s in step.switches}
    lines = []
    for m in range(1, len(idx)):
        name = f"{proc}_{m}"
        decls.append(_robtarget(name, data.X_PF[idx[m]], conf[m]))
        zone = "fine" if m == len(idx) - 1 or zone_mm == 0 else "zPath"
        triggers = [_trigg_io(by_move[m], lines)] if m in by_move else []
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
        + ".",  # fmt: skip
        f"Links: MoveAbsJ to fine points ({LINK_SPEED}); approach, seams, retract: MoveL / "
        "TriggL at the planned speeds.",
    ]
    if io is not None and io.digital_output is not None:
        lines.append(
            f"Process output do{io.digital_output}: TriggIO on {io.on_lead_m * 1e3:g} mm "
            f"before each seam's start, off {io.off_lead_m * 1e3:g} mm before its end."
        )
    if io is not None and io.analog_output is not None:
        lines.append(
            f"Flow ao{io.analog_output}: TriggSpeed, logical value = "
            f"{io.per_mps / 1000:g} V per mm/s x TCP speed; set the signal's I/O "
            f"configuration to add {io.offset:g} V and limit it to [{io.min:g}, {io.max:g}] V."
        )
    return header_lines(data.job, conventions=lines, forced=forced)
