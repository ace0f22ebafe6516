"""The summary table and the verdict of report.html, filled from report.json.

Visualization only: numerical code never imports this module. Every number in the
table is a ``<span data-key data-value>`` naming the report.json entry it shows, so
tests can check the page against the report. SI in report.json; millimetres and
degrees only on the page.
"""

from __future__ import annotations

import html
import json
import re
from pathlib import Path

import numpy as np

from offline_prog.export.program import ProgramData

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


def escape(value) -> str:
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
        out += [escape(template[end : match.start()]), '<span class="num" data-key="', escape(key)]
        out += ['" data-value="', escape(json.dumps(value)), '">', escape(shown), "</span>"]
        end = match.end()
    return "".join(out) + escape(template[end:])


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
ROWS = (
    ("Cell", "{name} ({cell})"),
    ("Robot", "{robot}, IK branch {robot_motion.branch:d}"),
    (
        "Tool",
        "{tool}, turned {robot_motion.tool_rotation_deg:.1f °} about its axis "
        "({robot_motion.tool_turn_deg.0:.1f °} to {robot_motion.tool_turn_deg.1:.1f °} along "
        "the path)",
    ),
    ("Part", "{part}"),
    ("Path length", "{path.length_m:.4f m} ({path.source}, {path.n_points:d} points)"),
    (
        "Fit error",
        "max {fit.max_error_mm:.4f mm}, RMS {fit.rms_error_mm:.4f mm} (tolerance "
        "{fit.tolerance_mm:.3f mm}; degree {fit.degree:d}, {fit.n_control_points:d} control "
        "points)",
    ),
    (
        "Cycle time",
        "{trajectory.duration_s:.3f s} (without joint limits "
        "{robot_motion.cycle_time_without_joint_limits_s:.3f s})",
    ),
    (
        "Speed command",
        "{motion.limits.speed_m_s:.4f m/s} at the {motion.speed_reference}, "
        "reached {motion.top_speed_m_s:.4f m/s}; acceleration "
        "{motion.limits.max_acceleration_m_s2:.3f m/s²}, "
        "jerk {motion.limits.max_jerk_m_s3:.2f m/s³}",
    ),
    (
        "TCP speed held",
        "max deviation {trajectory.tcp_speed_max_error_rel:.2g %} of the top "
        "speed; chord check {trajectory.chord_speed_max_error_rel:.2g %}",
    ),
    (
        "Flange",
        "max speed {trajectory.max_flange_speed_m_s:.4f m/s}, acceleration "
        "{trajectory.max_flange_acceleration_m_s2:.3f m/s²}, angular speed "
        "{trajectory.max_angular_speed_rad_s:.3f rad/s}",
    ),
    (
        "Cusps",
        "{cusps:d}",
        "cusps",
        "σ = {cusps.#.sigma_m:.4f m}: {cusps.#.kind}, flange at "
        "{cusps.#.flange_speed_ratio:.2f ×} the TCP speed",
    ),
    ("Minimum distance", None),
    (
        "Joint-limit margins",
        "(min {robot_motion.min_joint_limit_margin_deg:.1f °})",
        f"{_RM}.joint_limit_margin_deg",
        f"{{{_RM}.joint_limit_margin_deg.#:.1f °}}",
        True,
    ),
    (
        "Joint speed use",
        "of the limit",
        f"{_RM}.max_joint_speed_use",
        f"{{{_RM}.max_joint_speed_use.#:.1f %}}",
        True,
    ),
    (
        "Largest joint step",
        f"{{{_STEP}.step_deg:.3f °}} on joint {{{_STEP}.joint:d}} at σ = {{{_STEP}.sigma_m:.4f m}}",
    ),
    (
        "Singularity distance",
        "",
        f"{_RM}.singularities",
        f"#: {{{_RM}.singularities.#.distance:.3f}} {{{_RM}.singularities.#.unit}} at "
        f"σ = {{{_RM}.singularities.#.sigma_m:.4f m}}",
    ),
    (
        "Speed reductions",
        f"{{{_RED}:d}}",
        _RED,
        f"σ {{{_RED}.#.sigma_start_m:.4f m}} to "
        f"{{{_RED}.#.sigma_end_m:.4f m}}: {{{_RED}.#.speed_m_s:.4f m/s}} "
        f"(−{{{_RED}.#.reduction_percent:.1f %}})",
    ),
)


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
        f"<li>{escape(p.relative_to(plan_dir).as_posix())} ({p.stat().st_size:,} bytes)</li>"
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
        q, qd = data.controller_column(col, "q", j), data.controller_column(col, "qd", j)
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
