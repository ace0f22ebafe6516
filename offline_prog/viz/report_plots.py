"""The plots of report.html, drawn in the browser: interactive uPlot charts and SVG views.

Visualization only: numerical code never imports this module. Python does no drawing
here (matplotlib took seconds per report): it gathers the plan folder's columns once
(trajectory.csv, clearance.csv; SI converted to mm and degrees at this edge) and
describes each chart as a list of panels and series by column name; the page's script
draws them with uPlot (vendored in ``viz/assets``, MIT licence), which zooms on a
drag (double-click resets) and shows every value under the cursor, synchronised across
panels. The 3D views are two static SVG projections (top and side) of the part's path
with its process frames F in P, and of the flange path with the base B and tool T in I.
Frames: I inertial, B robot base, E flange, P part, F process frame, T fixed tool.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.export.program import ProgramData
from offline_prog.viz.outline import outline_in

XYZ_COLORS = ("#0072bd", "#d95318", "#edb120")  # x|α, y|β, z|γ, as in the paper's fig. 5
TRIAD_COLORS = ("#d62728", "#2ca02c", "#1f77b4")  # a frame's x, y, z axes
LIMIT_COLOR = "#c62828"
GRIPPER_COLOR = "#3b5b8c"
GROUP_COLORS = [*XYZ_COLORS, "#7e2f8e", "#77ac30", "#4dbeee"]  # distance per pair group
N_TRIADS = 24  # process frames drawn along the path
MAX_SVG_POINTS = 800  # per polyline of a view (a drawing, not data)
SIGNIFICANT_DIGITS = 6  # of each plotted value (the CSV keeps 10)
ASSETS = Path(__file__).resolve().parent / "assets"


def _series(label: str, column: str, color: str, *, dash: bool = False) -> dict:
    return {"label": label, "col": column, "color": color, "dash": dash}


def _limit(label: str, value: float) -> dict:
    return {"label": label, "const": float(value), "color": LIMIT_COLOR, "dash": True}


def _xyz(ylabel: str, columns: tuple[str, str, str], labels: str) -> dict:
    series = [_series(lab, c, col) for lab, c, col in zip(labels, columns, XYZ_COLORS, strict=True)]
    return {"ylabel": ylabel, "series": series}


def commanded_speed(report: dict, s: np.ndarray) -> np.ndarray:
    """(N,) speed cap of the time law at its parameter s [m]: top speed, lowered on
    report.json's speed-reduction stretches [m/s]."""
    cap = np.full(len(s), report["motion"]["top_speed_m_s"])
    for r in report["robot_motion"]["speed_reductions"]:
        inside = (s >= r["sigma_start_m"]) & (s <= r["sigma_end_m"])
        cap[inside] = np.minimum(cap[inside], r["speed_m_s"])
    return cap


def plot_columns(report: dict, col: dict, data: ProgramData, clearance: dict | None) -> dict:
    """Every plotted column once, at the page's units (mm, mm/s, °, °/s), by name."""
    out = {"t": col["t"]}
    for name in ("x", "y", "z"):
        out[f"{name}_mm"] = col[name] * 1e3
    for name in ("alpha", "beta", "gamma"):
        out[f"{name}_deg"] = np.rad2deg(col[name])
    for name in ("vx", "vy", "vz", "wx", "wy", "wz", "ax", "ay", "az", "dwx", "dwy", "dwz"):
        out[name] = col[name]
    flange = np.linalg.norm(np.column_stack([col["vx"], col["vy"], col["vz"]]), axis=1)
    if report["motion"]["speed_reference"] == "tcp":
        s, measured, other = col["sigma"], col["tcp_speed"], flange
    else:  # the law runs on the flange path's arc length
        p = np.column_stack([col["x"], col["y"], col["z"]])
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        measured, other = flange, col["tcp_speed"]
    out["speed_mm_s"], out["other_speed_mm_s"] = measured * 1e3, other * 1e3
    out["command_mm_s"] = commanded_speed(report, s) * 1e3
    for j in range(len(data.joint_names)):
        out[f"q{j + 1}_deg"] = np.rad2deg(data.controller_column(col, "q", j))
        out[f"qd{j + 1}_deg_s"] = np.rad2deg(data.controller_column(col, "qd", j))
    if clearance:
        out["clearance_t"] = clearance["t_s"]
        for name, values in clearance.items():
            if name != "t_s":
                out[f"distance:{name.removesuffix('_m')}"] = values * 1e3
    return out


