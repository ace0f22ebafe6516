"""``offline-prog place CELL.yaml --out DIR``: where the tool should stand and how the
gripper should hold the part (the paper's outlook), one named stage per line.

1. ``load``: the cell and its ``place:`` block checked (bad input: one line, exit 2).
2. ``engine``: a Dask LocalCluster (one worker per core), the cluster at
   ``--scheduler``, or this process (``--workers 0``); the cell sent to it once.
3. ``search``: the grid screen and CMA-ES on the planning pipeline
   (:mod:`~offline_prog.placement.search`).
4. ``outputs``: placement.json, placed.yaml, best_preview.html and placement.html,
   written into a fresh folder that replaces ``--out`` only when all are written.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from offline_prog.atomic import staged_folder, write_manifest
from offline_prog.config.cell import load_cell
from offline_prog.config.checks import check_cell
from offline_prog.errors import InputError, PlanFailedError
from offline_prog.placement.context import context
from offline_prog.placement.engine import DaskEngine, SerialEngine
from offline_prog.placement.evaluate import plan_candidate
from offline_prog.placement.outputs import placed_text, placement_json, write_json
from offline_prog.placement.payload import cell_payload
from offline_prog.placement.search import search
from offline_prog.placement.search_map import render_placement_html
from offline_prog.placement.space import Candidate, check_place
from offline_prog.results.plan_folder import check_out_dir
from offline_prog.robot.model import ROBOTS_DIR

NAMES = ("placement.json", "placed.yaml", "placement.html", "best_preview.html")


def place_cell(
    cell_file: Path,
    out_dir: Path,
    *,
    budget: int | None = None,
    seed: int | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[str, int, int], None] = lambda stage, done, total: None,
) -> dict:
    """Search the placement of ``cell_file`` and write the placement folder.

    Args:
        budget, seed: override ``place.budget`` / ``place.seed``.
        workers: LocalCluster workers (None: one per core; 0: this process, no Dask).
        scheduler: a Dask scheduler address (an existing cluster).
        progress: called with (stage, done, total) as candidates finish.

    Returns:
        placement.json's content.

    Raises:
        InputError: bad input, an unreachable scheduler, a bad --out (exit 2).
    """
    cell_file, out_dir = Path(cell_file), Path(out_dir)
    check_out_dir(out_dir)
    cell = load_cell(cell_file)
    check_cell(cell_file, cell, ROBOTS_DIR)
    place, space = check_place(cell_file, cell, budget=budget, seed=seed)
    payload = cell_payload(cell_file, cell)
    started = time.perf_counter()
    if workers == 0 and not scheduler:
        engine = SerialEngine(payload)
    else:
        engine = DaskEngine(payload, workers=workers, scheduler=scheduler)
    try:
        totals = {"screen": len(space.grid(place.screen_points)), "plan": place.budget}
        done = {"screen": 0, "plan": 0}

        def run(stage: str, candidates: list[Candidate]):
            def advance(n: int) -> None:
                done[stage] += n
                progress(stage, done[stage], totals[stage])

            return engine.map(stage, candidates, advance)

        result = search(space, place, space.baseline, run)
    finally:
        engine.close()
    wall = time.perf_counter() - started
    evaluated = len(result.evaluated)
    engine_info = {
        "scheduler": engine.scheduler,
        "workers": engine.workers,
        "candidates_evaluated": evaluated,
        "screened": len(result.screened),
        "wall_time_s": wall,
        "search_s": result.wall_s,
        "candidates_per_s": evaluated / result.wall_s if result.wall_s > 0 else None,
        "evaluation_s_mean": sum(e.seconds for e in result.evaluated) / evaluated,
    }
    data = placement_json(result, space, place, engine_info)
    progress("outputs", 0, 1)
    ctx = context(payload)
    with staged_folder(out_dir) as folder:
        (folder / "placed.yaml").write_text(placed_text(cell_file, ctx, result.best, out_dir))
        preview = None
        if result.best.feasible:
            from offline_prog.plan import JobPlan
            from offline_prog.viz.job_preview import write_job_preview_html
            from offline_prog.viz.preview import write_preview_html

            try:
                plan = plan_candidate(ctx, result.best.candidate)
            except (PlanFailedError, InputError):  # evaluated feasible: cannot happen
                plan = None
            if plan is not None:
                write = write_job_preview_html if isinstance(plan, JobPlan) else write_preview_html
                write(plan, folder / "best_preview.html")
                preview = "best_preview.html"
        write_json(folder / "placement.json", data)
        (folder / "placement.html").write_text(render_placement_html(result, data, preview))
        names = sorted(p.name for p in folder.iterdir())
        write_manifest(folder, {"plan": names})
    progress("outputs", 1, 1)
    return data
