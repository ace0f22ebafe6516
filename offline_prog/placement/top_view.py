"""placement.html's top view: the tool positions p_IT in the x–y plane of I, drawn to
scale (one mm is as long in x as in y) with ticked axes in mm.

Drawn: the robot base (B's origin) and the reach of its wrist centre at the
shoulder's height (the arm stretched: ``path_ik.reach_excess``'s longest stretch plus
the shoulder's offset); every screened candidate as a dot in the colour of its fate
(screened out by reach, joint limits, stand or collision; not planned); every planned
one as a circle coloured by its cycle time on the colour scale drawn beside (feasible)
or in its failure's colour; the cell as given as a square, the best as a star, and the
best's stands (their footprint, turned with the tool).
"""

from __future__ import annotations

import dataclasses
import html
import math

import numpy as np

from offline_prog.placement.objective import Evaluation
from offline_prog.placement.search import Placement

WIDTH, HEIGHT, PAD, SCALE_W = 640, 560, 56, 70  # SVG size, margins, colour scale [px]
# Cycle-time colour scale: fastest to slowest planned candidate (viridis' stops).
VIRIDIS = ((68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37))
# Planned but infeasible, by failure kind (errors.Failure values, "stand", "refused").
FAILURE_COLORS = {
    "out_of_reach": "#d62728",
    "joint_limit": "#ff7f0e",
    "joint_rate_limit": "#bcbd22",
    "singularity": "#9467bd",
    "collision": "#8c564b",
    "stand": "#e377c2",
    "refused": "#7f7f7f",
}
# Screened candidates by fate (search.FATES).
FATE_COLORS = {
    "reach": "#f4b6b6",
    "joint_limit": "#ffd2a8",
    "stand": "#f6c6e6",
    "collision": "#d9c2b8",
    "bound": "#9ecae1",
    "rank": "#c8c8c8",
    "screen_rank": "#e4e4e4",
}


@dataclasses.dataclass(frozen=True)
class Layout:
    """What the map draws besides the candidates.

    Attributes:
        p_IB_mm: (2,) the robot base's origin in x, y of I [mm].
        reach_mm: the wrist centre's reach about the base's axis [mm].
        stands: [(name, (K, 2) footprint corners in x, y of I [mm])] of the best.
    """

    p_IB_mm: tuple[float, float]
    reach_mm: float
    stands: list[tuple[str, np.ndarray]]


def colour(t: float, low: float, high: float) -> str:
    """The colour of cycle time t [s] on the scale low … high (viridis)."""
    u = 0.0 if high <= low else min(1.0, max(0.0, (t - low) / (high - low)))
    x = u * (len(VIRIDIS) - 1)
    k = min(int(x), len(VIRIDIS) - 2)
    a, b = VIRIDIS[k], VIRIDIS[k + 1]
    r, g, bl = (round(p + (x - k) * (q - p)) for p, q in zip(a, b, strict=True))
    return f"rgb({r},{g},{bl})"


def _nice_step(span: float) -> float:
    """A tick step of 1, 2 or 5 × 10ⁿ giving about six ticks over span."""
    raw = span / 6.0
    base = 10.0 ** math.floor(math.log10(raw))
    return next(m * base for m in (1.0, 2.0, 5.0, 10.0) if m * base >= raw)


class _Frame:
    """Millimetres of I onto the SVG's pixels, equal scale in x and y (y up)."""

    def __init__(self, xs: list[float], ys: list[float]):
        x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
        plot_w, plot_h = WIDTH - 2 * PAD - SCALE_W, HEIGHT - 2 * PAD
        self.k = min(plot_w / max(x1 - x0, 1.0), plot_h / max(y1 - y0, 1.0))
        # Centred in the plot area.
        self.x0 = x0 - (plot_w / self.k - (x1 - x0)) / 2
        self.y0 = y0 - (plot_h / self.k - (y1 - y0)) / 2
        self.x1, self.y1 = self.x0 + plot_w / self.k, self.y0 + plot_h / self.k

    def __call__(self, x: float, y: float) -> tuple[float, float]:
        return PAD + (x - self.x0) * self.k, HEIGHT - PAD - (y - self.y0) * self.k


def _axes(at: _Frame) -> list[str]:
    items = []
    left, bottom = at(at.x0, at.y0)
    right, top = at(at.x1, at.y1)
    items.append(
        f'<rect x="{left:.1f}" y="{top:.1f}" width="{right - left:.1f}" '
        f'height="{bottom - top:.1f}" fill="none" stroke="#999"/>'
    )
    step = _nice_step(max(at.x1 - at.x0, at.y1 - at.y0))
    for value in np.arange(math.ceil(at.x0 / step) * step, at.x1 + 1e-9, step):
        x, _ = at(value, at.y0)
        items.append(
            f'<line x1="{x:.1f}" y1="{bottom:.1f}" x2="{x:.1f}" y2="{bottom + 5:.1f}" '
            f'stroke="#333"/><text class="tick" x="{x:.1f}" y="{bottom + 17:.1f}" '
            f'text-anchor="middle">{value:.0f}</text>'
        )
    for value in np.arange(math.ceil(at.y0 / step) * step, at.y1 + 1e-9, step):
        _, y = at(at.x0, value)
        items.append(
            f'<line x1="{left - 5:.1f}" y1="{y:.1f}" x2="{left:.1f}" y2="{y:.1f}" '
            f'stroke="#333"/><text class="tick" x="{left - 8:.1f}" y="{y + 4:.1f}" '
            f'text-anchor="end">{value:.0f}</text>'
        )
    middle_x, middle_y = (left + right) / 2, (top + bottom) / 2
    items.append(
        f'<text x="{middle_x:.1f}" y="{HEIGHT - 12}" text-anchor="middle">x of I [mm]</text>'
        f'<text x="14" y="{middle_y:.1f}" transform="rotate(-90 14 {middle_y:.1f})" '
        'text-anchor="middle">y of I [mm]</text>'
    )
    return items


