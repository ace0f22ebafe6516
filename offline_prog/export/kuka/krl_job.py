"""KUKA KRL for KSS 8: a whole job as ``name.src`` / ``.dat`` plus one ``name_<k>``
module per seam, in the external-TCP style of :mod:`offline_prog.export.kuka.krl` (``$BASE``
= the fixed tool T, ``$TOOL`` = the part P, ``$IPO_MODE=#TCP``, LIN points X_TP).

Main program: home (``PTP`` to an ``E6AXIS``), then per seam: the link (``PTP`` through
its ``E6AXIS`` waypoints, fine points), the approach (``LIN`` to the seam's first
point), the seam's module (its LIN points, ``C_DIS``, speeds and point choice exactly as
a one-seam program), the retract (``LIN``), and the last link home.

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
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M
from offline_prog.export.header import header_lines
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.job_steps import JointMove, LinearMove, Process, job_steps
from offline_prog.export.kuka.krl import _load, _process_lines, _write
from offline_prog.export.kuka.krl_header import krl_comments
from offline_prog.export.kuka.kuka import X_KE, krl_frame, krl_num, status_turn, vel_cp
from offline_prog.io_events import Signal

ANALOG_FULL_SCALE_V = 10.0  # $ANOUT = ±1 is ±10 V
PTP_VEL_PERCENT, PTP_ACC_PERCENT = 100, 100  # links: the planned joint moves at full rate
_ZEROS = ",E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0"


def _axes(q: np.ndarray) -> str:
    return ",".join(f"A{i + 1} {krl_num(v, 5)}" for i, v in enumerate(np.rad2deg(q)))


def write_krl_job(
    data: JobProgramData,
    out_dir: Path,
    *,
    name: str = "offline_prog",
    chord_tol_m: float = DEFAULT_CHORD_TOL_M,
    angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD,
    blend_m: float = 0.001,
    tcp_pose_convention: str = "X_TP",
    forced: bool = False,
) -> list[Path]:
    """Write the job's KRL modules into out_dir; returns the files (main first).

    ``tcp_pose_convention``: the E6POS of the external-TCP points, "X_TP" (P in T, the
    default) or "X_PF" (T in P, the inverse; ``export --tcp-pose-convention``).
    """
    if tcp_pose_convention not in ("X_TP", "X_PF"):
        raise ValueError(
            f"write_krl: tcp_pose_convention {tcp_pose_convention!r}: use X_TP or X_PF"
        )
    robot = data.load_robot()
    if robot.family != "opw":
        raise ValueError(f"write_krl: robot {data.robot} is not an OPW arm (family {robot.family})")
    if len(name) > 20 or not name.replace("_", "a").isalnum() or not name[0].isalpha():
        raise ValueError(f"write_krl: name {name!r} is not a KRL name of <= 20 characters")
    job, io = data.job, data.process_io
    steps = job_steps(
        data, chord_tol_m, angle_tol_rad, convention=tcp_pose_convention, flow_where_set=True
    )
    src, modules = [], []
    decl = []  # main .dat declarations
    q_home = steps[0].targets[0]
    decl.append(f"DECL E6AXIS XHOME={{{_axes(q_home)}{_ZEROS}}}")
    flow = io is not None and io.analog_output is not None
    factor = f"{name.upper()}_FK"  # the flow's factor: live while $OUT is on, else 0
    if flow:
        decl.append(f"DECL GLOBAL REAL {factor}=0.0")
        src += _anout_on(io, factor)
    src += ["; Home", "PTP XHOME"]
    n_link, seam_no = 0, 0
    for step in steps:
        if isinstance(step, JointMove):
            n_link += 1
            src.append(f"; Link {n_link}: PTP through {len(step.targets) - 1} joint target(s)")
            for w, q in enumerate(step.targets[1:], start=1):
                decl.append(f"DECL E6AXIS XL{n_link}_{w}={{{_axes(q)}{_ZEROS}}}")
                src.append(f"PTP XL{n_link}_{w}")
        elif isinstance(step, LinearMove):
            seam_no += step.kind == "approach"
            label = f"X{step.kind[0].upper()}{seam_no}"  # XA<k> approach end, XR<k> retract end
            what = "Approach" if step.kind == "approach" else "Retract"
            src.append(f"; {what} of seam {step.seam}: LIN {step.length_m * 1e3:.1f} mm")
            src.append(f"$VEL.CP={vel_cp(step.speed_m_s):.4f}")
            src += [_trigger(s, io, factor) for s in step.switches]
            status, turn = status_turn(robot.params, step.q[None])
            pose = krl_frame(_point(step.X_PT, tcp_pose_convention))
            decl.append(f"DECL E6POS {label}={{{pose},S {status[0]},T {turn[0]}{_ZEROS}}}")
            src.append(f"LIN {label}")
        else:
            module = f"{name}_{seam_no}"
            src.append(f"; Seam {step.seam}: {len(step.indices) - 1} LIN points in {module}")
            src.append(f"{module}( )")
            modules.append((module, step))
    # The approach ends at the seam's first point: its E6POS is the seam's XP1.
    head = _header(data, steps, tcp_pose_convention, forced)
    ori = _ori_speed(job)
    main_src = [
        f"DEF {name}( )",
        *(f"EXT {m}( )" for m, _ in modules),
        ";FOLD INI",
        "BAS(#INITMOV,0)",
        ";ENDFOLD (INI)",
        *([line for line in _load(job).splitlines() if line]),
        "$BASE=FIXED_TOOL",
        "$TOOL=PART_ON_FLANGE",
        "$IPO_MODE=#TCP",
        "$ORI_TYPE=#VAR",
        "$ADVANCE=3",
        f"BAS(#VEL_PTP,{PTP_VEL_PERCENT})",
        f"BAS(#ACC_PTP,{PTP_ACC_PERCENT})",
        f"$VEL.ORI1={ori:.0f}",
        f"$VEL.ORI2={ori:.0f}",
        f"$APO.CDIS={blend_m * 1e3:.3f}",
        *src,
        *([f"ANOUT OFF $ANOUT[{io.analog_output}]"] if flow else []),
        "END",
    ]
    main_dat = [
        f"DEFDAT {name}" + (" PUBLIC" if flow else ""),
        "EXT BAS (BAS_COMMAND :IN,REAL :IN )",
        f"DECL FRAME PART_ON_FLANGE={{{krl_frame(X_KE @ job.X_EP)}}}",
        f"DECL FRAME FIXED_TOOL={{{krl_frame(job.X_BT)}}}",
        *decl,
        "ENDDAT",
    ]
    files = _write(Path(out_dir), name, head + main_src, head + main_dat)
    for module, step in modules:
        files += _seam_module(
            Path(out_dir), module, step, robot, head, io, factor, tcp_pose_convention
        )
    return files


def _point(X_PT: np.ndarray, convention: str) -> np.ndarray:
    """(4, 4) the E6POS of the tool frame T in P at a point: P in T (X_TP) or T in P."""
    return X_PT if convention == "X_PF" else np.linalg.inv(X_PT)


def _anout_on(io, factor: str) -> list[str]:
    """The flow's cyclic output, idle (factor 0) until a TRIGGER makes it live."""
    o = io.offset / ANALOG_FULL_SCALE_V
    lo, hi = io.min / ANALOG_FULL_SCALE_V, io.max / ANALOG_FULL_SCALE_V
    delay = f" DELAY={krl_num(-io.lag_s, 3)}" if io.lag_s > 0 else ""
    return [
        f"; Flow: $ANOUT[{io.analog_output}] follows $VEL_ACT while $OUT is on, idle otherwise",
        f"{factor}=0.0",
        f"ANOUT ON $ANOUT[{io.analog_output}]={factor}*$VEL_ACT+{krl_num(o, 6)}{delay} "
        f"MINIMUM={krl_num(lo, 4)} MAXIMUM={krl_num(hi, 4)}",
    ]


