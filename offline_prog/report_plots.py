"""The plots of report.html (matplotlib Figures on the Agg canvas; no pyplot state).

Visualization only: numerical code never imports this module. Each figure reads
the plan folder's data (trajectory.csv by column, plan.npz, report.json,
clearance.csv) and comes back as a base64 PNG. Frames: I inertial, B robot base,
E flange, P part, F process frame, T fixed tool; mm and degrees on the axes.
"""

from __future__ import annotations

import base64
import io
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Line3DCollection
from scipy.spatial.transform import Rotation

from offline_prog.export.program import ProgramData

XYZ_COLORS = ("#0072bd", "#d95318", "#edb120")  # x|α, y|β, z|γ, as in the paper's fig. 5
TRIAD_COLORS = ("#d62728", "#2ca02c", "#1f77b4")  # a frame's x, y, z axes
N_TRIADS = 24  # process frames drawn along the path
DPI = 90
_RC = {"font.size": 9, "axes.grid": True, "grid.alpha": 0.3, "lines.linewidth": 1.2}


def _png(fig) -> str:
    """Base64 PNG of a figure (no metadata, so equal plans give equal bytes)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=DPI, metadata={"Software": None})
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def _xyz(ax, t, series, labels, ylabel):
    for values, label, color in zip(series, labels, XYZ_COLORS, strict=True):
        ax.plot(t, values, color=color, label=label)
    ax.set_ylabel(ylabel)
    ax.legend(loc="lower right", bbox_to_anchor=(1, 1), ncol=3, fontsize=8, frameon=False)


def _pose_figure(col) -> Figure:
    """Paper fig. 5: flange pose, velocity and acceleration over time, in I."""
    fig = Figure(figsize=(13, 8), layout="constrained")
    ax = fig.subplots(3, 2, sharex=True)
    t, c = col["t"], lambda *names: [col[n] for n in names]
    _xyz(ax[0, 0], t, [v * 1e3 for v in c("x", "y", "z")], "xyz", "flange position p_IE [mm]")
    _xyz(ax[0, 1], t, [np.rad2deg(v) for v in c("alpha", "beta", "gamma")], "αβγ", "angles [°]")
    _xyz(ax[1, 0], t, c("vx", "vy", "vz"), "xyz", "velocity v_IE [m/s]")
    _xyz(ax[1, 1], t, c("wx", "wy", "wz"), "xyz", "angular velocity w_IE [rad/s]")
    _xyz(ax[2, 0], t, c("ax", "ay", "az"), "xyz", "acceleration a_IE [m/s²]")
    _xyz(ax[2, 1], t, c("dwx", "dwy", "dwz"), "xyz", "angular acc. [rad/s²]")
    for a in ax[2]:
        a.set_xlabel("time t [s]")
    return fig


def commanded_speed(report: dict, s: np.ndarray) -> np.ndarray:
    """(N,) speed cap of the time law at its parameter s [m]: top speed, lowered on
    report.json's speed-reduction stretches [m/s]."""
    cap = np.full(len(s), report["motion"]["top_speed_m_s"])
    for r in report["robot_motion"]["speed_reductions"]:
        inside = (s >= r["sigma_start_m"]) & (s <= r["sigma_end_m"])
        cap[inside] = np.minimum(cap[inside], r["speed_m_s"])
    return cap


def _speed_figure(report: dict, col) -> Figure:
    fig = Figure(figsize=(13, 3.4), layout="constrained")
    ax, t = fig.subplots(), col["t"]
    flange = np.linalg.norm(np.column_stack([col["vx"], col["vy"], col["vz"]]), axis=1)
    if report["motion"]["speed_reference"] == "tcp":
        s, measured, other = col["sigma"], ("TCP speed", col["tcp_speed"]), ("flange", flange)
    else:  # the law runs on the flange path's arc length
        p = np.column_stack([col["x"], col["y"], col["z"]])
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        measured, other = ("flange speed", flange), ("TCP", col["tcp_speed"])
    cap = commanded_speed(report, s)
    ax.plot(t, other[1] * 1e3, color="#bbbbbb", label=f"{other[0]} speed (not commanded)")
    ax.plot(t, cap * 1e3, color="black", ls="--", label="commanded (limit, reductions)")
    ax.plot(t, measured[1] * 1e3, color=XYZ_COLORS[0], label=measured[0])
    ax.fill_between(
        t, 0, cap * 1e3, where=cap < cap.max(), color="#ffcc80", alpha=0.5, label="speed reduced"
    )
    ax.set_ylim(0, 1.15e3 * max(cap.max(), measured[1].max()))
    ax.set(xlabel="time t [s]", ylabel="speed [mm/s]")
    ax.legend(loc="lower center", ncol=4, fontsize=8)
    return fig


