"""``offline-prog place CELL.yaml --out DIR``: where the tool should stand and how the
gripper should hold the part (the paper's outlook), one named stage per line.

1. ``load``: the cell and its ``place:`` block checked (bad input: one line, exit 2).
2. ``engine``: a Dask LocalCluster (one worker per core), the cluster at
   ``--scheduler``, or this process (``--workers 0``); the cell sent to it once.
3. ``search``: the grid screened, its best ranked by a cheaper law, the few that can
   win planned in full (:mod:`~offline_prog.placement.search`).
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
from offline_prog.placement.context import Context, keep, load_context
from offline_prog.placement.engine import DaskEngine, SerialEngine
from offline_prog.placement.evaluate import plan_candidate
from offline_prog.placement.objective import Evaluation
from offline_prog.placement.outputs import layout_of, placed_text, placement_json, write_json
from offline_prog.placement.payload import CellPayload, cell_payload
from offline_prog.placement.search import Placement, search
from offline_prog.placement.search_map import render_placement_html
from offline_prog.placement.space import Candidate, check_place
from offline_prog.results.plan_folder import check_out_dir
from offline_prog.robot.model import ROBOTS_DIR


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
    place, space, payload, ctx = load(cell_file, out_dir, budget, seed)
    started = time.perf_counter()
    engine = start_engine(payload, workers, scheduler)
    try:
        result = search(space, place, space.baseline, _runner(engine, place, progress))
    finally:
        engine.close()
    figures = engine_figures(engine, result, started)
    data = placement_json(result, space, place, figures, ctx)
    progress("outputs", 0, 1)
    write_folder(out_dir, cell_file, ctx, result, data)
    progress("outputs", 1, 1)
    return data


def load(cell_file: Path, out_dir: Path, budget: int | None, seed: int | None):
    """Stage ``load``: --out, the cell and its ``place:`` block checked; the cell loaded
    and fitted here first (its errors name the user's file, not a worker's copy); the
    payload for the workers.

    Returns:
        (PlaceConfig, SearchSpace, CellPayload, Context).
    """
    check_out_dir(out_dir)
    cell = load_cell(cell_file)
    check_cell(cell_file, cell, ROBOTS_DIR)
    place, space = check_place(cell_file, cell, budget=budget, seed=seed)
    ctx = load_context(cell_file)
    payload = cell_payload(cell_file, cell)
    keep(payload, ctx)
    return place, space, payload, ctx


def start_engine(payload: CellPayload, workers: int | None, scheduler: str | None):
    """Stage ``engine``: this process (``--workers 0``) or Dask."""
    if workers == 0 and not scheduler:
        return SerialEngine(payload)
    return DaskEngine(payload, workers=workers, scheduler=scheduler)


def _runner(engine, place, progress):
    """``search``'s ``run``: the engine's map, telling ``progress`` per stage (the
    screen's and the rank's totals are their batches'; the plans', the budget)."""
    done = {"screen": 0, "rank": 0, "plan": 0}

    def run(stage: str, candidates: list[Candidate]):
        total = place.budget if stage == "plan" else done[stage] + len(candidates)

        def advance(n: int) -> None:
            done[stage] += n
            progress(stage, done[stage], total)

        return engine.map(stage, candidates, advance)

    return run


def engine_figures(engine, result: Placement, started: float) -> dict:
    """placement.json's ``engine``."""
    evaluated = len(result.evaluated)
    return {
        "scheduler": engine.scheduler,
        "workers": engine.workers,
        "candidates_evaluated": evaluated,
        "screened": len(result.screened),
        "wall_time_s": time.perf_counter() - started,
        "search_s": result.wall_s,
        "candidates_per_s": evaluated / result.wall_s if result.wall_s > 0 else None,
        "evaluation_s_mean": sum(e.seconds for e in result.evaluated) / evaluated,
    }


def write_folder(out_dir: Path, cell_file: Path, ctx: Context, result: Placement, data: dict):
    """Stage ``outputs``: the folder, written aside and swapped in when complete."""
    with staged_folder(out_dir) as folder:
        (folder / "placed.yaml").write_text(
            placed_text(cell_file, ctx, result.best, out_dir), encoding="utf-8"
        )
        preview = None
        if result.best.feasible:
            write_best_preview(ctx, result.best, folder / "best_preview.html")
            preview = "best_preview.html"
        write_json(folder / "placement.json", data)
        (folder / "placement.html").write_text(
            render_placement_html(result, data, preview, layout_of(ctx, result.best)),
            encoding="utf-8",
        )
        write_manifest(folder, {"plan": sorted(p.name for p in folder.iterdir())})


def write_best_preview(ctx: Context, best: Evaluation, file: Path) -> None:
    """The best candidate planned again here, as an animated MeshCat page."""
    from offline_prog.viz.job_preview import write_job_preview_html

    plan = plan_candidate(ctx, best.candidate)  # evaluated feasible: plans again
    write_job_preview_html(plan, file)
