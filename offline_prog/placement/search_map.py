"""placement.html: a top view of the search, the top-k table and the best plan.

The map is an SVG of the tool positions p_IT in the x–y plane of I [mm]: screened
grid points small (grey: the path IK can follow the path, red: it cannot), evaluated
candidates as circles coloured by cycle time (feasible) or red with the reason as
tooltip, the cell as given as a square and the best as a star. The best placement's
animated MeshCat scene (best_preview.html) is embedded below it.
"""

from __future__ import annotations

import html
import math

from offline_prog.placement.objective import Evaluation
from offline_prog.placement.search import Placement

SIZE, PAD = 560, 50  # SVG size and margin [px]
# Cycle-time colour scale: fastest to slowest feasible candidate (viridis ends).
FAST, SLOW = (68, 1, 84), (253, 231, 37)
# Infeasible candidates by failure kind (errors.Failure values, "refused").
FAILURE_COLORS = {
    "out_of_reach": "#d62728",
    "joint_limit": "#ff7f0e",
    "joint_rate_limit": "#bcbd22",
    "singularity": "#9467bd",
    "collision": "#8c564b",
    "refused": "#7f7f7f",
}


def _colour(t: float, low: float, high: float) -> str:
    u = 0.0 if high <= low else (t - low) / (high - low)
    r, g, b = (round(a + u * (b - a)) for a, b in zip(FAST, SLOW, strict=True))
    return f"rgb({r},{g},{b})"


def _map_svg(result: Placement) -> str:
    points = [e.candidate.X_IT[0] for e in result.screened + result.evaluated]
    xs = [1e3 * p[0] for p in points]
    ys = [1e3 * p[1] for p in points]
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    span = max(x1 - x0, y1 - y0, 1.0)
    scale = (SIZE - 2 * PAD) / span

    def at(e: Evaluation) -> tuple[float, float]:
        p = e.candidate.X_IT[0]
        return PAD + (1e3 * p[0] - x0) * scale, SIZE - PAD - (1e3 * p[1] - y0) * scale

    feasible = [e.cycle_time_s for e in result.evaluated if e.feasible]
    low, high = (min(feasible), max(feasible)) if feasible else (0.0, 1.0)
    items = []
    for e in result.screened:
        x, y = at(e)
        colour = "#bbb" if e.feasible else "#f3a0a0"
        items.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="2" fill="{colour}"/>')
    for e in result.evaluated[1:]:
        x, y = at(e)
        if e.feasible:
            tip = f"{e.cycle_time_s:.2f} s, margin {e.joint_limit_margin_deg:.1f}°"
            fill = _colour(e.cycle_time_s, low, high)
        else:
            tip, fill = e.reason, FAILURE_COLORS.get(e.failure, "#d62728")
        items.append(
            f'<circle cx="{x:.1f}" cy="{y:.1f}" r="5" fill="{fill}" stroke="#333" '
            f'stroke-width="0.5"><title>{html.escape(tip)}</title></circle>'
        )
    x, y = at(result.baseline)
    items.append(
        f'<rect x="{x - 6:.1f}" y="{y - 6:.1f}" width="12" height="12" fill="none" '
        'stroke="#000" stroke-width="2"><title>the cell as given</title></rect>'
    )
    x, y = at(result.best)
    star = " ".join(
        f"{x + r * math.sin(k * math.pi / 5):.1f},{y - r * math.cos(k * math.pi / 5):.1f}"
        for k, r in zip(range(10), [11, 4.5] * 5, strict=True)
    )
    items.append(
        f'<polygon points="{star}" fill="#ff7f0e" stroke="#000"><title>best</title></polygon>'
    )
    axes = (
        f'<text x="{SIZE / 2}" y="{SIZE - 12}" text-anchor="middle">x of I [mm] '
        f"{x0:.0f} … {x0 + span:.0f}</text>"
        f'<text x="14" y="{SIZE / 2}" transform="rotate(-90 14 {SIZE / 2})" '
        f'text-anchor="middle">y of I [mm] {y0:.0f} … {y0 + span:.0f}</text>'
    )
    return (
        f'<svg id="search-map" width="{SIZE}" height="{SIZE}" viewBox="0 0 {SIZE} {SIZE}" '
        f'xmlns="http://www.w3.org/2000/svg"><rect width="100%" height="100%" fill="#fff" '
        f'stroke="#ccc"/>{"".join(items)}{axes}</svg>'
    )


def _row(cells: list) -> str:
    return "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in cells) + "</tr>"


def render_placement_html(result: Placement, data: dict, preview: str | None) -> str:
    """The page, from the search result and placement.json's ``data``."""
    cut = data["cycle_time_cut"]
    best = data["best"]
    legend = ", ".join(
        f'<span style="color:{colour}">●</span> {kind.replace("_", " ")}'
        for kind, colour in FAILURE_COLORS.items()
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
                ", ".join(f"{v:.4f}" for v in c["X_IT"]["translation"]),
                ", ".join(f"{v:.2f}" for v in c["X_IT"]["rpy_deg"]),
                c["grasp"],
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
<p>{engine["candidates_evaluated"]} candidates through the planning pipeline and
{engine["screened"]} screened by the path IK in {engine["wall_time_s"]:.1f} s on
{engine["workers"]} worker(s) ({html.escape(engine["scheduler"])}).</p>
<h2>Tool positions (top view)</h2>
<p>Small dots: screened grid (grey: the path IK follows the path; red: it cannot).
Circles: evaluated, feasible from dark (fast) to yellow (slow); infeasible by why
({legend}; hover for the whole reason).
Square: the cell as given. Star: best.</p>
{_map_svg(result)}
<h2>Best candidates</h2>
<table id="candidates"><tr>{"".join(f"<th>{h}</th>" for h in header)}</tr>{"".join(rows)}</table>
{frame}
</body></html>
"""
