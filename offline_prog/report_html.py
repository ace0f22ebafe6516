"""report.html: a self-contained page that shows a finished plan to a person.

Visualization only: numerical code never imports this module. It reads the plan
folder alone (report.json, trajectory.csv, plan.npz, the names in programs/), so
a report can be rebuilt without re-planning. Plots are matplotlib figures on the
Agg canvas (no pyplot state), embedded as base64 PNG: the page loads nothing.
Frames (paper letters): I inertial, B robot base, E flange, P part, F process
frame, T fixed tool. SI inside; millimetres and degrees only on the page.

Every number in the summary table is a ``<span data-key data-value>`` naming the
report.json entry it shows, so tests can check the page against the report.
"""

from __future__ import annotations

import base64
import html
import io
import json
import re
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Line3DCollection
from scipy.spatial.transform import Rotation

from offline_prog.atomic import write_atomic
from offline_prog.export.program import ProgramData

REPORT_FILE = "report.html"
PROGRAMS_DIR = "programs"  # as offline_prog.export.formats.PROGRAMS_DIR
# Pass/fail: a measured speed off the command by more than this fraction of the top
# speed fails; the joint checks on trajectory.csv allow this much rounding.
SPEED_ERROR_MAX_REL = 1e-3
JOINT_CHECK_TOL = 1e-6
# Unit shown on the page -> factor from the report's unit, by the key's unit suffix.
_SCALES = {("_m", "mm"): 1e3, ("_rel", "%"): 100.0, ("_use", "%"): 100.0}
_FIELD = re.compile(r"\{([\w.#]+)(?::([^\s}]*)(?: ([^}]*))?)?\}")


def lookup(report: dict, key: str):
    """The value at a dotted key of report.json (list items by index)."""
    value = report
    for part in key.split("."):
        value = value[int(part)] if isinstance(value, list) else value[part]
    return value


def _e(value) -> str:
    return html.escape(str(value), quote=True)


def fill(template: str, report: dict) -> str:
    """HTML of ``template`` with each ``{key:format unit}`` field taken from report.json.

    Literal text is escaped. A list shows its length; a string shows as is; a number
    is scaled to the unit (``_m`` keys shown in mm ×1000, ``_rel``/``_use`` in % ×100).
    """
    out, end = [], 0
    for match in _FIELD.finditer(template):
        key, fmt, unit = match.groups()
        value = lookup(report, key)
        if isinstance(value, list):
            value = len(value)
        stem = re.sub(r"(\.\d+)+$", "", key)  # list items take their list's unit
        scale = next((f for (s, u), f in _SCALES.items() if stem.endswith(s) and unit == u), 1.0)
        shown = format(value * scale if scale != 1.0 else value, fmt) if fmt else str(value)
        shown += "" if not unit else unit if unit in "°%×" else f" {unit}"
        out += [_e(template[end : match.start()]), '<span class="num" data-key="', _e(key)]
        out += ['" data-value="', _e(json.dumps(value)), '">', _e(shown), "</span>"]
        end = match.end()
    return "".join(out) + _e(template[end:])


def _items(report: dict, key: str, template: str, *, inline: bool = False) -> str:
    """``template`` filled for each entry of the list or dict at ``key`` (``#`` = index
    or dict key), as a bullet list or inline with joint labels J1, J2, ..."""
    value = lookup(report, key)
    keys = list(value) if isinstance(value, dict) else range(len(value))
    if inline:
        return " ".join(
            f'<span class="lbl">J{i + 1}</span> {fill(template.replace("#", str(i)), report)}'
            for i in keys
        )
    filled = (fill(template.replace("#", str(i)), report) for i in keys)
    return "<ul>" + "".join(f"<li>{item}</li>" for item in filled) + "</ul>"


def collision_prefix(report: dict) -> str | None:
    """Where report.json keeps the collision check: "collision." (a nested record),
    "" (top-level ``min_distance_m`` / ``collision_free``), or None: not checked."""
    if isinstance(report.get("collision"), dict):
        return "collision."
    return "" if {"min_distance_m", "collision_free"} & set(report) else None