def _joint_figure(col, data: ProgramData, rates: bool) -> Figure:
    fig = Figure(figsize=(13, 5.2), layout="constrained")
    t, names = col["t"], data.joint_names
    for j, ax in enumerate(fig.subplots(2, 3, sharex=True).ravel()):
        if rates:
            values, lower, upper = (
                data.controller_column(col, "qd", j),
                -data.qd_max[j],
                data.qd_max[j],
            )
        else:
            values, lower, upper = (
                data.controller_column(col, "q", j),
                data.q_lower[j],
                data.q_upper[j],
            )
        ax.plot(t, np.rad2deg(values), color=XYZ_COLORS[0])
        for limit in (lower, upper):
            ax.axhline(np.rad2deg(limit), color="#c62828", ls="--", lw=1)
        coupled = " (controller: q2 + q3)" if data.j23_coupled and j == 2 else ""
        ax.set_title(f"J{j + 1} {names[j]}{coupled}", fontsize=9)
        ax.set_ylabel("q̇ [°/s]" if rates else "q [°]")
        if j >= 3:
            ax.set_xlabel("time t [s]")
    return fig


def _distance_figure(clearance: dict, report: dict) -> Figure:
    """Smallest distance per pair group over time (clearance.csv), with the clearance."""
    fig = Figure(figsize=(13, 3.2), layout="constrained")
    ax = fig.subplots()
    t = clearance["t_s"]
    for name, values in clearance.items():
        if name != "t_s":
            ax.plot(t, values * 1e3, label=name.removesuffix("_m"))
    ax.axhline(0.0, color="#c62828", ls="--", lw=1)
    if report.get("clearance_m") is not None:
        ax.axhline(report["clearance_m"] * 1e3, color="#ef6c00", ls=":", lw=1, label="clearance")
    ax.set(xlabel="time t [s]", ylabel="minimum distance [mm]")
    ax.legend(loc="upper right", fontsize=8, ncols=4)
    return fig


def _triads(ax, X: np.ndarray, length: float, lw: float = 1.2) -> None:
    """Draw (K, 4, 4) frames as x/y/z segments of ``length`` [m]."""
    for axis, color in enumerate(TRIAD_COLORS):
        ends = X[:, :3, 3] + length * X[:, :3, axis]
        segments = np.stack([X[:, :3, 3], ends], axis=1)
        ax.add_collection3d(Line3DCollection(segments, colors=color, linewidths=lw))


def _equal_axes(ax, points: np.ndarray) -> None:
    """Equal scale on all axes; flat extents get a floor of a quarter of the largest."""
    low, high = points.min(axis=0), points.max(axis=0)
    span = np.maximum(high - low, 0.25 * (high - low).max()) * 1.1
    mid = (low + high) / 2
    for setter, m, h in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), mid, span / 2, strict=True):
        setter(m - h, m + h)
    ax.set_box_aspect(span)
    ax.locator_params(nbins=5)