def _joint_panels(data: ProgramData, rates: bool) -> list[dict]:
    panels = []
    for j, name in enumerate(data.joint_names):
        formula = "q2 + q3" if data.j23_factor > 0 else "q3 − q2"
        coupled = f" (controller: {formula})" if data.j23_coupled and j == 2 else ""
        low, high = (
            (-data.qd_max[j], data.qd_max[j]) if rates else (data.q_lower[j], data.q_upper[j])
        )
        column = f"qd{j + 1}_deg_s" if rates else f"q{j + 1}_deg"
        panels.append(
            {
                "title": f"J{j + 1} {name}{coupled}",
                "ylabel": "q̇ [°/s]" if rates else "q [°]",
                "series": [
                    _series(f"J{j + 1}", column, XYZ_COLORS[0]),
                    _limit("lower limit", np.rad2deg(low)),
                    _limit("upper limit", np.rad2deg(high)),
                ],
            }
        )
    return panels


def plot_specs(report: dict, data: ProgramData, columns: dict) -> list[dict]:
    """The charts in page order: caption, panel grid width and panels (series by column)."""
    ref = report["motion"]["speed_reference"].replace("tcp", "TCP")
    measured, other = ("TCP speed", "flange") if ref == "TCP" else ("flange speed", "TCP")
    pose = [
        _xyz("flange position p_IE [mm]", ("x_mm", "y_mm", "z_mm"), "xyz"),
        _xyz("angles [°]", ("alpha_deg", "beta_deg", "gamma_deg"), "αβγ"),
        _xyz("velocity v_IE [m/s]", ("vx", "vy", "vz"), "xyz"),
        _xyz("angular velocity w_IE [rad/s]", ("wx", "wy", "wz"), "xyz"),
        _xyz("acceleration a_IE [m/s²]", ("ax", "ay", "az"), "xyz"),
        _xyz("angular acc. [rad/s²]", ("dwx", "dwy", "dwz"), "xyz"),
    ]
    speed = {
        "ylabel": "speed [mm/s]",
        "series": [
            _series(f"{other} speed (not commanded)", "other_speed_mm_s", "#bbbbbb"),
            _series("commanded (limit, reductions)", "command_mm_s", "#000000", dash=True),
            _series(measured, "speed_mm_s", XYZ_COLORS[0]),
        ],
        "bands": slowdown_bands(report),
    }
    specs = [
        (
            "pose",
            "Flange trajectory in I (as the paper's fig. 5): position, Tait-Bryan angles "
            "R = Rx(α)Ry(β)Rz(γ), linear and angular velocity and acceleration.",
            2,
            pose,
        ),
        (
            "speed",
            f"Speed at the {ref} against the command: the speed limit, lowered where "
            "the joint limits forced a speed reduction; time-optimal slowdowns are shaded, "
            "each named by its limiting joint and constraint.",
            1,
            [speed],
        ),
        ("joints", "Joint positions with their limits (dashed).", 3, _joint_panels(data, False)),
        ("rates", "Joint velocities with their limits (dashed).", 3, _joint_panels(data, True)),
    ]
    groups = [name for name in columns if name.startswith("distance:")]
    if groups:
        series = [
            _series(name.removeprefix("distance:"), name, color)
            for name, color in zip(groups, GROUP_COLORS * len(groups), strict=False)
        ]
        series.append(_limit("contact", 0.0))
        if report.get("clearance_m") is not None:
            series.append({**_limit("clearance", report["clearance_m"] * 1e3), "color": "#ef6c00"})
        panel = {"x": "clearance_t", "ylabel": "minimum distance [mm]", "series": series}
        specs.append(
            (
                "distance",
                "Minimum distance over time per pair group (robot, part, tool, "
                "obstacles), against the required clearance.",
                1,
                [panel],
            )
        )
    return [{"id": i, "caption": c, "columns": n, "panels": p} for i, c, n, p in specs]


