"""report.html of a whole job: a self-contained page read from the plan folder alone
(report.json, trajectory.csv, the names in programs/).

Summary: the verdict, the seam order (and the estimated saving against the given
order), the cycle time split into process and air time, one row per seam and per link,
and the process I/O switches. Plots (uPlot, inlined: ``viz.report_plots``): the TCP
speed over the whole job with the process output and the flow value on the same time
axis (the I/O timeline), and the joints against their limits. Views (SVG,
``viz.report_plots.views_svg``): the part with each seam's path and process frames and
the gripper's outline in P, and the flange path of the whole job in the cell I, from
plan.npz + job.npz. Every plan folder's report.html is this page (a ``path:`` cell is a
one-seam job).
"""

from __future__ import annotations

import csv
import html
import json
from pathlib import Path

import numpy as np

from offline_prog.atomic import MANIFEST, write_atomic
from offline_prog.export.formats import PROGRAMS_DIR
from offline_prog.export.job_program import JobProgramData
from offline_prog.viz.report_plots import PLOT_SCRIPT, plot_assets, views_svg

REPORT_FILE = "report.html"
JOINT_COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b")
MAX_PLOT_POINTS = 6000  # rows kept for the page's plots (every k-th row beyond)
XYZ_ABG = ("x", "y", "z", "alpha", "beta", "gamma")  # the flange in I (trajectory.csv)
QUALITY_SPAN = 3.0  # the quality plot's value axis: at most this many band widths beyond


_CSS = """
body{font-family:system-ui,sans-serif;margin:24px auto;max-width:1180px;color:#222}
h1{margin-bottom:4px} .sub{color:#666;margin-top:0}
table{border-collapse:collapse;width:100%;font-size:14px}
th,td{border-bottom:1px solid #ddd;padding:5px 8px;text-align:left;vertical-align:top}
th{width:190px;background:#f6f6f6} ul{margin:2px 0;padding-left:20px}
.lbl{color:#666} .pass,.fail{font-weight:bold;padding:2px 10px;border-radius:4px;color:#fff}
.pass{background:#2e7d32} .fail{background:#c62828}
figure{margin:18px 0} figcaption{color:#444;font-size:14px}
.plot{display:flex;flex-wrap:wrap;gap:8px} .views{display:flex;flex-wrap:wrap;gap:8px}
.view{border:1px solid #eee} .hint{color:#666;font-size:13px}
.u-legend{font-size:11px;line-height:1.2} .u-legend tr{display:inline-block;margin-right:8px}
.u-legend th,.u-legend td{padding:0 2px} .u-title{font-size:13px}
"""


def _e(value) -> str:
    """``value`` as HTML text (quotes escaped too: safe in an attribute)."""
    return html.escape(str(value), quote=True)