def min_distance(report: dict) -> float | None:
    """Minimum distance between robot, part, tool and obstacles [m], or None."""
    prefix = collision_prefix(report)
    value = None if prefix is None else lookup(report, f"{prefix}min_distance_m")
    return None if value is None else float(value)


# The summary table: (label, template[, list key, item template[, inline]]) with
# report.json fields in {key:format unit}; the item template repeats for each entry.
_RM, _STEP, _RED = (
    "robot_motion",
    "robot_motion.largest_joint_step",
    "robot_motion.speed_reductions",
)
# fmt: off
ROWS = (
    ("Cell", "{name} ({cell})"),
    ("Robot", "{robot}, IK branch {robot_motion.branch:d}"),
    ("Tool", "{tool}, turned {robot_motion.tool_rotation_deg:.1f °} about its axis"),
    ("Part", "{part}"),
    ("Path length", "{path.length_m:.4f m} ({path.source}, {path.n_points:d} points)"),
    ("Fit error", "max {fit.max_error_mm:.4f mm}, RMS {fit.rms_error_mm:.4f mm} (tolerance "
     "{fit.tolerance_mm:.3f mm}; degree {fit.degree:d}, {fit.n_control_points:d} control "
     "points)"),
    ("Cycle time", "{trajectory.duration_s:.3f s} (without joint limits "
     "{robot_motion.cycle_time_without_joint_limits_s:.3f s})"),
    ("Speed command", "{motion.limits.speed_m_s:.4f m/s} at the {motion.speed_reference}, "
     "reached {motion.top_speed_m_s:.4f m/s}; acceleration "
     "{motion.limits.max_acceleration_m_s2:.3f m/s²}, jerk {motion.limits.max_jerk_m_s3:.2f m/s³}"),
    ("TCP speed held", "max deviation {trajectory.tcp_speed_max_error_rel:.2g %} of the top "
     "speed; chord check {trajectory.chord_speed_max_error_rel:.2g %}"),
    ("Flange", "max speed {trajectory.max_flange_speed_m_s:.4f m/s}, acceleration "
     "{trajectory.max_flange_acceleration_m_s2:.3f m/s²}, angular speed "
     "{trajectory.max_angular_speed_rad_s:.3f rad/s}"),
    ("Cusps", "{cusps:d}", "cusps", "σ = {cusps.#.sigma_m:.4f m}: {cusps.#.kind}, flange at "
     "{cusps.#.flange_speed_ratio:.2f ×} the TCP speed"),
    ("Minimum distance", None),
    ("Joint-limit margins", "(min {robot_motion.min_joint_limit_margin_deg:.1f °})",
     f"{_RM}.joint_limit_margin_deg", f"{{{_RM}.joint_limit_margin_deg.#:.1f °}}", True),
    ("Joint speed use", "of the limit", f"{_RM}.max_joint_speed_use",
     f"{{{_RM}.max_joint_speed_use.#:.1f %}}", True),
    ("Largest joint step", f"{{{_STEP}.step_deg:.3f °}} on joint {{{_STEP}.joint:d}} at "
     f"σ = {{{_STEP}.sigma_m:.4f m}}"),
    ("Singularity distance", "", f"{_RM}.singularities",
     f"#: {{{_RM}.singularities.#.distance:.3f}} {{{_RM}.singularities.#.unit}} at "
     f"σ = {{{_RM}.singularities.#.sigma_m:.4f m}}"),
    ("Speed reductions", f"{{{_RED}:d}}", _RED, f"σ {{{_RED}.#.sigma_start_m:.4f m}} to "
     f"{{{_RED}.#.sigma_end_m:.4f m}}: {{{_RED}.#.speed_m_s:.4f m/s}} "
     f"(−{{{_RED}.#.reduction_percent:.1f %}})"),
)
# fmt: on