def slowdown_bands(report: dict) -> list[dict]:
    """The time law's slowdowns (time_optimal) as shaded bands of the speed plot:
    {t0, t1 [s], label: the limiting joint and constraint, e.g. "J3 acceleration"}."""
    bands = []
    for slow in report["robot_motion"].get("slowdowns", []):
        joint = f"J{slow['joint']} " if slow["joint"] is not None else ""
        bands.append(
            {"t0": slow["t_start_s"], "t1": slow["t_end_s"], "label": joint + slow["constraint"]}
        )
    return bands


def _rounded(values: np.ndarray) -> list[float]:
    """Values rounded to SIGNIFICANT_DIGITS of the column's largest magnitude."""
    values = np.asarray(values, dtype=float)
    top = float(np.abs(values).max()) if values.size else 0.0
    decimals = SIGNIFICANT_DIGITS - 1 - (int(np.floor(np.log10(top))) if top > 0 else 0)
    return np.round(values, max(decimals, 0)).tolist()


def plot_data_json(report: dict, col: dict, data: ProgramData, clearance: dict | None) -> str:
    """The page's plot data: {"columns": {name: values}, "plots": plot_specs}, as JSON
    that is safe inside a ``<script type="application/json">`` element."""
    columns = plot_columns(report, col, data, clearance)
    payload = {
        "columns": {name: _rounded(values) for name, values in columns.items()},
        "plots": plot_specs(report, data, columns),
    }
    text = json.dumps(payload, ensure_ascii=False, separators=(",", ":"), allow_nan=False)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def _svg_view(lines: list[tuple[np.ndarray, str, float]], labels, axes: tuple[int, int], title):
    """One orthographic SVG view: polylines (K, 3) [m] projected on two axes of their
    frame, with text labels at points; equal scale, y up."""
    points = np.vstack([p[:, axes] for p, _, _ in lines] + [p[None, axes] for p, _ in labels])
    low, high = points.min(axis=0), points.max(axis=0)
    span = max(float((high - low).max()), 1e-6) * 1.15
    mid = (low + high) / 2
    size, pad = 420, 24

    def xy(p):
        u = (p[:, axes] - mid) / span
        return np.column_stack([size / 2 + u[:, 0] * size, size / 2 - u[:, 1] * size]) + pad

    body = []
    for p, color, width in lines:
        p = p[:: max(1, len(p) // MAX_SVG_POINTS)] if len(p) > MAX_SVG_POINTS else p
        d = " ".join(f"{a:.1f},{b:.1f}" for a, b in xy(p))
        body.append(f'<polyline points="{d}" fill="none" stroke="{color}" stroke-width="{width}"/>')
    for p, text in labels:
        ((a, b),) = xy(p[None])
        body.append(
            f'<circle cx="{a:.1f}" cy="{b:.1f}" r="3"/><text x="{a + 5:.1f}" '
            f'y="{b - 5:.1f}">{text}</text>'
        )
    names = "xyz"
    full = size + 2 * pad
    return (
        f'<svg class="view" viewBox="0 0 {full} {full + 18}" width="{full}" height="{full + 18}"'
        f' xmlns="http://www.w3.org/2000/svg" font-size="12"><rect width="100%" height="100%"'
        f' fill="#fff"/><text x="{pad}" y="16">{title} ({names[axes[0]]} right, '
        f"{names[axes[1]]} up)</text>{''.join(body)}</svg>"
    )


def _triad_lines(X: np.ndarray, length: float, width: float) -> list:
    return [
        (np.stack([X[i, :3, 3], X[i, :3, 3] + length * X[i, :3, axis]]), color, width)
        for i in range(len(X))
        for axis, color in enumerate(TRIAD_COLORS)
    ]


def views_svg(
    col: dict,
    data: ProgramData,
    gripper: list[dict] | None = None,
    *,
    seams: list[tuple[str, np.ndarray]] | None = None,
) -> str:
    """Four SVG views: the part's path with process frames F in P (top, side), and
    the flange path with the part's path at t = 0, base B and tool T in I (top, side);
    the gripper's outline (its shapes in E, report.json's ``gripper``) in both.

    Args:
        col: trajectory.csv's columns by name; its first row's x, y, z, alpha, beta,
            gamma (the flange in I) place the robot base.
        data: the plan's rows (a seam's, or a whole job's: the flange path X_BE).
        seams: (name, X_PF (N, 4, 4) in P) of each seam of a job, drawn and named on
            the part; None: the rows' own X_PT, one seam.
    """
    seams = seams or [("start", data.X_PT)]  # the tool frame T in P: F on the seams
    length = sum(
        float(np.sum(np.linalg.norm(np.diff(X[:, :3, 3], axis=0), axis=1))) for _, X in seams
    )
    part, part_labels = [], [(np.zeros(3), "P")]
    for k, (name, X_PF) in enumerate(seams):
        color = "#000" if len(seams) == 1 else GROUP_COLORS[k % len(GROUP_COLORS)]
        n = max(2, N_TRIADS // len(seams))
        pick = np.linspace(0, len(X_PF) - 1, n).round().astype(int)
        part += [(X_PF[:, :3, 3], color, 1.5)]
        part += _triad_lines(X_PF[pick], 0.7 * length / N_TRIADS, 1.0)
        part_labels.append((X_PF[0, :3, 3], html.escape(name)))
    # The cell in I from sample 0: X_IB from the CSV's X_IE and plan.npz's X_BE.
    angles = np.column_stack([col["alpha"][:1], col["beta"][:1], col["gamma"][:1]])
    X_IE0 = np.eye(4)
    X_IE0[:3, :3] = Rotation.from_euler("XYZ", angles).as_matrix()[0]
    X_IE0[:3, 3] = [col["x"][0], col["y"][0], col["z"][0]]
    X_IB = X_IE0 @ np.linalg.inv(data.X_BE[0])
    p_IE = (X_IB @ np.c_[data.X_BE[:, :3, 3], np.ones(len(data.X_BE))].T).T[:, :3]
    X_IP0 = X_IE0 @ data.X_EP
    X_IT = X_IB @ data.X_BT
    cell = [(p_IE, XYZ_COLORS[0], 1.5)]
    cell += [(X[:, :3, 3] @ X_IP0[:3, :3].T + X_IP0[:3, 3], "#888", 1.0) for _, X in seams]
    size = 0.08 * float(
        np.ptp(np.vstack([p_IE, X_IB[None, :3, 3], X_IT[None, :3, 3]]), axis=0).max()
    )
    cell += _triad_lines(np.stack([X_IB, X_IT]), size, 2.0)
    cell_labels = [(X_IB[:3, 3], "B (robot base)"), (X_IT[:3, 3], "T (tool)")]
    for frame_pose, lines in ((np.linalg.inv(data.X_EP), part), (X_IE0, cell)):
        lines += [(p, GRIPPER_COLOR, 1.0) for p in outline_in(frame_pose, gripper or [])]
    paths = "path" if len(seams) == 1 else "seams' paths"
    return "".join(
        [
            _svg_view(part, part_labels, (0, 1), f"Part P: {paths} and frames F, top"),
            _svg_view(part, part_labels, (0, 2), "Part P: side"),
            _svg_view(cell, cell_labels, (0, 1), f"Cell I: flange path, {paths} at t=0, top"),
            _svg_view(cell, cell_labels, (0, 2), "Cell I: side"),
        ]
    )


def read_clearance(plan_dir: Path) -> dict | None:
    """clearance.csv by column ({"t_s": ..., "<group>_m": ...}), or None if absent."""
    file = Path(plan_dir) / "clearance.csv"
    if not file.is_file():
        return None
    names = file.read_text(encoding="utf-8").splitlines()[0].split(",")
    table = np.loadtxt(file, delimiter=",", skiprows=1, ndmin=2)
    return {name: table[:, i] for i, name in enumerate(names)}


# Draws every chart of the JSON in #plot-data into its <div id=...> (uPlot, one per panel).
PLOT_SCRIPT = (ASSETS / "plots.js").read_text(encoding="utf-8")


def plot_assets() -> tuple[str, str]:
    """(uPlot's CSS, uPlot's script) to inline in the page."""
    css, script = (ASSETS / name for name in ("uPlot.min.css", "uPlot.iife.min.js"))
    return css.read_text(encoding="utf-8"), script.read_text(encoding="utf-8")