def _columns(plan_dir: Path, report: dict) -> dict[str, np.ndarray]:
    """The columns of trajectory.csv that the plots draw (``_drawn``), every k-th row
    beyond MAX_PLOT_POINTS and the last: ``segment`` as text, the others as numbers
    (empty cells NaN: the quality column off the dispensing rows). Only those rows and
    columns are parsed, by numpy's C reader: the same numbers as converting every
    cell's text."""
    header, *body = (
        (plan_dir / "trajectory.csv").read_text(encoding="utf-8").removesuffix("\n").split("\n")
    )
    header = next(csv.reader([header]))
    drawn = [name for name in header if _drawn(name, report)]
    step = max(1, len(body) // MAX_PLOT_POINTS)
    kept = body[::step] + ([body[-1]] if (len(body) - 1) % step else [])
    out = {}
    for names, as_text in _groups(drawn, report):
        if not names:
            continue
        cells = np.loadtxt(
            kept,
            delimiter=",",
            usecols=[header.index(name) for name in names],
            dtype=str if as_text else float,
            ndmin=2,
            comments=None,
        )
        for name, column in zip(names, cells.T, strict=True):
            if name == "segment":
                out[name] = column.astype(object)
            elif as_text:  # empty cells are NaN
                out[name] = np.where(column == "", "nan", column).astype(float)
            else:
                out[name] = column
    return {name: out[name] for name in drawn}


def _drawn(name: str, report: dict) -> bool:
    """Whether the plots draw trajectory.csv's column ``name``."""
    quality = report.get("quality") or {}
    return (
        name in ("t", "segment", "tcp_speed", *(f"q{j + 1}" for j in range(6)))
        or (name[:2] in ("do", "ao") and name[2:].isdigit())
        or name == quality.get("column")
    )


def _groups(names: list[str], report: dict) -> list[tuple[list[str], bool]]:
    """The drawn columns read as numbers and those read as text (the segment, and the
    quality column, empty off the dispensing rows)."""
    text = {"segment", (report.get("quality") or {}).get("column")}
    return [([x for x in names if x not in text], False), ([x for x in names if x in text], True)]


def _series(values: np.ndarray, scale: float = 1.0) -> list:
    finite = np.isfinite(values).tolist()
    return [
        round(v * scale, 6) if ok else None
        for v, ok in zip(np.asarray(values, dtype=float).tolist(), finite, strict=True)
    ]


def _plots(report: dict, col: dict) -> dict:
    t = col["t"]
    on_link = col["segment"] == "link"  # the tool is off the part's path: a gap
    columns = {"t": _series(t), "v": _series(np.where(on_link, np.nan, col["tcp_speed"]), 1e3)}
    io = [name for name in col if name[:2] in ("do", "ao") and name[2:].isdigit()]
    for name in io:
        columns[name] = _series(col[name])
    for j in range(6):
        columns[f"q{j + 1}"] = _series(col[f"q{j + 1}"], 180.0 / np.pi)
    speed = {
        "title": "TCP speed along the part",
        "ylabel": "speed [mm/s]",
        "series": [{"col": "v", "label": "v_TCP [mm/s]", "color": "#1f77b4"}],
    }
    io_panel = {
        "title": "process I/O (on the same time axis)",
        "ylabel": "output",
        "series": [
            {
                "col": name,
                "label": f"{name} {'[0/1]' if name[0] == 'd' else '[V]'}",
                "color": "#2e7d32" if name[0] == "d" else "#c62828",
            }
            for name in io
        ],
    }
    joints = {
        "title": "joint positions",
        "ylabel": "q [deg]",
        "series": [
            {"col": f"q{j + 1}", "label": f"q{j + 1} [deg]", "color": JOINT_COLORS[j]}
            for j in range(6)
        ],
    }
    panels = [speed, io_panel] if io else [speed]
    quality = _quality_plot(report.get("quality"), col, columns)
    return {
        "columns": columns,
        "plots": quality
        + [
            {
                "id": "plot-speed",
                "columns": 1,
                "panels": panels,
                "caption": "TCP speed over the whole job (gaps: links, where the tool is off "
                "the part's path) and the process output and flow value.",
            },
            {
                "id": "plot-joints",
                "columns": 1,
                "panels": [joints],
                "caption": "Joint positions over the whole job, home to home.",
            },
        ],
    }


def _quality_plot(quality: dict | None, col: dict, columns: dict) -> list[dict]:
    """The process quality over the job's time with its band shaded (report.json
    ``quality``, trajectory.csv's column of the model); none without a model. The value
    axis spans the band and the values, up to QUALITY_SPAN band widths beyond it (a
    standstill's spike would flatten the rest)."""
    if not quality or quality["column"] not in col:
        return []
    name, unit, (low, high) = quality["column"], quality["unit"], quality["band"]
    values = col[name]
    columns[name] = _series(values)
    finite = values[np.isfinite(values)]
    width = high - low
    top = min(max(finite.max(initial=high), high), high + QUALITY_SPAN * width)
    bottom = max(min(finite.min(initial=low), low), low - QUALITY_SPAN * width)
    margin = 0.1 * (top - bottom)
    share = quality["share_within_band"]
    within = "" if share is None else f"; {100 * share:.1f} % of the process length in the band"
    panel = {
        "title": f"process quality: {quality['model']} [{unit}]{within}",
        "ylabel": f"{name} [{unit}]",
        "series": [{"col": name, "label": f"{name} [{unit}]", "color": "#6a1b9a"}],
        "ybands": [{"y0": low, "y1": high, "label": f"band {low:g} .. {high:g} {unit}"}],
        "yrange": [bottom - margin, top + margin],
    }
    return [
        {
            "id": "plot-quality",
            "columns": 1,
            "panels": [panel],
            "caption": "Process quality along the job over time (only where the process "
            "runs), predicted by the process model from the planned speed and the outputs "
            "as the programs set them; shaded: the band. Stretches outside it and their "
            "causes are listed under Process quality.",
        }
    ]


def _quality_section(quality: dict | None) -> str:
    """The process quality's figures and its stretches outside the band (report.json
    ``quality``); empty without a model."""
    if not quality:
        return ""

    def share(key: str) -> str:
        value = quality.get(key)
        return "" if value is None else f"{100 * value:.1f} %"

    unit = quality["unit"]
    low, high = quality["band"]
    figures = [
        ("model", f"{quality['model']} ({quality['column']})"),
        ("band", f"{low:g} .. {high:g} {unit} (target {quality['target']:g})"),
        ("min .. max", f"{quality['min']:.4g} .. {quality['max']:.4g} {unit}")
        if quality["min"] is not None
        else ("min .. max", "nothing dispensed"),
        ("within the band", share("share_within_band") + " of the process length"),
    ]
    if "share_within_band_uncompensated" in quality:
        figures.append(("with compensation off", share("share_within_band_uncompensated")))
    stretches = _table(
        ["seam", "σ from [mm]", "σ to [mm]", "t from [s]", "t to [s]", f"worst [{unit}]", "cause"],
        [
            [
                x["seam"],
                f"{x['sigma_start_m'] * 1e3:.1f}",
                f"{x['sigma_end_m'] * 1e3:.1f}",
                f"{x['t_start_s']:.3f}",
                f"{x['t_end_s']:.3f}",
                "standstill" if x["worst"] is None else f"{x['worst']:.4g}",
                x["cause"],
            ]
            for x in quality["stretches_outside"]
        ],
    )
    rows = "".join(f"<tr><th>{_e(k)}</th><td>{_e(v)}</td></tr>" for k, v in figures)
    return (
        f'<h2>Process quality</h2><table id="quality">{rows}</table>'
        f"<p>{quality['n_stretches_outside']} stretches outside the band:</p>{stretches}"
    )


def _table(header: list[str], rows: list[list]) -> str:
    head = "".join(f"<th>{_e(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{_e(v)}</td>" for v in row) + "</tr>" for row in rows)
    return f'<table class="list"><tr>{head}</tr>{body}</table>'