def _scale(low: float, high: float) -> list[str]:
    """The cycle-time colour scale, fast at the bottom."""
    x, top, bottom = WIDTH - SCALE_W + 4, PAD, HEIGHT - PAD
    stops = "".join(
        f'<stop offset="{k / (len(VIRIDIS) - 1):.2f}" stop-color="rgb{c}"/>'
        for k, c in enumerate(VIRIDIS)
    )
    items = [
        f'<defs><linearGradient id="cycle" x1="0" y1="1" x2="0" y2="0">{stops}'
        "</linearGradient></defs>",
        f'<rect x="{x}" y="{top}" width="14" height="{bottom - top}" fill="url(#cycle)" '
        'stroke="#999"/>',
        f'<text class="tick" x="{x + 18}" y="{bottom}">{low:.2f} s</text>',
        f'<text class="tick" x="{x + 18}" y="{top + 10}">{high:.2f} s</text>',
        f'<text class="tick" x="{x - 2}" y="{top - 8}">cycle</text>',
    ]
    return items


def _star(x: float, y: float) -> str:
    return " ".join(
        f"{x + r * math.sin(k * math.pi / 5):.1f},{y - r * math.cos(k * math.pi / 5):.1f}"
        for k, r in zip(range(10), [11, 4.5] * 5, strict=True)
    )


def top_view_svg(result: Placement, layout: Layout) -> str:
    """The map (see the module)."""

    def mm(e: Evaluation) -> tuple[float, float]:
        p = e.candidate.X_IT[0]
        return 1e3 * p[0], 1e3 * p[1]

    points = [mm(e) for e in result.screened + result.evaluated]
    bx, by = layout.p_IB_mm
    xs = [p[0] for p in points] + [bx - layout.reach_mm, bx + layout.reach_mm]
    ys = [p[1] for p in points] + [by - layout.reach_mm, by + layout.reach_mm]
    for _, corners in layout.stands:
        xs += list(corners[:, 0])
        ys += list(corners[:, 1])
    at = _Frame(xs, ys)
    items = _axes(at)
    cx, cy = at(bx, by)
    items.append(
        f'<circle cx="{cx:.1f}" cy="{cy:.1f}" r="{layout.reach_mm * at.k:.1f}" fill="none" '
        'stroke="#555" stroke-dasharray="6 4"><title>the wrist centre\'s reach at the '
        "shoulder's height</title></circle>"
        f'<circle cx="{cx:.1f}" cy="{cy:.1f}" r="9" fill="#444"><title>robot base B</title>'
        f'</circle><text x="{cx + 12:.1f}" y="{cy + 4:.1f}">robot</text>'
    )
    for e, fate in zip(result.screened, result.fates, strict=True):
        if fate == "planned":
            continue
        x, y = at(*mm(e))
        tip = html.escape(e.reason or fate.replace("_", " "))
        items.append(
            f'<circle cx="{x:.1f}" cy="{y:.1f}" r="2.5" fill="{FATE_COLORS[fate]}">'
            f"<title>{tip}</title></circle>"
        )
    feasible = [e.cycle_time_s for e in result.evaluated if e.feasible]
    low, high = (min(feasible), max(feasible)) if feasible else (0.0, 1.0)
    for e in result.evaluated[1:]:
        x, y = at(*mm(e))
        if e.feasible:
            tip = f"{e.cycle_time_s:.2f} s, margin {e.joint_limit_margin_deg:.1f}°"
            fill = colour(e.cycle_time_s, low, high)
        else:
            tip, fill = e.reason, FAILURE_COLORS.get(e.failure, "#d62728")
        items.append(
            f'<circle cx="{x:.1f}" cy="{y:.1f}" r="5.5" fill="{fill}" stroke="#333" '
            f'stroke-width="0.5"><title>{html.escape(tip)}</title></circle>'
        )
    for name, corners in layout.stands:
        path = " ".join(f"{p[0]:.1f},{p[1]:.1f}" for p in (at(*c) for c in corners))
        items.append(
            f'<polygon points="{path}" fill="none" stroke="#e377c2" stroke-width="1.5">'
            f"<title>{html.escape(name)} (best placement)</title></polygon>"
        )
    x, y = at(*mm(result.baseline))
    items.append(
        f'<rect x="{x - 6:.1f}" y="{y - 6:.1f}" width="12" height="12" fill="none" '
        'stroke="#000" stroke-width="2"><title>the cell as given</title></rect>'
    )
    x, y = at(*mm(result.best))
    items.append(
        f'<polygon points="{_star(x, y)}" fill="#ff7f0e" stroke="#000"><title>best</title>'
        "</polygon>"
    )
    if feasible:
        items += _scale(low, high)
    return (
        f'<svg id="search-map" width="{WIDTH}" height="{HEIGHT}" '
        f'viewBox="0 0 {WIDTH} {HEIGHT}" xmlns="http://www.w3.org/2000/svg">'
        "<style>text{font:12px sans-serif}.tick{font-size:11px}</style>"
        f'<rect width="100%" height="100%" fill="#fff"/>{"".join(items)}</svg>'
    )
