"""report.html: a self-contained page that shows a finished plan to a person.

Visualization only: numerical code never imports this module. It reads the plan
folder alone (report.json, trajectory.csv, plan.npz, the names in programs/), so
a report can be rebuilt without re-planning. Plots are drawn by the page itself
(uPlot, inlined, with the data as JSON; see ``report_plots``): the page loads nothing.
Frames (paper letters): I inertial, B robot base, E flange, P part, F process
frame, T fixed tool. SI inside; millimetres and degrees only on the page.

Every number in the summary table is a ``<span data-key data-value>`` naming the
report.json entry it shows, so tests can check the page against the report.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from offline_prog.atomic import MANIFEST, write_atomic
from offline_prog.export.program import ProgramData
from offline_prog.viz.report_plots import (
    PLOT_SCRIPT,
    plot_assets,
    plot_data_json,
    read_clearance,
    views_svg,
)
from offline_prog.viz.report_summary import escape as _e
from offline_prog.viz.report_summary import summary_rows, verdict

REPORT_FILE = "report.html"
PROGRAMS_DIR = "programs"  # as offline_prog.export.formats.PROGRAMS_DIR


def load_plan_folder(plan_dir: Path) -> tuple[dict, dict[str, np.ndarray], ProgramData, list]:
    """report.json, trajectory.csv by column (SI), plan.npz, and the program files.

    Raises:
        ValueError: naming the file that is missing or unreadable.
    """
    plan_dir = Path(plan_dir)
    file = plan_dir / "report.json"
    try:
        report = json.loads(file.read_text(encoding="utf-8"))
        file = plan_dir / "trajectory.csv"
        with open(file, encoding="utf-8") as stream:
            header = stream.readline().strip().split(",")
            table = np.loadtxt(stream, delimiter=",", ndmin=2)
    except (OSError, ValueError) as error:
        raise ValueError(f"{file}: not readable as a plan output ({error})") from None
    columns = {name: table[:, i] for i, name in enumerate(header)}
    programs = sorted(
        p for p in (plan_dir / PROGRAMS_DIR).glob("**/*") if p.is_file() and p.name != MANIFEST
    )
    return report, columns, ProgramData.load(plan_dir), programs


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


def render_report_html(plan_dir: Path, *, folder_name: str | None = None) -> str:
    """The report page of a plan folder, as one HTML string (deterministic).

    ``folder_name``: the plan folder's name as the user will see it (the writer
    renders into a staged temporary folder swapped in under this name); default
    ``plan_dir``'s own name."""
    plan_dir = Path(plan_dir)
    folder_name = folder_name or plan_dir.name
    report, col, data, programs = load_plan_folder(plan_dir)
    fail, note = verdict(report, col, data)
    word = '<span class="fail">FAIL</span>' if fail else '<span class="pass">PASS</span>'
    reasons = [f'<li class="reason">{_e(s)}</li>' for s in fail] + [
        f'<li class="reason note">note: {_e(s)}</li>' for s in note
    ]
    rows = [("Result", f'{word}<ul class="reasons">{"".join(reasons)}</ul>')]
    rows += summary_rows(report, programs, plan_dir)
    table = "".join(f"<tr><th>{_e(label)}</th><td>{cell}</td></tr>" for label, cell in rows)
    plot_json = plot_data_json(report, col, data, read_clearance(plan_dir))
    figures = "".join(
        f'<figure><div class="plot" id="{plot["id"]}"></div>'
        f"<figcaption>{_e(plot['caption'])}</figcaption></figure>"
        for plot in json.loads(plot_json)["plots"]
    )
    figures += (
        f'<figure><div class="views">{views_svg(col, data, report.get("gripper"))}</div>'
        "<figcaption>Views: the part with its processing path and process frames F (x = t "
        "red, y = n green, z = b blue), and the flange path in the cell; the gripper's "
        "outline (blue-grey) on the part and at the flange at t = 0.</figcaption></figure>"
    )
    css, script = plot_assets()
    title = f"Plan report: {report.get('name') or folder_name}"
    return (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{_e(title)}'
        f"</title><style>{_CSS}{css}</style></head><body><h1>{_e(title)}</h1>"
        f'<p class="sub">{_e(report.get("generator", ""))}, '
        f"planned {_e(report.get('generated', ''))}"
        f"; plan folder {_e(folder_name)}</p><h2>Summary</h2>"
        f'<table id="summary">{table}</table><h2>Plots</h2><p class="hint">Drag to zoom '
        "into a time range, double-click to reset; the cursor shows every value.</p>"
        f'{figures}<script type="application/json" id="plot-data">{plot_json}</script>'
        f"<script>{script}</script><script>{PLOT_SCRIPT}</script></body></html>\n"
    )


def write_report_html(plan_dir: Path, *, folder_name: str | None = None) -> Path:
    """Write ``plan_dir/report.html`` (atomically) and return its path; folder_name
    as for :func:`render_report_html`.

    Raises:
        ValueError: the folder lacks report.json, trajectory.csv or plan.npz.
    """
    target = Path(plan_dir) / REPORT_FILE
    write_atomic(target, render_report_html(plan_dir, folder_name=folder_name))
    return target