def _min_distance_cell(report: dict) -> str:
    """The distance row. The closest pair is read as outputs.collision_summary writes
    it (closest_pair {pair: [a, b], t_s, sigma_m}) or as collision.CollisionResult
    does (closest {a, b, t_s, sigma_m}); clearance_m where given."""
    p = collision_prefix(report)
    if p is None:
        return "not checked"
    if min_distance(report) is None:
        return "checked, no pair measured"
    record = lookup(report, p[:-1]) if p else report
    text = f"{{{p}min_distance_m:.2f mm}}"
    for key, a, b in (("closest_pair", "pair.0", "pair.1"), ("closest", "a", "b")):
        if isinstance(record.get(key), dict):
            c = f"{p}{key}"
            text += f" between {{{c}.{a}}} and {{{c}.{b}}} at t = {{{c}.t_s:.3f s}}, "
            text += f"σ = {{{c}.sigma_m:.4f m}}"
            break
    if record.get("clearance_m") is not None:
        text += f" (clearance {{{p}clearance_m:.2f mm}})"
    return fill(text, report)


def summary_rows(report: dict, programs: list[Path], plan_dir: Path) -> list[tuple[str, str]]:
    """(label, cell HTML) rows of the summary table (ROWS, then the program files)."""
    rows = []
    for label, head, *items in ROWS:
        if head is None:
            rows.append((label, _min_distance_cell(report)))
            continue
        cell = fill(head, report)
        if items:
            key, template, *inline = items
            listed = _items(report, key, template, inline=bool(inline))
            cell = f"{listed} {cell}" if inline else f"{cell}{listed}"
        rows.append((label, cell))
    files = [
        f"<li>{_e(p.relative_to(plan_dir).as_posix())} ({p.stat().st_size:,} bytes)</li>"
        for p in programs
    ]
    rows.append(("Programs", f'<ul class="files">{"".join(files)}</ul>' if files else "none"))
    return rows


def verdict(report: dict, col: dict, data: ProgramData) -> tuple[list[str], list[str]]:
    """(failures, notes) as sentences; the plan passes when there is no failure.

    Besides report.json's own numbers, joint positions and speeds are re-checked
    against plan.npz's limits on trajectory.csv, i.e. on what the programs got.
    """
    fail, note = [], []
    if not data.feasible or report.get("feasible", True) is False:
        fail.append(f"the planner marked the plan failed: {data.failure or report.get('failure')}")
    fit, tr = report["fit"], report["trajectory"]
    if fit["max_error_mm"] > fit["tolerance_mm"]:
        fail.append(f"fit error {fit['max_error_mm']:.4f} mm above {fit['tolerance_mm']} mm")
    for key in ("tcp_speed_max_error_rel", "chord_speed_max_error_rel"):
        if tr[key] > SPEED_ERROR_MAX_REL:
            fail.append(f"speed not held: {key} = {tr[key]:.2g} > {SPEED_ERROR_MAX_REL:g}")
    for j in range(len(data.q_lower)):
        q, qd = col[f"q{j + 1}"], col[f"qd{j + 1}"]
        if (
            q.min() < data.q_lower[j] - JOINT_CHECK_TOL
            or q.max() > data.q_upper[j] + JOINT_CHECK_TOL
        ):
            fail.append(f"joint {j + 1} leaves its position limits in trajectory.csv")
        if np.abs(qd).max() > data.qd_max[j] * (1.0 + JOINT_CHECK_TOL):
            fail.append(f"joint {j + 1} exceeds its speed limit in trajectory.csv")
    prefix, distance = collision_prefix(report), min_distance(report)
    record = {} if prefix is None else lookup(report, prefix[:-1]) if prefix else report
    if prefix is None:
        note.append("collisions and clearances were not checked")
    elif record.get("collision_free") is False or (distance is not None and distance <= 0):
        clearance = record.get("clearance_m") or 0.0
        fail.append(
            record.get("message")
            or f"collision check: minimum distance {distance * 1e3:.2f} mm, below the "
            f"clearance {clearance * 1e3:.2f} mm"
        )
    if n_cusps := sum(c["kind"] == "cusp" for c in report["cusps"]):
        note.append(f"{n_cusps} cusp(s) where the flange nearly stops")
    if report["robot_motion"]["speed_reductions"]:
        note.append("the process speed is reduced on stretches to respect joint limits")
    if report["motion"]["top_speed_reduced"]:
        note.append("the path is too short to reach the commanded speed")
    for kind, entry in report["robot_motion"]["singularities"].items():
        if entry["near"]:
            note.append(f"near a {kind} singularity on {len(entry['near'])} stretch(es)")
    return fail, note