def _views_figure(col, data: ProgramData) -> Figure:
    """Left: processing path and process frames F in P. Right: the cell in I."""
    fig = Figure(figsize=(13, 6), layout="constrained")
    X_PF = data.X_PF
    p_PF = X_PF[:, :3, 3]
    length = float(np.sum(np.linalg.norm(np.diff(p_PF, axis=0), axis=1)))
    sigma = col["sigma"]
    pick = np.searchsorted(sigma, np.linspace(sigma[0], sigma[-1], N_TRIADS))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    ax.plot(*p_PF.T, color="black", lw=1.5, label="processing path")
    triad = 0.7 * length / N_TRIADS
    _triads(ax, X_PF[np.minimum(pick, len(sigma) - 1)], triad)
    _triads(ax, np.eye(4)[None], 2 * triad, lw=2.5)
    ax.text(0, 0, 0, " P", fontsize=10)
    ax.scatter(*p_PF[0], color="black", s=20)
    ax.text(*p_PF[0], " start", fontsize=8)
    _equal_axes(ax, np.vstack([p_PF, np.zeros(3)]))
    ax.set(
        title="Part P: path and process frames F (x=t red, y=n green, z=b blue)",
        xlabel="x [m]",
        ylabel="y [m]",
        zlabel="z [m]",
    )
    # The cell in I: X_IE from the CSV (R = Rx(α)Ry(β)Rz(γ)); X_IB and X_IT from sample 0.
    X_IE = np.tile(np.eye(4), (len(sigma), 1, 1))
    X_IE[:, :3, :3] = Rotation.from_euler(
        "XYZ", np.column_stack([col["alpha"], col["beta"], col["gamma"]])
    ).as_matrix()
    X_IE[:, :3, 3] = np.column_stack([col["x"], col["y"], col["z"]])
    X_IB = X_IE[0] @ np.linalg.inv(data.X_BE[0])
    X_IT = X_IB @ data.X_BT
    p_IF0 = (X_IE[0] @ data.X_EP @ np.c_[p_PF, np.ones(len(p_PF))].T).T[:, :3]  # part at t=0
    ax = fig.add_subplot(1, 2, 2, projection="3d")
    ax.plot(*X_IE[:, :3, 3].T, color=XYZ_COLORS[0], lw=1.5, label="flange path p_IE")
    ax.plot(*p_IF0.T, color="#888888", ls="--", lw=1, label="processing path at t = 0")
    points = np.vstack([X_IE[:, :3, 3], p_IF0, X_IB[None, :3, 3], X_IT[None, :3, 3]])
    size = 0.08 * (points.max(axis=0) - points.min(axis=0)).max()
    _triads(ax, X_IE[np.minimum(pick[::2], len(sigma) - 1)], 0.5 * size, lw=0.8)
    for X, name in ((X_IB, " B (robot base)"), (X_IT, " T (tool)")):
        _triads(ax, X[None], size, lw=2.5)
        ax.text(*X[:3, 3], name, fontsize=9)
    _equal_axes(ax, points)
    ax.set(
        title="Cell I: flange path E, robot base B, fixed tool T",
        xlabel="x [m]",
        ylabel="y [m]",
        zlabel="z [m]",
    )
    ax.legend(loc="upper left", fontsize=8)
    return fig


def read_clearance(plan_dir: Path) -> dict | None:
    """clearance.csv by column ({"t_s": ..., "<group>_m": ...}), or None if absent."""
    file = Path(plan_dir) / "clearance.csv"
    if not file.is_file():
        return None
    names = file.read_text().splitlines()[0].split(",")
    table = np.loadtxt(file, delimiter=",", skiprows=1, ndmin=2)
    return {name: table[:, i] for i, name in enumerate(names)}


def report_figures(
    report: dict, col, data: ProgramData, clearance: dict | None = None
) -> list[tuple[str, str]]:
    """(caption, base64 PNG) of every plot, in page order."""
    ref = report["motion"]["speed_reference"].replace("tcp", "TCP")
    plots = [
        ("Flange trajectory in I (as the paper's fig. 5): position, Tait-Bryan angles "
         "R = Rx(α)Ry(β)Rz(γ), linear and angular velocity and acceleration.",
         lambda: _pose_figure(col)),
        (f"Speed at the {ref} against the command: the speed limit, lowered where the "
         "joint limits forced a speed reduction.", lambda: _speed_figure(report, col)),
        ("Joint positions with their limits (dashed).",
         lambda: _joint_figure(col, data, rates=False)),
        ("Joint velocities with their limits (dashed).",
         lambda: _joint_figure(col, data, rates=True)),
        ("Minimum distance over time per pair group (robot, part, tool, obstacles), "
         "against the required clearance.",
         (lambda: _distance_figure(clearance, report)) if clearance else None),
        ("3D views: the part with its processing path and process frames, and the flange "
         "path in the cell.", lambda: _views_figure(col, data)),
    ]  # fmt: skip
    with matplotlib.rc_context(_RC):  # rc settings apply when artists are made
        return [(caption, _png(make())) for caption, make in plots if make is not None]