def _trigger(switch, io, factor: str) -> str:
    """The TRIGGER of one I/O event: $OUT for the process output, the flow's factor
    for the flow (placed where the plan sets it, ``lag_s`` ahead)."""
    path = krl_num(-switch.before_end_m * 1e3, 3)
    if switch.signal is Signal.DIGITAL:
        state = "TRUE" if switch.state else "FALSE"
        return f"TRIGGER WHEN PATH={path} DELAY=0 DO $OUT[{switch.output}]={state} PRIO=-1"
    f = io.per_mps / ANALOG_FULL_SCALE_V if switch.state else 0.0
    return f"TRIGGER WHEN PATH={path} DELAY=0 DO {factor}={krl_num(f, 6)} PRIO=-1"


def _seam_module(
    folder: Path, module: str, step: Process, robot, head, io, factor: str, convention: str
) -> list[Path]:
    """``module.src`` / ``.dat``: the seam's LIN points (the first is where the approach
    ended), with the switches before the LIN whose motion holds them."""
    data, idx = step.data, step.indices
    names = [f"XP{k + 1}" for k in range(len(idx))]
    status, turn = status_turn(robot.params, data.q[idx])
    poses = _point(data.X_PF[idx], convention)
    decls = [
        f"DECL E6POS {n}={{{krl_frame(X)},S {s},T {t}{_ZEROS}}}"
        for n, X, s, t in zip(names, poses, status, turn, strict=True)
    ]
    lines = _process_lines(names, idx, data.tcp_speed, line_limit=10**9)[0]
    body = []
    for line in lines:
        if line.startswith("LIN "):
            m = names.index(line.split()[1])
            body += [_trigger(s, io, factor) for s in step.switches_before(m)]
        body.append(line)
    src = [f"DEF {module}( )", *body, "END"]
    note = [
        f"; Seam {step.seam}: deviation <= {step.max_chord_m * 1e3:.4f} mm, "
        f"{np.rad2deg(step.max_angle_rad):.4f} deg from the plan"
    ]
    dat = [f"DEFDAT {module}", "EXT BAS (BAS_COMMAND :IN,REAL :IN )", *decls[1:], "ENDDAT"]
    # XP1 is the approach's end (main .dat XA<k>): the first LIN here goes to XP2.
    return _write(folder, module, head + note + src, head + note + dat)


