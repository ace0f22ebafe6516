"""Issue 25's table: interactive speed, each figure with the import floor of the same run.

    python scripts/bench_table.py [--runs 3] [--big-runs 1] [--big-seams 30]
        [--candidates 5] [--cells STEM ...]    (or: python scripts/bench.py --only table)

Whole commands are fresh processes as a user runs them (stdout piped: no progress
display; the package byte-compiled first, as the README's install leaves it), median
of ``--runs``; the 30-seam job (scripts/support/many_seams.py, order auto)
median of ``--big-runs``. The import floor is the median wall time of
``python -c "import pydrake.all"`` measured between the other figures, so each ratio
holds on a noisy machine. The placement candidate is the seal job's placement demo
(cells/placement/seal_job_far_kr16.yaml) through ``place``'s own serial engine, after
the cell is loaded (as a worker runs it), median over candidates, and the feasible
ones' rate on ``place``'s default engine (two Dask workers on this machine); the
session re-plan is a tool-pose change (X_IT x ± 5 mm, a fresh value each time) on every
demo cell.
"""

from __future__ import annotations

import argparse
import compileall
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # this checkout's package for the in-process figures
    sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent / "support"))  # many_seams
CELLS = ROOT / "cells"
PLACE_JOB = CELLS / "placement" / "seal_job_far_kr16.yaml"
CANDIDATES = 5  # seeded placement candidates
GOALS_S = {
    "plan seal_plate_kr16": 1.5,
    "plan seal_job_kr16 (4 seams)": 3.0,
    "plan 30-seam job": 15.0,
    "place: one feasible job candidate": 1.0,
    "session re-plan, tool pose (slowest cell)": 0.3,
}


