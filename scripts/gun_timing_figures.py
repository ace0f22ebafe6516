"""Issue 37's gun-timing figures: the bead on a closed seam with the valve's response
times and an overlap, as the plan predicts it and as the programs set it.

Plans the sealing demo (KR 16, a closed border, bead 12 mm² ± 5 %, lag 0.08 s) with
``on``/``off`` switches carrying ``delay_s`` and ``overlap_mm: 5``, and prints:

- the share of the gun-on (valve-open) length within ±5 % of the target area and the
  worst gun-on row, with and without the first/last ``RAMP_MM`` of the seam (the seam
  runs flying, ``path.entry``; ``scripts/flying_entry_figures.py`` compares it with
  ``entry: rest`` on every demo cell);
- the overlap: how far past the seam's start the valve closes, and whether the valve is
  open over the whole closed contour (no gap);
- the last 5 mm before the valve closes: the bead there (the cut-off is no longer led).

Run: ``PYTHONPATH=. python scripts/gun_timing_figures.py [--out DIR]``
"""

from __future__ import annotations

import argparse
import re
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
CELL = REPO / "cells" / "seal_plate_kr16.yaml"
OVERLAP_MM = 5.0
ON_DELAY_S, OFF_DELAY_S = 0.04, 0.03
RAMP_MM = 10.0  # excluded at both ends for the "without the rest start" figure
IO = (
    "  process_io:\n"
    f"    on:  {{digital_output: 1, lead_mm: 0, delay_s: {ON_DELAY_S}}}\n"
    f"    off: {{digital_output: 1, lead_mm: 0, delay_s: {OFF_DELAY_S}}}\n"
    "    flow: {analog_output: 1, min: 0.0, max: 10.0}\n"
)


def cell_text() -> str:
    text = CELL.read_text(encoding="utf-8").replace(": data/", f": {REPO}/cells/data/")
    text = re.sub(r"  process_io:\n    flow: \{[^}]*\}\n", IO, text)
    return text.replace("  closed: true\n", f"  closed: true\n  overlap_mm: {OVERLAP_MM}\n")


def figures(job) -> dict:
    s, q = job.samples, job.quality
    process = next(g for g in s.segments if g.kind == "process")
    rows = np.arange(process.start, process.stop)
    path = s.path_m[rows]
    valve = job.io.valve[rows]
    column = q.column[rows]
    scale = q.model.unit_scale  # the column is in the report's unit (mm²)
    low, high = (b * scale for b in q.model.band)
    target = q.model.target * scale
    w = np.gradient(path)
    length = path[-1]  # L + overlap
    closed_length = length - OVERLAP_MM * 1e-3
    off = next(e for e in job.io.switches if not e.state)
    on = next(e for e in job.io.switches if e.state)
    out = {}
    for name, keep in (
        ("whole seam", valve),
        (
            f"without the first/last {RAMP_MM:g} mm",
            valve & (path > RAMP_MM * 1e-3) & (path < length - RAMP_MM * 1e-3),
        ),
        ("last 5 mm before the valve closes", valve & (path > off.path_m - 5e-3)),
    ):
        finite = keep & np.isfinite(column)
        ok = finite & (column >= low) & (column <= high)
        deviation = np.abs(column[finite] / target - 1.0)
        worst = int(np.argmax(deviation))
        out[name] = (
            float((w * ok).sum() / (w * keep).sum()),
            float(deviation[worst] * np.sign(column[finite][worst] / target - 1.0)),
            float(path[finite][worst] * 1e3),
        )
    gap = not (on.path_m <= 1e-9 and off.path_m >= closed_length - 1e-9)
    return {
        "shares": out,
        "overlap_mm": (off.path_m - closed_length) * 1e3,
        "gap": gap,
        "set_ahead_ms": ((on.t_s, off.t_s), (on.set_path_m * 1e3, off.set_path_m * 1e3)),
        "cycle_s": float(s.t[-1] - s.t[0]),
    }


def main() -> None:
    from offline_prog.plan import plan_job

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    work = args.out or Path(tempfile.mkdtemp())
    work.mkdir(parents=True, exist_ok=True)
    cell = work / "seal_overlap.yaml"
    cell.write_text(cell_text(), encoding="utf-8")
    job = plan_job(cell)
    assert job.feasible, job.failure
    f = figures(job)
    print(f"cell: {CELL.name} + on/off delay {ON_DELAY_S}/{OFF_DELAY_S} s, overlap {OVERLAP_MM} mm")
    for name, (share, worst, at) in f["shares"].items():
        print(
            f"  {name:38s} within ±5 %: {share * 100:6.2f} %  "
            f"worst {worst * 100:+7.2f} % at {at:.1f} mm"
        )
    print(
        f"  overlap past the start: {f['overlap_mm']:.3f} mm (asked {OVERLAP_MM}); gap: {f['gap']}"
    )
    (t_on, t_off), (p_on, p_off) = f["set_ahead_ms"]
    print(
        f"  gun set on at {p_on:.2f} mm (t {t_on:.3f} s), off at {p_off:.2f} mm (t {t_off:.3f} s)"
    )
    print(f"  cycle {f['cycle_s']:.2f} s")


if __name__ == "__main__":
    main()