def _ori_speed(job) -> float:
    from scipy.spatial.transform import Rotation

    from offline_prog.export.kuka.krl import ORI_SPEED_MARGIN, ORI_SPEED_MIN_DEG_S

    R = job.X_BE[:, :3, :3]
    dt = np.diff(job.t)
    omega = Rotation.from_matrix(np.swapaxes(R[:-1], 1, 2) @ R[1:]).magnitude() / dt
    return max(np.ceil(ORI_SPEED_MARGIN * np.rad2deg(omega.max())), ORI_SPEED_MIN_DEG_S)


def _header(data: JobProgramData, steps, convention: str, forced: bool) -> list[str]:
    io = data.process_io
    order = ", ".join(data.seam_names)
    lines = [
        f"Job: {len(data.seam_names)} seams in this order: {order}.",
        "Style external_tcp: $BASE = fixed tool T in $WORLD (= base_link), $TOOL = part P "
        "in $FLANGE, $IPO_MODE = #TCP; E6POS = "
        + ("T in P (X_PF)" if convention == "X_PF" else "P in T (X_TP)")
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
    if io is not None and io.analog_output is not None:
        lines.append(
            f"Flow $ANOUT[{io.analog_output}] = ({io.per_mps:g} V per m/s * $VEL_ACT + "
            f"{io.offset:g} V) / 10 V within [{io.min:g}, {io.max:g}] V while the process "
            f"output is on, {io.idle:g} V otherwise; leads by the dispenser's lag "
            f"{io.lag_s:g} s."
        )
    return krl_comments(header_lines(data.job, conventions=lines, forced=forced))