def load_plan_folder(plan_dir: Path) -> tuple[dict, dict[str, np.ndarray], ProgramData, list]:
    """report.json, trajectory.csv by column (SI), plan.npz, and the program files.

    Raises:
        ValueError: naming the file that is missing or unreadable.
    """
    plan_dir = Path(plan_dir)
    file = plan_dir / "report.json"
    try:
        report = json.loads(file.read_text())
        file = plan_dir / "trajectory.csv"
        with open(file) as stream:
            header = stream.readline().strip().split(",")
            table = np.loadtxt(stream, delimiter=",", ndmin=2)
    except (OSError, ValueError) as error:
        raise ValueError(f"{file}: not readable as a plan output ({error})") from None
    columns = {name: table[:, i] for i, name in enumerate(header)}
    programs = sorted(p for p in (plan_dir / PROGRAMS_DIR).glob("**/*") if p.is_file())
    return report, columns, ProgramData.load(plan_dir), programs


# --- figures (matplotlib Figure on the Agg canvas; no pyplot, no global state) ---

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
            values, lower, upper = col[f"qd{j + 1}"], -data.qd_max[j], data.qd_max[j]
        else:
            values, lower, upper = col[f"q{j + 1}"], data.q_lower[j], data.q_upper[j]
        ax.plot(t, np.rad2deg(values), color=XYZ_COLORS[0])
        for limit in (lower, upper):
            ax.axhline(np.rad2deg(limit), color="#c62828", ls="--", lw=1)
        ax.set_title(f"J{j + 1} {names[j]}", fontsize=9)
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


_CSS = """
body{font-family:system-ui,sans-serif;margin:24px auto;max-width:1180px;color:#222}
h1{margin-bottom:4px} .sub{color:#666;margin-top:0}
table{border-collapse:collapse;width:100%;font-size:14px}
th,td{border-bottom:1px solid #ddd;padding:5px 8px;text-align:left;vertical-align:top}
th{width:190px;background:#f6f6f6} ul{margin:2px 0;padding-left:20px}
.lbl{color:#666} .pass,.fail{font-weight:bold;padding:2px 10px;border-radius:4px;color:#fff}
.pass{background:#2e7d32} .fail{background:#c62828}
figure{margin:18px 0} img{width:100%;border:1px solid #eee}
figcaption{color:#444;font-size:14px}
"""


def render_report_html(plan_dir: Path) -> str:
    """The report page of a plan folder, as one HTML string (deterministic)."""
    plan_dir = Path(plan_dir)
    report, col, data, programs = load_plan_folder(plan_dir)
    fail, note = verdict(report, col, data)
    word = '<span class="fail">FAIL</span>' if fail else '<span class="pass">PASS</span>'
    reasons = [f'<li class="reason">{_e(s)}</li>' for s in fail] + [
        f'<li class="reason note">note: {_e(s)}</li>' for s in note
    ]
    rows = [("Result", f'{word}<ul class="reasons">{"".join(reasons)}</ul>')]
    rows += summary_rows(report, programs, plan_dir)
    table = "".join(f"<tr><th>{_e(label)}</th><td>{cell}</td></tr>" for label, cell in rows)
    figures = "".join(
        f'<figure><img alt="{_e(caption)}" src="data:image/png;base64,{png}">'
        f"<figcaption>{_e(caption)}</figcaption></figure>"
        for caption, png in report_figures(report, col, data, read_clearance(plan_dir))
    )
    title = f"Plan report: {report.get('name') or plan_dir.name}"
    return (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{_e(title)}'
        f"</title><style>{_CSS}</style></head><body><h1>{_e(title)}</h1>"
        f'<p class="sub">{_e(report.get("generator", ""))}, '
        f"planned {_e(report.get('generated', ''))}"
        f"; plan folder {_e(plan_dir.name)}</p><h2>Summary</h2>"
        f'<table id="summary">{table}</table><h2>Plots</h2>{figures}</body></html>\n'
    )


def write_report_html(plan_dir: Path) -> Path:
    """Write ``plan_dir/report.html`` (atomically) and return its path.

    Raises:
        ValueError: the folder lacks report.json, trajectory.csv or plan.npz.
    """
    target = Path(plan_dir) / REPORT_FILE
    write_atomic(target, render_report_html(plan_dir))
    return target
