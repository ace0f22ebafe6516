"""Universal Robots URScript: the planned joint trajectory streamed with servoj.

Plain URScript has no remote TCP, so the plan's joint trajectory is resampled to
the controller period (0.002 s on e-Series) with cubic Hermite interpolation of
q and q̇ and sent with one ``servoj`` per period. As an option, ``movel`` poses
of the part frame P (set as the TCP with ``set_tcp``) are written instead, in
the controller's base frame, which is the URDF ``base_link`` turned π about z.
URScript units: metres, radians, seconds; poses ``p[x, y, z, rx, ry, rz]`` with a
rotation vector.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.atomic import write_atomic
from offline_prog.export.densify import densify
from offline_prog.export.header import header_lines
from offline_prog.export.kuka.krl_points import process_points
from offline_prog.export.payload import payload
from offline_prog.export.program import ProgramData
from offline_prog.export.text import identifier, urscript_comment

E_SERIES_PERIOD_S = 0.002
SERVOJ_LOOKAHEAD_S = 0.1
SERVOJ_GAIN = 300
NAME_MAX = 63  # our bound for the program's function name
MOVEL_ACCEL_M_S2 = 1.0
MOVEL_MIN_SPEED_M_S = 1e-4
MOVEL_MAX_SPEED_M_S = 3.0  # beyond any UR arm's tool speed (e-Series safety limit: 5 m/s)
START_SPEED_RAD_S = 0.5  # movej to the start
START_ACCEL_RAD_S2 = 1.0
# The controller's base frame C in the URDF base_link B: turned π about z.
X_BC = np.diag([-1.0, -1.0, 1.0, 1.0])


@dataclasses.dataclass(frozen=True)
class UrScriptResult:
    file: Path
    n_commands: int
    period_s: float


def resample_joints(data: ProgramData, period_s: float) -> tuple[np.ndarray, np.ndarray]:
    """(t (M,), q (M, 6)) on the controller period, on the plan's straight joint steps
    (:func:`joints_on_steps`)."""
    t = np.arange(0.0, data.t[-1], period_s)
    t = np.append(t, data.t[-1]) if data.t[-1] - t[-1] > 1e-9 else t
    return t, joints_on_steps(data.t, data.q, t)


def joints_on_steps(t: np.ndarray, q: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """(M, 6) the joints at times ``grid`` (M,) [s], linear between the plan's samples
    t (N,), q (N, 6) [rad]: the straight joint step between two samples is what the
    collision check certified (collision.check), so a servoj target never leaves it."""
    return np.column_stack([np.interp(grid, t, q[:, j]) for j in range(q.shape[1])])


def _list(values: np.ndarray, digits: int = 7) -> str:
    return "[" + ", ".join(f"{v:.{digits}f}" for v in values) + "]"


def _pose(X: np.ndarray) -> str:
    rotvec = Rotation.from_matrix(X[:3, :3]).as_rotvec()
    return "p" + _list(np.concatenate([X[:3, 3], rotvec]))


def movel_points(data: ProgramData, chord_tol_m: float, angle_tol_rad: float):
    """The movel targets and speeds: (X_CP (K, 4, 4) part frame P in the controller
    base C, v (K-1,) [m/s] on each segment).

    movel moves the set_tcp point (P) in straight lines in C, so the points are chosen
    as for KRL's flange style (the nozzle's curve on the part within the tolerances,
    against the continuous plan), and v is what the controller interpolates: the
    length of the segment of P over its planned duration (keeps the planned timing).
    """
    dense = densify(data, chord_tol_m, angle_tol_rad)
    plan = dense.data
    idx, _, _ = process_points(
        plan, "flange", *dense.selection_tolerances(chord_tol_m, angle_tol_rad)
    )
    X_CP = np.linalg.inv(X_BC) @ plan.X_BE[idx] @ plan.X_EP
    v = np.linalg.norm(np.diff(X_CP[:, :3, 3], axis=0), axis=1) / np.diff(plan.t[idx])
    if not np.all(v <= MOVEL_MAX_SPEED_M_S):  # NaN too
        raise ValueError(
            f"URScript movel: v {np.nanmax(v):g} m/s is beyond {MOVEL_MAX_SPEED_M_S:g} m/s "
            "(the plan's speeds are m/s, not mm/s)"
        )
    return X_CP, np.maximum(v, MOVEL_MIN_SPEED_M_S)


def urscript_text(
    data: ProgramData,
    *,
    name: str = "offline_prog",
    mode: str = "servoj",
    period_s: float = E_SERIES_PERIOD_S,
    chord_tol_m: float = 0.05e-3,
    angle_tol_rad: float = np.deg2rad(0.1),
    forced: bool = False,
) -> tuple[str, int]:
    """The program text and its number of motion commands.

    Args:
        mode: "servoj" (the joint trajectory at the controller period) or "movel"
            (the part frame as TCP, LIN poses chosen within the tolerances).
    """
    conventions = [
        "Units: m, rad, s. Joint order: " + ", ".join(data.joint_names) + ".",
        f"Mode: {mode}. "
        + (
            f"servoj every {period_s} s (joint trajectory resampled from the plan)."
            if mode == "servoj"
            else "movel poses of the part frame (set_tcp) in the controller base frame "
            "(URDF base_link turned pi about z), rotation vectors. v = speed of the part origin "
            "(the set_tcp point) on each segment: its length / planned time."
        ),
    ]
    identifier(name, max_chars=NAME_MAX, what="name")
    header = header_lines(data, conventions=conventions, forced=forced)
    lines = [f"# {urscript_comment(line)}" for line in header]
    lines.append(f"def {name}():")
    if (load := payload(data.payload)) is not None:  # gripper + part, CoG in the flange
        mass, p_EC = load.total(data.X_EP)
        lines.append(f"  set_payload({mass:.3f}, {_list(p_EC, 4)})")
    q0 = data.q[0]
    lines.append(f"  movej({_list(q0)}, a={START_ACCEL_RAD_S2}, v={START_SPEED_RAD_S})")
    if mode == "servoj":
        _, q = resample_joints(data, period_s)
        lines += [
            f"  servoj({_list(row)}, t={period_s}, lookahead_time={SERVOJ_LOOKAHEAD_S}, "
            f"gain={SERVOJ_GAIN})"
            for row in q[1:]
        ]
        lines.append("  stopj(2.0)")
        count = len(q) - 1
    elif mode == "movel":
        lines.append(f"  set_tcp({_pose(data.X_EP)})")  # the part frame P in the flange
        X_CP, v = movel_points(data, chord_tol_m, angle_tol_rad)
        for X, speed in zip(X_CP[1:], v, strict=True):
            lines.append(
                f"  movel({_pose(X)}, a={MOVEL_ACCEL_M_S2}, v={speed:.5f}, "
                f"r={min(chord_tol_m, 0.001):.5f})"
            )
        count = len(X_CP) - 1
    else:
        raise ValueError(f"URScript mode must be 'servoj' or 'movel', got {mode!r}")
    lines.append("end")
    lines.append(f"{name}()")
    return "\n".join(lines) + "\n", count


def write_urscript(data: ProgramData, out_dir: Path, **options) -> UrScriptResult:
    """Write ``out_dir/<name>.script`` (see urscript_text for the options)."""
    name = options.get("name", "offline_prog")
    text, count = urscript_text(data, **options)
    file = Path(out_dir) / f"{name}.script"
    write_atomic(file, text)
    return UrScriptResult(file, count, options.get("period_s", E_SERIES_PERIOD_S))
