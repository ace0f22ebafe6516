"""The placement search: a grid screened by the analytic path IK, then CMA-ES (the
``cma`` package) on the full planning pipeline, for ``place.budget`` evaluations.

1. ``screen``: a regular grid over the ranges, every grasp, by the analytic path IK
   and a steady-speed cycle-time estimate (~10 ms each; no evaluation spent).
2. ``first``: the cell as given and the best POPULATION − 1 screened candidates
   through the pipeline (one batch).
3. ``cma``: CMA-ES over the unit box from the best candidate so far, its grasp fixed,
   in generations of POPULATION; each generation is ranked by the lexicographic
   objective (``Evaluation.key``: CMA-ES uses ranks only). When it converges it
   restarts from the best screened candidate not yet used, until the budget is spent.

Batches are fixed by the budget and POPULATION, never by the number of workers, and
results come back in batch order: the same seed gives the same placement on one core
or on a cluster.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable

import numpy as np

from offline_prog.config.cell import PlaceConfig
from offline_prog.placement.objective import Evaluation
from offline_prog.placement.space import Candidate, SearchSpace

POPULATION = 8  # candidates per batch and per CMA-ES generation
SIGMA0 = 0.2  # CMA-ES initial step, a share of each range
CMA_TOL_X = 1e-3  # converged when steps are below 0.1 % of each range (its only stop)


@dataclasses.dataclass
class Placement:
    """What the search found.

    Attributes:
        best: the best evaluation (lexicographic objective).
        baseline: the cell as given.
        evaluated: every full evaluation, in order (baseline first).
        screened: every screened grid point.
        wall_s: the search's wall time [s] (from the first evaluation).
    """

    best: Evaluation
    baseline: Evaluation
    evaluated: list[Evaluation]
    screened: list[Evaluation]
    wall_s: float


def _cma(space: SearchSpace, start: Evaluation, seed: int):
    import cma

    options = {
        "bounds": [0.0, 1.0],
        "popsize": POPULATION,
        "seed": seed + 1,  # cma: 0 is random
        "verbose": -9,
        "tolx": CMA_TOL_X,
        # Ranks are told (0 … 7 every generation): the best value never changes, so
        # the tests on function values would stop the run after 10 generations.
        "tolfun": 0,
        "tolfunhist": 0,
        "tolstagnation": 10**9,
        "tolflatfitness": 10**9,
    }
    x0 = np.clip(np.asarray(start.candidate.x, dtype=float), 0.05, 0.95)
    return cma.CMAEvolutionStrategy(x0, SIGMA0, options)


def _ranks(batch: list[Evaluation]) -> list[float]:
    """Each evaluation's rank in the batch by the objective (ties share a rank)."""
    keys = [e.key() for e in batch]
    order = sorted(set(keys))
    return [float(order.index(k)) for k in keys]


def search(
    space: SearchSpace,
    place: PlaceConfig,
    baseline: Candidate,
    run: Callable[[str, list[Candidate]], list[Evaluation]],
) -> Placement:
    """Spend ``place.budget`` pipeline evaluations on the best placement.

    Args:
        space: the search space; place: the checked ``place:`` block.
        baseline: the cell's own placement.
        run: evaluates a batch with a stage ("screen" | "plan"), results in order.
    """
    start = time.perf_counter()
    screened = run("screen", space.grid(place.screen_points))
    unused = sorted(screened, key=Evaluation.key)  # best first
    # The cell as given and the best screened points: one batch.
    first = [e.candidate for e in unused[: min(POPULATION, place.budget) - 1]]
    unused = unused[len(first) :]
    evaluated = run("plan", [baseline, *first])
    budget = place.budget - len(evaluated)
    if space.dimensions == 0 or budget <= 0:  # grasps only: each is one evaluation
        evaluated += run("plan", [e.candidate for e in unused[:budget]])
        return _result(evaluated, screened, start)
    origin, seed = min(evaluated[1:], key=Evaluation.key), place.seed
    while budget > 0:
        es = _cma(space, origin, seed)
        while budget > 0 and not es.stop():
            xs = es.ask()[:budget]
            batch = run("plan", [space.candidate(x, origin.candidate.grasp) for x in xs])
            evaluated += batch
            budget -= len(batch)
            if len(batch) == POPULATION:
                es.tell(xs, _ranks(batch))
        # Converged: restart from the best screened point not yet used (or the best).
        origin = min(evaluated[1:], key=Evaluation.key)
        if budget > 0 and unused:
            evaluated += run("plan", [unused.pop(0).candidate])
            budget -= 1
            origin = evaluated[-1]
        seed += 1
    return _result(evaluated, screened, start)


def _result(evaluated: list[Evaluation], screened: list[Evaluation], start: float) -> Placement:
    best = min(evaluated, key=Evaluation.key)
    return Placement(best, evaluated[0], evaluated, screened, time.perf_counter() - start)
