"""The placement search in two stages: every candidate screened cheaply and soundly, a
few planned in full (issue 40).

1. ``screen``: a regular grid over the ranges, every grasp (``SearchSpace.grid``:
   the seed shifts it within its cells),
   each candidate by ``placement.screen`` (~30 ms a seam): ruled out where no tool
   turn and branch the planner may take reaches the path or keeps it inside the
   joint limits, or its stand cannot stand; else its cycle time's lower bound and a
   steady-speed estimate.
2. ``rank``: the best RANK_FACTOR × budget by that estimate again, by the cheaper law
   (TOPP-RA on the planner's variant) and a coarse collision look (the fixed layout
   in contact rules a candidate out; a first variant below the clearance ranks it
   after those that are clear).
3. ``plan``: the cell as given and the best POPULATION − 1 by the cheaper law through
   the planning pipeline, then the next ones in batches of POPULATION, best first,
   branch and bound: a candidate whose lower bound cannot beat the best plan so far
   (its cycle time, when its quality share cannot be beaten either) is not planned;
   until ``place.budget`` plans are made or no candidate is left.

Every screened candidate ends with its fate (:data:`FATES`), which placement.json
states. Batches are fixed by the budget and POPULATION, never by the number of
workers, and results come back in batch order: the same seed gives the same placement
on one core or on a cluster.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable

from offline_prog.config.cell import PlaceConfig
from offline_prog.placement.objective import (
    CYCLE_RESOLUTION_S,
    QUALITY_RESOLUTION,
    Evaluation,
)
from offline_prog.placement.space import Candidate, SearchSpace

POPULATION = 8  # candidates per batch of plans
RANK_FACTOR = 3  # the cheaper law ranks this many times the budget
# What became of a screened candidate (placement.json's ``screening``).
FATES = {
    "planned": "planned in full",
    "reach": "screened out: no tool turn and branch reaches the path",
    "joint_limit": "screened out: no tool turn and branch keeps the joint limits",
    "stand": "screened out: its stand would be too long or too short",
    "collision": "screened out: the fixed layout collides (robot base, tool, obstacles)",
    "bound": "not planned: its lower bound cannot beat the best plan",
    "rank": "not planned: outside the budget's best by the cheaper law",
    "screen_rank": "not ranked: outside the best by the screen's estimate",
}


@dataclasses.dataclass
class Placement:
    """What the search found.

    Attributes:
        best: the best evaluation (lexicographic objective).
        baseline: the cell as given.
        evaluated: every full evaluation, in order (baseline first).
        screened: every screened grid point (its latest stage: "rank" where ranked).
        fates: each screened candidate's fate (a :data:`FATES` key), in that order.
        wall_s: the search's wall time [s] (from the first evaluation).
    """

    best: Evaluation
    baseline: Evaluation
    evaluated: list[Evaluation]
    screened: list[Evaluation]
    fates: list[str]
    wall_s: float


def _estimate_key(e: Evaluation) -> tuple:
    """Screen or rank order: feasible first (clear of collisions before not), the
    closest to feasible, the shortest estimate."""
    estimate = e.cycle_time_s if math.isfinite(e.cycle_time_s) else math.inf
    return (e.tier, e.collides, e.violation, estimate)


def cannot_win(e: Evaluation, best: Evaluation) -> bool:
    """Branch and bound: no plan of ``e`` can beat ``best`` (a feasible plan). Its
    quality share is at most 1, so only a best plan with the whole share within the
    band prunes; then a lower bound a resolution step above the best cycle prunes."""
    if not best.feasible:
        return False
    share = best.quality_share if math.isfinite(best.quality_share) else 1.0
    if round(share / QUALITY_RESOLUTION) < round(1.0 / QUALITY_RESOLUTION):
        return False
    return e.bound_s >= best.cycle_time_s + CYCLE_RESOLUTION_S


def search(
    space: SearchSpace,
    place: PlaceConfig,
    baseline: Candidate,
    run: Callable[[str, list[Candidate]], list[Evaluation]],
) -> Placement:
    """Screen the grid, rank its best, plan at most ``place.budget`` candidates.

    Args:
        space: the search space; place: the checked ``place:`` block.
        baseline: the cell's own placement.
        run: evaluates a batch with a stage ("screen" | "rank" | "plan"), in order.
    """
    start = time.perf_counter()
    base_screen, *screened = run("screen", [baseline, *space.grid(place.screen_points, place.seed)])
    fates = [e.screened_out for e in screened]
    open_ = sorted(
        (i for i, e in enumerate(screened) if not e.screened_out),
        key=lambda i: _estimate_key(screened[i]),
    )
    chosen, rest = open_[: RANK_FACTOR * place.budget], open_[RANK_FACTOR * place.budget :]
    for i in rest:
        fates[i] = "screen_rank"
    for i, e in zip(chosen, run("rank", [screened[i].candidate for i in chosen]), strict=True):
        screened[i], fates[i] = e, e.screened_out
    order = sorted((i for i in chosen if not fates[i]), key=lambda i: _estimate_key(screened[i]))
    evaluated: list[Evaluation] = []
    batch_size = POPULATION - 1  # the first batch: the cell as given besides
    while order and len(evaluated) < place.budget:
        best = min(evaluated, key=Evaluation.key) if evaluated else None
        batch = []
        room = min(batch_size, place.budget - len(evaluated) - (0 if evaluated else 1))
        while order and len(batch) < room:
            i = order.pop(0)
            if best is not None and cannot_win(screened[i], best):
                fates[i] = "bound"
                continue
            batch.append(i)
            fates[i] = "planned"
        first = [] if evaluated else [base_screen]
        batch_screens = first + [screened[i] for i in batch]
        if batch_screens:
            planned = run("plan", [e.candidate for e in batch_screens])
            evaluated += [
                dataclasses.replace(e, bound_s=s.bound_s)
                for e, s in zip(planned, batch_screens, strict=True)
            ]
        batch_size = POPULATION
    if not evaluated:
        evaluated = [dataclasses.replace(run("plan", [baseline])[0], bound_s=base_screen.bound_s)]
    best = min(evaluated, key=Evaluation.key)
    for i in order:
        fates[i] = "bound" if cannot_win(screened[i], best) else "rank"
    return Placement(best, evaluated[0], evaluated, screened, fates, time.perf_counter() - start)
