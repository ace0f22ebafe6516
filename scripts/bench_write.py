"""Benchmark: writing the plan folder (everything after planning), per demo cell.

Run: ``python scripts/bench_write.py [CELL.yaml ...] [--runs 5] [--package=DIR]
[--baseline]`` (default: the demo cells in cells/). Each cell is planned once; then
``write_job_outputs`` writes its folder ``--runs`` times into a temporary folder and
its median wall time and CPU time (of this process: preview.html is drawn in a second
one) are printed, with the median CPU time of each part measured alone in the same
process (the report, the CSVs, the program data, the npz files, each program
format, report.html, and preview.html, which a second process writes beside the rest,
after trajectory.csv). ``--package=/work/main`` times that checkout's writers instead of
this one's: a before/after on the same machine at about the same time.

``--baseline`` also times the KRL point selection as it was before it was batched
(``process_points`` with one deviation per candidate segment and numpy call, kept in
scripts/support/selection_reference.py) against today's on each seam, and checks that both
select the same points with the same deviations.
"""

from __future__ import annotations

import argparse
import functools
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

# This checkout's package, or the one of --package (another checkout, e.g. the tree
# before a change, to compare on the same machine at the same time).
_PACKAGE = next((a.split("=", 1)[1] for a in sys.argv if a.startswith("--package=")), None)
sys.path.insert(0, _PACKAGE or str(Path(__file__).resolve().parents[1]))

from offline_prog.export.densify import densify  # noqa: E402
from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M  # noqa: E402
from offline_prog.export.formats import PROGRAMS_DIR, default_formats, export  # noqa: E402
from offline_prog.export.points import PointRule, process_points  # noqa: E402
from offline_prog.plan import plan_job  # noqa: E402
from offline_prog.results import job_folder  # noqa: E402
from offline_prog.results.job_report import job_report  # noqa: E402
from offline_prog.results.job_table import trajectory_csv  # noqa: E402
from offline_prog.results.program_data import job_program_data  # noqa: E402
from offline_prog.viz.job_preview import write_job_preview_html  # noqa: E402
from offline_prog.viz.job_report_html import write_job_report_html  # noqa: E402

CELLS = Path(__file__).resolve().parents[1] / "cells"
DEMO_CELLS = (
    "seal_plate_kr16.yaml",
    "seal_job_kr16.yaml",
    "cad_seal_kr16.yaml",
    "tape_cylinder_ur10e.yaml",
    "weld_seam_irb2400.yaml",
)


def median_time(runs: int, function, clock=time.process_time) -> float:
    """Median time [s] of ``runs`` calls by ``clock``: this process's CPU time by
    default (steadier than wall time on a machine shared with other work)."""
    times = []
    for _ in range(runs):
        start = clock()
        function()
        times.append(clock() - start)
    return float(np.median(times))


def parts(job, folder: Path, runs: int) -> dict[str, float]:
    """Median time [s] of each part of the folder, each measured alone."""
    summary = job_report(job)
    data = job_program_data(job, summary)
    out = {
        "report": median_time(runs, lambda: job_report(job)),
        "trajectory.csv": median_time(runs, lambda: trajectory_csv(job)),
        "program data": median_time(runs, lambda: job_program_data(job, summary)),
        "npz": median_time(runs, lambda: data.save(folder)),
    }
    if data.feasible:
        for fmt in default_formats(data.language):
            out[fmt] = median_time(runs, lambda fmt=fmt: export(data, fmt, folder / PROGRAMS_DIR))
    plan_dir = folder / "plan"
    job_folder.write_job_outputs(job, plan_dir)  # report.html's inputs
    out["report.html"] = median_time(
        runs, lambda: write_job_report_html(plan_dir, folder_name=plan_dir.name)
    )
    out["preview.html (child)"] = median_time(
        runs, lambda: write_job_preview_html(job, folder / "preview.html")
    )
    return out


def baseline(job, summary: dict, runs: int) -> None:
    """The KRL point selection of every seam, before and after, and whether they agree."""
    # The point selection as it was (one segment per numpy call), kept for the tests too.
    sys.path.insert(0, str(Path(__file__).resolve().parent / "support"))
    from selection_reference import reference_process_points

    data = job_program_data(job, summary)
    for style in ("external_tcp", "flange"):
        old = new = 0.0
        same = True
        for seam in data.seams:
            dense = densify(seam, DEFAULT_CHORD_TOL_M, DEFAULT_ANGLE_TOL_RAD)
            tol = dense.selection_tolerances(DEFAULT_CHORD_TOL_M, DEFAULT_ANGLE_TOL_RAD)
            args = (dense.data, style, *tol, "X_TP")
            rule = PointRule(style)
            new_args = (dense.data, rule, *tol)
            old += median_time(runs, lambda args=args: reference_process_points(*args))
            new += median_time(runs, lambda args=new_args: process_points(*args))
            a, b = reference_process_points(*args), process_points(*new_args)
            same &= np.array_equal(a[0], b[0]) and a[1:] == b[1:]
        print(
            f"    KRL point selection ({style}): before {old * 1e3:.0f} ms, "
            f"now {new * 1e3:.0f} ms, same points and deviations: {same}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cells", nargs="*", type=Path, help="cell files (default: the demos)")
    parser.add_argument("--runs", type=int, default=5, help="writes of each folder (5)")
    parser.add_argument(
        "--baseline", action="store_true", help="also the KRL point selection before batching"
    )
    parser.add_argument("--package", help="=DIR: the checkout whose offline_prog to time")
    args = parser.parse_args()
    cells = args.cells or [CELLS / name for name in DEMO_CELLS]
    print(f"== writing the plan folder (median of {args.runs}; parts: CPU time) ==")
    for cell in cells:
        job = plan_job(cell)
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "out"
            write = functools.partial(job_folder.write_job_outputs, job, out)
            wall = median_time(args.runs, write, time.perf_counter)
            cpu = median_time(args.runs, write)
            each = parts(job, Path(tmp) / "parts", args.runs)
        rows = len(job.samples.t)
        print(
            f"{cell.name}: {wall * 1e3:.0f} ms wall, {cpu * 1e3:.0f} ms CPU in this process "
            f"({rows} rows, {len(job.chosen)} seams)"
        )
        print("    " + ", ".join(f"{k} {v * 1e3:.0f} ms" for k, v in each.items()))
        if args.baseline:
            baseline(job, job_report(job), args.runs)


if __name__ == "__main__":
    main()
