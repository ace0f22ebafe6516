"""Placement in two stages against every candidate planned in full (issue 40's
acceptance), side by side, in one run.

Run: ``python scripts/place_two_stage.py [--screen-points 81] [--workers 2] [CELL ...]``
(default: the placement demos in cells/placement/). For each cell, on one Dask
LocalCluster (started and loaded before either is timed), with the cell's seed and
budget and the same grid of candidates (``--screen-points`` per grasp):

1. the two-stage search of ``offline-prog place`` (``placement.search``): the screen,
   the cheaper law's ranking, at most the budget planned in full, branch and bound;
2. every candidate of that grid (and the cell as given) planned in full.

Printed: each one's best objective (feasible, quality share within the band, cycle
time), wall time and CPU time (this process and the workers), the machine's load;
whether the two objectives are equal (the share and the cycle time each within its
resolution) and the two-stage search's share of the full one's wall time (the
acceptance: equal, at most a third).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's package

from offline_prog.config.cell import load_cell  # noqa: E402
from offline_prog.placement.context import keep, load_context  # noqa: E402
from offline_prog.placement.engine import DaskEngine  # noqa: E402
from offline_prog.placement.objective import (  # noqa: E402
    CYCLE_RESOLUTION_S,
    QUALITY_RESOLUTION,
    Evaluation,
)
from offline_prog.placement.payload import cell_payload  # noqa: E402
from offline_prog.placement.search import search  # noqa: E402
from offline_prog.placement.space import check_place  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DEMOS = sorted((ROOT / "cells" / "placement").glob("*.yaml"))


def same_objective(a: Evaluation, b: Evaluation) -> bool:
    """What the acceptance compares: both feasible or not; the quality share within the
    band and the cycle time each within its resolution of the other (the margins that
    break ties are left out)."""
    if a.feasible != b.feasible:
        return False
    if not a.feasible:
        return True
    share_a, share_b = (e.quality_share if math.isfinite(e.quality_share) else 1.0 for e in (a, b))
    return (
        abs(share_a - share_b) <= QUALITY_RESOLUTION
        and abs(a.cycle_time_s - b.cycle_time_s) <= CYCLE_RESOLUTION_S
    )


def cpu_s(engine: DaskEngine) -> float:
    """CPU seconds so far of this process and of every worker process [s]."""
    mine = os.times()
    workers = engine.client.run(lambda: sum(os.times()[:2]))
    return mine.user + mine.system + sum(workers.values())


def timed(engine: DaskEngine, work):
    start_wall, start_cpu = time.perf_counter(), cpu_s(engine)
    result = work()
    return result, time.perf_counter() - start_wall, cpu_s(engine) - start_cpu


def describe(e: Evaluation) -> str:
    if not e.feasible:
        return f"infeasible ({e.reason})"
    share = "" if math.isnan(e.quality_share) else f", {100 * e.quality_share:.1f} % in band"
    return f"{e.cycle_time_s:.3f} s{share}"


def compare(file: Path, screen_points: int, workers: int) -> bool:
    cell = load_cell(file)
    place, space = check_place(file, cell)
    place = dataclasses.replace(place, screen_points=screen_points)
    payload = cell_payload(file, cell)
    keep(payload, load_context(file))
    engine = DaskEngine(payload, workers=workers)
    try:
        two, two_wall, two_cpu = timed(
            engine, lambda: search(space, place, space.baseline, engine.map)
        )
        grid = [space.baseline, *space.grid(screen_points, place.seed)]
        every, full_wall, full_cpu = timed(engine, lambda: engine.map("plan", grid))
    finally:
        engine.close()
    best = min(every, key=Evaluation.key)
    same = same_objective(two.best, best)
    print(f"== {file.stem}: {len(grid)} candidates, budget {place.budget}, seed {place.seed}")
    print(
        f"  two stages:     {describe(two.best):<36} {two_wall:7.1f} s wall {two_cpu:7.1f} s CPU"
        f"  ({len(two.evaluated)} planned)"
    )
    print(
        f"  all in full:    {describe(best):<36} {full_wall:7.1f} s wall {full_cpu:7.1f} s CPU"
        f"  ({len(every)} planned)"
    )
    print(
        f"  objective equal: {'yes' if same else 'NO'}; two stages take "
        f"{two_wall / full_wall:.2f} of the wall time, {two_cpu / full_cpu:.2f} of the CPU"
    )
    return same and two_wall <= full_wall / 3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cells", nargs="*", type=Path, default=DEMOS)
    parser.add_argument("--screen-points", type=int, default=81, help="grid points per grasp")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    print(f"load average before: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    met = [compare(file, args.screen_points, args.workers) for file in args.cells]
    print(f"load average after: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(f"acceptance (equal, at most a third of the wall time): {sum(met)} of {len(met)} cells")


if __name__ == "__main__":
    main()
