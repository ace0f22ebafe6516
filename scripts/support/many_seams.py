"""Jobs of any size, generated: n short seams on the demo plate of
cells/seal_job_kr16.yaml (KUKA KR 16-2, fixed nozzle, guard post), within reach.

Seams on a grid over the plate's underside (340 × 250 mm inside the border), every
third a closed circle, the others straight stripes along x; each may run either way
(``direction: auto``, so the order search chooses direction and branch too). For the
tests and scripts/bench_job_size.py; no hand-written 100-seam files.
"""

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
PLATE_MM = (340.0, 250.0)  # the region the seams share, centred on P


def many_seam_cell(folder: Path, n: int) -> Path:
    """Write ``job_<n>_seams.yaml`` in ``folder`` (the demo job's cell with n seams)."""
    text = (REPO / "cells" / "seal_job_kr16.yaml").read_text()
    head, tail = text[: text.index("\nseams:") + 1], text[text.index("\njob:") + 1 :]
    width, height = PLATE_MM
    columns = max(1, round((n * width / height) ** 0.5))
    rows = -(-n // columns)
    pitch_x, pitch_y = width / columns, height / rows
    seams = ["seams:"]
    for k in range(n):
        row, column = divmod(k, columns)
        x, y = -width / 2 + pitch_x * (column + 0.5), -height / 2 + pitch_y * (row + 0.5)
        common = "units: mm, normal: [0, 0, 1], direction: auto"
        if k % 3 == 2:
            radius = 0.3 * min(pitch_x, pitch_y)
            centre = f"[{x:.1f}, {y:.1f}, 0]"
            shape = f"{{kind: arc, center: {centre}, radius: {radius:.1f}, start_deg: 0, "
            shape += "end_deg: 360}, closed: true"
        else:
            half = 0.3 * pitch_x
            start, end = f"[{x - half:.1f}, {y:.1f}, 0]", f"[{x + half:.1f}, {y:.1f}, 0]"
            shape = f"{{kind: line, start: {start}, end: {end}}}"
        seams.append(f"  - {{name: s{k}, analytic: {shape}, {common}}}")
    file = Path(folder) / f"job_{n}_seams.yaml"
    file.write_text(head + "\n".join(seams) + "\n" + tail)
    return file