def render_job_report_html(plan_dir: Path, *, folder_name: str | None = None) -> str:
    """The report page of a job's plan folder, as one HTML string; ``folder_name``: the
    plan folder's name as the user sees it (the writer renders into a staged temporary
    folder swapped in under it); default ``plan_dir``'s own name."""
    plan_dir = Path(plan_dir)
    folder_name = folder_name or plan_dir.name
    report = json.loads((plan_dir / "report.json").read_text(encoding="utf-8"))
    col = _columns(plan_dir, report)
    job = report["job"]
    ok = report["collision_free"]
    word = '<span class="pass">PASS</span>' if ok else '<span class="fail">FAIL</span>'
    programs = sorted(
        p.relative_to(plan_dir).as_posix()
        for p in (plan_dir / PROGRAMS_DIR).glob("**/*")
        if p.is_file() and p.name != MANIFEST
    )
    order = ", ".join(f"{o['seam']} ({o['direction']})" for o in job["order"])
    summary = [
        ("Result", word),
        (
            "Order",
            f"{order}: {job['order_mode']} ({job['order_method']}), estimated "
            f"saving {job['estimated_saving_s']:.2f} s against the given order",
        ),
        (
            "Cycle time",
            f"{job['cycle_time_s']:.2f} s: process {job['process_time_s']:.2f} s, "
            f"air {job['air_time_s']:.2f} s (links {job['link_time_s']:.2f} s, "
            f"approach and retract {job['approach_retract_time_s']:.2f} s)",
        ),
        (
            "Clearance",
            "none checked"
            if report["min_distance_m"] is None
            else f"min distance {report['min_distance_m'] * 1e3:.1f} mm",
        ),
        ("Programs", ", ".join(programs) or "none (the plan failed)"),
    ]
    table = "".join(
        f"<tr><th>{_e(k)}</th><td>{v if k == 'Result' else _e(v)}</td></tr>" for k, v in summary
    )
    seams = _table(
        ["seam", "length [mm]", "time [s]", "fit max error [mm]", "min clearance [mm]"],
        [
            [
                s["seam"],
                f"{s['path']['length_m'] * 1e3:.1f}",
                f"{s['trajectory']['duration_s']:.2f}",
                f"{s['fit']['max_error_mm']:.4f}",
                "" if s["min_distance_m"] is None else f"{s['min_distance_m'] * 1e3:.1f}",
            ]
            for s in report["seams"]
        ],
    )
    links = _table(
        ["link", "method", "time [s]", "joint path [deg]", "waypoints", "min clearance [mm]"],
        [
            [
                k["name"],
                k["method"] or f"FAILED: {k['failure']}",
                f"{k['duration_s']:.2f}",
                f"{np.rad2deg(k['length_rad']):.1f}",
                k["waypoints"],
                "" if k["min_clearance_m"] is None else f"{k['min_clearance_m'] * 1e3:.1f}",
            ]
            for k in report["links"]
        ],
    )
    events = _table(
        ["seam", "output", "state", "position along the path [mm]", "t [s]"],
        [
            [
                e["seam"],
                e["digital_output"],
                e["state"],
                f"{e['path_m'] * 1e3:.2f}",
                f"{e['t_s']:.3f}",
            ]
            for e in report["process_io"]
        ],
    )
    quality = _quality_section(report.get("quality"))
    data = _plots(report, col)
    text = json.dumps(data, separators=(",", ":"), allow_nan=False)
    text = text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")
    figures = "".join(
        f'<figure><div class="plot" id="{p["id"]}"></div><figcaption>{_e(p["caption"])}'
        "</figcaption></figure>"
        for p in data["plots"]
    )
    figures += _views(plan_dir, report)
    css, script = plot_assets()
    title = f"Job report: {report.get('name') or folder_name}"
    return (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{_e(title)}'
        f"</title><style>{_CSS}{css}</style></head><body><h1>{_e(title)}</h1>"
        f'<p class="sub">{_e(report.get("generator", ""))}, planned '
        f"{_e(report.get('generated', ''))}; plan folder {_e(folder_name)}</p><h2>Summary</h2>"
        f'<table id="summary">{table}'
        f"</table><h2>Seams</h2>{seams}<h2>Links</h2>{links}<h2>Process I/O</h2>{events}{quality}"
        f'<h2>Plots</h2><p class="hint">Drag to zoom into a time range, double-click to '
        f"reset.</p>{figures}"
        f'<script type="application/json" id="plot-data">{text}</script>'
        f"<script>{script}</script><script>{PLOT_SCRIPT}</script></body></html>\n"
    )


def _views(plan_dir: Path, report: dict) -> str:
    """The four SVG views of the job (``report_plots.views_svg``): each seam's path in
    P, the job's flange path in I, the gripper's outline in both."""
    data = JobProgramData.load(plan_dir)
    with open(plan_dir / "trajectory.csv", encoding="utf-8") as stream:
        header, first = (next(csv.reader([stream.readline()])) for _ in range(2))
    col = {name: np.array([float(first[header.index(name)])]) for name in XYZ_ABG}
    seams = [(name, seam.X_PT) for name, seam in zip(data.seam_names, data.seams, strict=True)]
    svg = views_svg(col, data.job, report.get("gripper"), seams=seams)
    return (
        f'<h2>Views</h2><figure><div class="views">{svg}</div><figcaption>The part with '
        "each seam's path and its process frames F (x = t red, y = n green, z = b blue), and "
        "the flange path of the whole job in the cell; the gripper's outline (blue-grey) on "
        "the part and at the flange at t = 0.</figcaption></figure>"
    )


def write_job_report_html(plan_dir: Path, *, folder_name: str | None = None) -> Path:
    target = Path(plan_dir) / REPORT_FILE
    write_atomic(target, render_job_report_html(plan_dir, folder_name=folder_name))
    return target
