"""placement.html: the top view of the search (``placement.top_view``), what the
screen did, the best distinct candidates and the best plan (its animated MeshCat
scene, best_preview.html, embedded below)."""

from __future__ import annotations

import html

from offline_prog.placement.search import FATES, Placement
from offline_prog.placement.top_view import FAILURE_COLORS, FATE_COLORS, Layout, top_view_svg


def _row(cells: list) -> str:
    return "<tr>" + "".join(f"<td>{html.escape(_text(c))}</td>" for c in cells) + "</tr>"


def _text(value) -> str:
    """A cell's text: yes / no for a boolean (not Python's True)."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    return str(value)


def render_placement_html(
    result: Placement, data: dict, preview: str | None, layout: Layout
) -> str:
    """The page, from the search result, placement.json's ``data`` and the layout."""
    cut = data["cycle_time_cut"]
    best = data["best"]
    legend = ", ".join(
        f'<span style="color:{colour}">●</span> {kind.replace("_", " ")}'
        for kind, colour in FAILURE_COLORS.items()
    )
    fates = data["screening"]["fates"]
    fate_legend = ", ".join(
        f'<span style="color:{FATE_COLORS[fate]}">●</span> {html.escape(FATES[fate])} '
        f"({fates[fate]})"
        for fate in FATE_COLORS
        if fates.get(fate)
    )
    summary = (
        f"best: {'feasible' if best['feasible'] else 'infeasible: ' + best['reason']}"
        + (f", cycle {best['cycle_time_s']:.2f} s" if best["cycle_time_s"] else "")
        + (
            f", {cut['percent']:.1f} % faster than the cell as given"
            if cut["percent"] is not None
            else ""
        )
    )
    header = [
        "#",
        "feasible",
        "cycle [s]",
        "limit margin [°]",
        "singularity [°]",
        "clearance [mm]",
        "lower bound [s]",
        "X_IT translation [m]",
        "X_IT rpy [°]",
        "grasp",
        "reason",
    ]

    def number(v, digits=2):
        return "" if v is None else f"{v:.{digits}f}"

    rows = [
        _row(
            [
                k + 1,
                c["feasible"],
                number(c["cycle_time_s"]),
                number(c["joint_limit_margin_deg"], 1),
                number(c["singularity_margin_deg"], 1),
                number(c["clearance_mm"], 1),
                number(c["lower_bound_s"]),
                ", ".join(f"{v:.4f}" for v in c["X_IT"]["translation"]),
                ", ".join(f"{v:.2f}" for v in c["X_IT"]["rpy_deg"]),
                "as given" if c["grasp"] < 0 else c["grasp"] + 1,
                c["reason"],
            ]
        )
        for k, c in enumerate(data["candidates"])
    ]
    engine = data["engine"]
    frame = (
        f'<h2>Best placement</h2><iframe src="{html.escape(preview)}" width="900" height="560" '
        'style="border:1px solid #ccc"></iframe>'
        if preview
        else "<p>No feasible placement to show.</p>"
    )
    why = (
        f"<p>Why not more: {html.escape(cut['why_not_more'])}</p>"
        if cut.get("why_not_more")
        else ""
    )
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>Placement search</title>
<style>body{{font-family:sans-serif;margin:24px}}table{{border-collapse:collapse}}
td,th{{border:1px solid #ccc;padding:2px 6px;font-size:13px}}</style></head><body>
<h1>Placement search</h1>
<p id="summary">{html.escape(summary)}</p>{why}
<p>{engine["screened"]} candidates screened (every tool turn and branch by the analytic
IK, a lower bound of the cycle time), the best ranked by a cheaper law, and
{engine["candidates_evaluated"]} planned in full, in {engine["wall_time_s"]:.1f} s on
{engine["workers"]} worker(s) ({html.escape(engine["scheduler"])}).</p>
<h2>Tool positions (top view)</h2>
<p>Dots: screened candidates by what became of them ({fate_legend}).
Circles: planned in full, feasible coloured by cycle time on the scale at the right;
infeasible by why ({legend}; hover for the whole reason).
Square: the cell as given. Star: best, with its stand's footprint. Dashed: the reach of
the robot's wrist centre at its shoulder's height.</p>
{top_view_svg(result, layout)}
<h2>Best candidates (distinct)</h2>
<table id="candidates"><tr>{"".join(f"<th>{h}</th>" for h in header)}</tr>{"".join(rows)}</table>
{frame}
</body></html>
"""