def _wall(command: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(command, cwd=ROOT, check=False, capture_output=True)
    return time.perf_counter() - start


def import_floor(runs: int) -> float:
    """Median wall time [s] of ``python -c "import pydrake.all"``."""
    return statistics.median(
        _wall([sys.executable, "-c", "import pydrake.all"]) for _ in range(runs)
    )


def plan_command(cell: Path, runs: int) -> float:
    """Median wall time [s] of ``offline-prog plan CELL --out TMP``."""
    with tempfile.TemporaryDirectory() as out:
        command = [sys.executable, "-m", "offline_prog", "plan", str(cell), "--out", out]
        return statistics.median(_wall(command) for _ in range(runs))


def many_seams_command(n: int, runs: int) -> float:
    from many_seams import many_seam_cell

    with tempfile.TemporaryDirectory() as folder:
        return plan_command(many_seam_cell(Path(folder), n), runs)


def place_batch(candidates: int = CANDIDATES):
    """(the place job's payload, ``candidates`` seeded candidates of its search space)."""
    from offline_prog.config.cell import load_cell
    from offline_prog.placement.payload import cell_payload
    from offline_prog.placement.space import check_place

    cell = load_cell(PLACE_JOB)
    _, space = check_place(PLACE_JOB, cell)
    rng = np.random.default_rng(0)
    batch = [space.candidate(x, 0) for x in rng.uniform(0.1, 0.9, (candidates, 4))]
    return cell_payload(PLACE_JOB, cell), batch


def place_candidate(candidates: int = CANDIDATES) -> float:
    """Median seconds of one feasible job candidate through place's serial engine (of
    ``candidates`` seeded ones; those the robot cannot reach fail in a fraction of it)."""
    from offline_prog.placement.engine import SerialEngine

    payload, batch = place_batch(candidates)
    engine = SerialEngine(payload)
    try:
        engine.map("screen", batch[:1])  # loads the cell, as a worker has
        seconds = []
        for candidate in batch:
            start = time.perf_counter()
            (evaluation,) = engine.map("plan", [candidate])
            if evaluation.feasible:  # an unreachable candidate stops early: not counted
                seconds.append(time.perf_counter() - start)
    finally:
        engine.close()
    return statistics.median(seconds) if seconds else float("nan")


def place_throughput(workers: int = 2, rounds: int = 5, candidates: int = CANDIDATES) -> float:
    """Seconds per feasible job candidate through ``place``'s default engine (a
    LocalCluster of one worker per core), after each worker has loaded the cell: the
    feasible ones of place_candidate's seeded candidates, ``rounds`` times over."""
    from offline_prog.placement.engine import DaskEngine

    payload, batch = place_batch(candidates)
    engine = DaskEngine(payload, workers=workers)
    try:
        feasible = [e.candidate for e in engine.map("plan", batch) if e.feasible]
        if not feasible:
            return float("nan")
        start = time.perf_counter()
        engine.map("plan", feasible * rounds)
        return (time.perf_counter() - start) / (len(feasible) * rounds)
    finally:
        engine.close()


def session_tool_pose(cell: Path, repeats: int) -> float:
    """Median seconds of a session re-plan after a tool-pose change."""
    from offline_prog.session.replan import Replanner
    from offline_prog.session.state import values, with_value

    planner = Replanner(cell)
    planner.plan(planner.initial)
    x = values(planner.initial)["X_IT.x"]
    seconds = []
    for step in ([5.0, -5.0] * repeats)[:repeats]:
        result = planner.plan(with_value(planner.initial, "X_IT.x", x + step))
        seconds.append(result.seconds)
    return statistics.median(seconds)


def bench_table(
    runs: int = 3,
    big_runs: int = 1,
    *,
    big_seams: int = 30,
    candidates: int = CANDIDATES,
    cells: list[Path] | None = None,
) -> None:
    """Print the table: ``runs`` of each figure, ``big_runs`` of the ``big_seams`` job,
    ``candidates`` seeded placement candidates, the session on ``cells`` (default: every
    demo cell)."""
    # Byte-compiled, as the README's install leaves it (a machine that sets
    # PYTHONDONTWRITEBYTECODE would else compile every module in every command).
    compiled = compileall.compile_dir(ROOT / "offline_prog", quiet=1)
    print(f"== issue 25: interactive speed (medians; floor = import pydrake.all, {runs} runs) ==")
    print(f"  the package byte-compiled as the README's install does: {bool(compiled)}")
    rows: list[tuple[str, float, float]] = []

    def row(name: str, seconds: float) -> None:
        floor = import_floor(runs)  # measured next to each figure
        rows.append((name, seconds, floor))
        goal = GOALS_S.get(name)
        verdict = (
            "" if goal is None else f"goal < {goal:g} s: {'holds' if seconds < goal else 'NOT met'}"
        )
        print(
            f"  {name:44s} {seconds:7.2f} s  {seconds / floor:6.1f}× floor"
            f" ({floor:.2f} s)  {verdict}"
        )

    row("plan seal_plate_kr16", plan_command(CELLS / "seal_plate_kr16.yaml", runs))
    row("plan seal_job_kr16 (4 seams)", plan_command(CELLS / "seal_job_kr16.yaml", runs))
    row(f"plan {big_seams}-seam job", many_seams_command(big_seams, big_runs))
    row("place: one feasible job candidate", place_candidate(candidates))
    row(
        "place: each feasible candidate, 2 workers",
        place_throughput(rounds=runs, candidates=candidates),
    )
    slowest = 0.0
    for cell in cells or sorted(CELLS.glob("*.yaml")):
        seconds = session_tool_pose(cell, runs)
        slowest = max(slowest, seconds)
        row(f"session re-plan, tool pose: {cell.stem}", seconds)
    row("session re-plan, tool pose (slowest cell)", slowest)
    print(f"  import floor, median of all: {statistics.median(r[2] for r in rows):.2f} s")


def add_table_flags(parser: argparse.ArgumentParser) -> None:
    """The table's sizes and cells (this script's flags; bench.py's too)."""
    parser.add_argument("--runs", type=int, default=3, help="runs of each figure (3)")
    parser.add_argument("--big-runs", type=int, default=1, help="runs of the big job (1)")
    parser.add_argument("--big-seams", type=int, default=30, help="seams of the big job (30)")
    parser.add_argument(
        "--candidates", type=int, default=CANDIDATES, help="seeded placement candidates (5)"
    )
    parser.add_argument(
        "--cells", nargs="+", metavar="STEM", help="demo cells by file stem (default: all)"
    )


def chosen_cells(parser: argparse.ArgumentParser, args) -> list[Path]:
    """The demo cells ``--cells`` names (default: every cell in cells/)."""
    if not args.cells:
        return sorted(CELLS.glob("*.yaml"))
    cells = [CELLS / f"{stem}.yaml" for stem in args.cells]
    missing = [str(c) for c in cells if not c.is_file()]
    if missing:
        parser.error(f"no such cell: {', '.join(missing)}")
    return cells


def table(args, cells: list[Path]) -> None:
    """:func:`bench_table` with the flags of :func:`add_table_flags`."""
    bench_table(
        args.runs, args.big_runs, big_seams=args.big_seams, candidates=args.candidates, cells=cells
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_table_flags(parser)
    args = parser.parse_args()
    table(args, chosen_cells(parser, args))


if __name__ == "__main__":
    main()
