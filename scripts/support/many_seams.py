"""Jobs of any size, generated: n short seams on the demo plate of
cells/seal_job_kr16.yaml (KUKA KR 16-2, fixed nozzle, guard post), within reach.

Seams on a grid over the plate's underside (340 × 250 mm inside the border), every
third a closed circle, the others straight stripes along x; each may run either way
(``direction: auto``, so the order search chooses direction and branch too). For the
tests and scripts/bench_job_size.py; no hand-written 100-seam files.

The seams keep clear of the gripper's suction cups on the plate's top face, as the demo's
own seams do: under a cup the nozzle tip is the plate's thickness (5 mm) from the cup, no
more than ``motion.clearance``, so such a seam collides in every tool rotation and branch
(its collision avoidance runs every attempt in vain and the job fails). A grid cell whose
seam would pass within CUP_MARGIN_MM of a cup's footprint is left out and the grid made
finer until n seams fit.
"""

from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
PLATE_MM = (340.0, 250.0)  # the region the seams share, centred on P
CUP_MARGIN_MM = 10.0  # a seam's nearest approach to a cup's footprint (tip radius 2 mm)


def many_seam_cell(folder: Path, n: int) -> Path:
    """Write ``job_<n>_seams.yaml`` in ``folder`` (the demo job's cell with n seams)."""
    file = REPO / "cells" / "seal_job_kr16.yaml"
    text = file.read_text(encoding="utf-8")
    head, tail = text[: text.index("\nseams:") + 1], text[text.index("\njob:") + 1 :]
    cups = _cup_footprints(file)
    for m in range(n, 4 * n + 1):  # the coarsest grid that holds n seams clear of the cups
        seams = [seam for j in range(m) if (seam := _grid_seam(j, m, cups)) is not None][:n]
        if len(seams) == n:
            break
    lines = ["seams:"]
    common = "units: mm, normal: [0, 0, 1], direction: auto"
    for k, shape in enumerate(seams):
        lines.append(f"  - {{name: s{k}, analytic: {shape}, {common}}}")
    out = Path(folder) / f"job_{n}_seams.yaml"
    out.write_text(head + "\n".join(lines) + "\n" + tail, encoding="utf-8")
    return out


def _grid_seam(j: int, m: int, cups: list[tuple[np.ndarray, float]]) -> str | None:
    """The analytic shape of grid cell j of m (a circle every third cell, else a stripe
    along x), or None where it passes within CUP_MARGIN_MM of a cup."""
    width, height = PLATE_MM
    columns = max(1, round((m * width / height) ** 0.5))
    rows = -(-m // columns)
    pitch_x, pitch_y = width / columns, height / rows
    row, column = divmod(j, columns)
    x, y = -width / 2 + pitch_x * (column + 0.5), -height / 2 + pitch_y * (row + 0.5)
    centre = np.array([x, y])
    if j % 3 == 2:
        radius = 0.3 * min(pitch_x, pitch_y)
        gaps = [abs(np.linalg.norm(c - centre) - radius) - r for c, r in cups]
        shape = f"{{kind: arc, center: [{x:.1f}, {y:.1f}, 0], radius: {radius:.1f}, "
        shape += "start_deg: 0, end_deg: 360}, closed: true"
    else:
        half = 0.3 * pitch_x
        gaps = [np.hypot(max(abs(c[0] - x) - half, 0.0), c[1] - y) - r for c, r in cups]
        shape = f"{{kind: line, start: [{x - half:.1f}, {y:.1f}, 0], "
        shape += f"end: [{x + half:.1f}, {y:.1f}, 0]}}"
    return None if min(gaps, default=np.inf) < CUP_MARGIN_MM else shape


def _cup_footprints(file: Path) -> list[tuple[np.ndarray, float]]:
    """[(centre (2,) in P's xy [mm], radius [mm])] of the gripper's cylinders that reach
    within the clearance of the plate's underside (the cups on its top face)."""
    from offline_prog.config.cell import load_cell, transform

    cell = load_cell(file)
    X_PE = transform(cell.part.X_PE)
    reach_m = cell.motion.clearance + 1e-3
    cups = []
    for shape in cell.gripper.geometry if cell.gripper else []:
        if shape.shape != "cylinder":
            continue
        X_PS = X_PE @ transform(shape.pose)  # S: the cylinder, its axis along z
        half_m = 0.5e-3 * shape.length_mm
        ends_P = [X_PS.multiply(np.array([0.0, 0.0, z])) for z in (-half_m, half_m)]
        if min(p[2] for p in ends_P) <= reach_m:
            cups.append((1e3 * X_PS.translation()[:2], shape.radius_mm))
    return cups
