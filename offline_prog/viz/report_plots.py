"""What report.html draws besides its own charts: the uPlot assets and SVG views.

Visualization only: numerical code never imports this module. The page's charts are
drawn in the browser by uPlot (vendored in ``viz/assets``, MIT licence; the page's
chart script ``assets/plots.js``), which zooms on a drag (double-click resets) and shows
every value under the cursor; the job page (``viz.job_report_html``) describes them.
The 3D views are two static SVG projections (top and side) of the part's paths with
their process frames F in P, and of the flange path with the base B and tool T in I.
Frames: I inertial, B robot base, E flange, P part, F process frame, T fixed tool.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.export.program import ProgramData
from offline_prog.viz.outline import outline_in

XYZ_COLORS = ("#0072bd", "#d95318", "#edb120")  # x|α, y|β, z|γ, as in the paper's fig. 5
TRIAD_COLORS = ("#d62728", "#2ca02c", "#1f77b4")  # a frame's x, y, z axes
GRIPPER_COLOR = "#3b5b8c"
GROUP_COLORS = [*XYZ_COLORS, "#7e2f8e", "#77ac30", "#4dbeee"]  # distance per pair group
N_TRIADS = 24  # process frames drawn along the path
MAX_SVG_POINTS = 800  # per polyline of a view (a drawing, not data)
ASSETS = Path(__file__).resolve().parent / "assets"


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


# Draws every chart of the JSON in #plot-data into its <div id=...> (uPlot, one per panel).
PLOT_SCRIPT = (ASSETS / "plots.js").read_text(encoding="utf-8")


def plot_assets() -> tuple[str, str]:
    """(uPlot's CSS, uPlot's script) to inline in the page."""
    css, script = (ASSETS / name for name in ("uPlot.min.css", "uPlot.iife.min.js"))
    return css.read_text(encoding="utf-8"), script.read_text(encoding="utf-8")
