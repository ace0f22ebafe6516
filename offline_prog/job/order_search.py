"""The seam-order search for jobs too large to solve exactly: a budgeted local search.

Starts: the given order and nearest-neighbour tours (by each seam pair's cheapest link)
from home and from the first ``MAX_STARTS`` seams, each costed with its options chosen
exactly; descents from them, the best first. A descent runs rounds: the 2-opt moves
(reverse a stretch) and or-opt moves (move a block of 1 .. ``MAX_BLOCK`` seams) that
put a seam next to one of its ``NEAR_SEAMS`` nearest seams (or home) are costed
exactly, each moved order's options chosen by the layered shortest path
(:class:`~offline_prog.job.link_costs.LinkCosts`) on the window where it differs from
the current tour, the shortest windows first; the best move is applied as soon as one
gains ``min_improvement_s`` (else the best of all). A descent ends when no move
improves or the round's gain is below ``min_improvement_s``; the search ends when the
descents are done or the next moves would pass the budget: a count of link estimates
added up, each round's bookkeeping counted alike (deterministic, unlike a clock, and
about proportional to the time: ~20 million per second here, so the default budget
is about a second). The starting tours are always costed (at most MAX_STARTS + 2).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from offline_prog.job.link_costs import LinkCosts

SEARCH_BUDGET = 20_000_000  # link estimates: ~1 s on this machine
MIN_IMPROVEMENT_S = 0.005  # a round gaining less than this [s] ends the search
NEAR_SEAMS = 8  # moves join a seam to one of its nearest seams (by the cheapest link)
MAX_BLOCK = 3  # or-opt moves blocks of up to this many seams
MAX_STARTS = 8  # nearest-neighbour starts from the first seams (and home)
BATCH_WORK = 4_000_000  # link estimates per batch: bounds the batch's memory

# progress(rounds, air time [s], used, budget) after each round.
SearchProgress = Callable[[int, float, int, int], None]


@dataclasses.dataclass
class SearchResult:
    """The search's answer and its counters (see :class:`~offline_prog.job.order.OrderSearch`)."""

    air_time_s: float
    sequence: list[int]  # option indices in run order
    start_air_time_s: float
    used: int = 0
    orders_evaluated: int = 0
    rounds: int = 0
    descents: int = 0  # descents started (from the starting tours, best first)
    stopped: str = ""
    improvements_s: list[float] = dataclasses.field(default_factory=list)


def local_search(
    costs: LinkCosts,
    *,
    budget: int = SEARCH_BUDGET,
    min_improvement_s: float = MIN_IMPROVEMENT_S,
    progress: SearchProgress | None = None,
) -> SearchResult:
    """The best tour found within ``budget`` link estimates (see the module)."""
    n = costs.n
    result = SearchResult(np.inf, [], np.inf)
    starts = _starts(costs)
    times = costs.window_times(
        starts[:, 1:-1], np.ones(len(starts), int), *_tables(costs, starts[0])
    )
    result.used += costs.window_work(len(starts), n)
    result.orders_evaluated += len(starts)
    by_time = np.argsort(times, kind="stable")
    result.start_air_time_s = float(times[by_time[0]])
    neighbours = _neighbours(costs)
    best_tour, best = starts[by_time[0]], result.start_air_time_s
    for k in by_time:
        search = (neighbours, budget, min_improvement_s, result, progress, best)
        tour, time_s = _descend(costs, starts[k], float(times[k]), *search)
        result.descents += 1
        if time_s < best - 1e-12:
            best_tour, best = tour, time_s
        if result.stopped == "budget":
            break
    result.air_time_s, result.sequence = costs.layered(list(best_tour[1:-1]))
    return result


def _descend(
    costs, tour, current, neighbours, budget, min_improvement_s, result, progress, best
) -> tuple[np.ndarray, float]:
    """Rounds of the best move among the shortest windows that gain ``min_improvement_s``
    (else among all), from ``tour`` of air time ``current`` [s], until a stop (the
    reason in ``result.stopped``)."""
    n = costs.n
    most = neighbours.size * (3 + 5 * MAX_BLOCK)  # moves a round can generate
    while True:
        if result.used + _bookkeeping(costs, most) > budget:
            result.stopped = "budget"
            return tour, current
        moves = _moves(n, neighbours, tour)
        result.used += _bookkeeping(costs, moves.shape[1])
        lo, length = _window(moves)
        shortest = np.argsort(_size_class(length, n), kind="stable")
        moves, lo, length = moves[:, shortest], lo[shortest], length[shortest]
        affordable = _within(costs, length, budget - result.used)
        truncated = affordable < len(lo)
        tables, gain, k = _tables(costs, tour), 0.0, -1
        for cls in _by_window(n, length[:affordable]):  # shortest windows first
            times = _costed(costs, moves[:, cls], lo[cls], length[cls], tables, result)
            if current - times.min() > gain:
                gain, k = current - float(times.min()), int(cls[np.argmin(times)])
            if gain > 1e-12 and gain >= min_improvement_s:
                truncated = False  # the moves left over are not needed this round
                break
        if gain > 1e-12:
            tour = tour[_source(moves[:, k : k + 1], np.arange(n + 2)[None, :])[0]]
            current -= gain
            result.rounds += 1
            result.improvements_s.append(gain)
            if progress is not None:
                progress(result.rounds, min(best, current), result.used, budget)
        if truncated:
            result.stopped = "budget"
        elif gain <= 1e-12:
            result.stopped = "no improving move"
        elif gain < min_improvement_s:
            result.stopped = "improvement below threshold"
        else:
            continue
        return tour, current


def _bookkeeping(costs: LinkCosts, moves: int) -> int:
    """A round's work besides costing moves, in link estimates: the current tour's
    tables (2 (n + 1) steps) and generating and sorting its moves (about one step of
    one window each: it takes about as long)."""
    return (2 * (costs.n + 1) + moves) * costs.width**2


def _tables(costs: LinkCosts, tour: np.ndarray):
    """The tour and its prefix and suffix tables (LinkCosts.forward, backward)."""
    return tour, costs.forward(tour), costs.backward(tour)


def _costed(costs, moves, lo, length, tables, result: SearchResult) -> np.ndarray:
    """(K,) air times of the tables' tour after each move (3, K), costed on the move's
    window (lo, length: (K,)), batched by window length (a window may grow over
    unchanged positions: the same answer). Counts the work in ``result``."""
    times, tour = np.empty(len(lo)), tables[0]
    sizes = _size_class(length, costs.n)
    for size in np.flatnonzero(np.bincount(sizes)):  # the classes present, ascending
        chosen = np.flatnonzero(sizes == size)
        start = np.minimum(lo[chosen], costs.n + 1 - size)  # windows end inside the tour
        per_batch = max(1, BATCH_WORK // costs.window_work(1, size))
        for first in range(0, len(chosen), per_batch):
            batch = slice(first, first + per_batch)
            at = start[batch, None] + np.arange(size)[None, :]
            window = tour[_source(moves[:, chosen[batch]], at)]
            times[chosen[batch]] = costs.window_times(window, start[batch], *tables)
            result.used += costs.window_work(len(chosen[batch]), int(size))
            result.orders_evaluated += len(chosen[batch])
    return times


def _by_window(n: int, length: np.ndarray) -> list[np.ndarray]:
    """Indices of the moves (sorted by window) grouped by window size class."""
    sizes = _size_class(length, n)
    return [np.flatnonzero(sizes == size) for size in np.flatnonzero(np.bincount(sizes))]


def _size_class(length: np.ndarray, n: int) -> np.ndarray:
    """Window lengths rounded up to a power of two (at most n): few batches, each at
    most twice the work of its windows."""
    return np.minimum(2 ** np.ceil(np.log2(np.maximum(length, 1))).astype(int), n)


def _within(costs: LinkCosts, length, left: int) -> int:
    """How many of the moves (in order) fit in ``left`` link estimates."""
    work = np.cumsum(costs.window_work(1, _size_class(length, costs.n)))
    return int(np.searchsorted(work, left, side="right"))


def _seam_links(costs: LinkCosts) -> np.ndarray:
    """(n + 1, n + 1) each seam pair's cheapest link [s] (index n: home); ∞ on the
    diagonal."""
    cheapest = costs.D.min(axis=(2, 3))
    np.fill_diagonal(cheapest, np.inf)
    return cheapest


def _starts(costs: LinkCosts) -> np.ndarray:
    """(S, n + 2) tours: the given order, then nearest-neighbour tours from home and
    from the first MAX_STARTS seams."""
    n, cheapest = costs.n, _seam_links(costs)
    tours = [costs.tour(np.arange(n))]
    for first in [n, *range(min(n, MAX_STARTS))]:
        order, left = [] if first == n else [first], np.ones(n, dtype=bool)
        left[order] = False
        at = first
        while left.any():
            at = int(np.argmin(np.where(left, cheapest[at, :n], np.inf)))
            order.append(at)
            left[at] = False
        tours.append(costs.tour(np.array(order)))
    return np.unique(np.array(tours), axis=0)


def _neighbours(costs: LinkCosts) -> np.ndarray:
    """(n + 1, k) each seam's (and home's) nearest seams or home, by the cheaper of the
    two directions' cheapest links."""
    cheapest = _seam_links(costs)
    near = np.minimum(cheapest, cheapest.T)
    k = min(NEAR_SEAMS, costs.n)
    return np.argsort(near, axis=1, kind="stable")[:, :k]


def _moves(n: int, neighbours: np.ndarray, tour: np.ndarray) -> np.ndarray:
    """(3, K) the 2-opt and or-opt moves that join a seam to one of its nearest seams
    or home, each as (s, z, t): reverse positions s .. s + z − 1 (t = −1), or move
    that block to before position t (1 ≤ t ≤ n + 1), in tour positions (home: 0, n + 1)."""
    k = neighbours.shape[1]
    where = np.empty(n + 1, dtype=int)
    where[tour[1:-1]] = np.arange(1, n + 1)
    where[n] = 0  # home: at position 0 (and n + 1)
    a, b = np.repeat(np.arange(n + 1), k), neighbours.ravel()
    i, j = np.minimum(where[a], where[b]), np.maximum(where[a], where[b])  # i = 0: home
    last = where[b[a == n]]  # a seam near home, to be run last
    # reverse i + 1 .. j or i .. j − 1: the seams at i and j become neighbours
    reverse = [(i + 1, j), (i, j - 1), (last, np.full(len(last), n))]
    moves = [np.stack([lo, hi - lo + 1, np.full(len(lo), -1)]) for lo, hi in reverse]
    for z in range(1, MAX_BLOCK + 1):
        # the block starting at j put right after i, the block ending at j right before
        # i, the same with i and j swapped, and a block ending at a seam near home last
        at_end = np.full(len(last), n + 1)
        pairs = ((j, i + 1), (j - z + 1, i), (i, j + 1), (i - z + 1, j), (last - z + 1, at_end))
        moves += [np.stack([s, np.full(len(s), z), t]) for s, t in pairs]
    s, z, t = np.concatenate(moves, axis=1)
    valid = (s >= 1) & (s + z - 1 <= n) & (z >= 2 - (t >= 0))
    valid &= (t == -1) | ((t >= 1) & (t <= n + 1) & ((t < s) | (t > s + z)))
    size = n + 3  # s, z, t + 1 all within 0 .. n + 2: one integer per move, for unique
    key = np.unique((s[valid] * size + z[valid]) * size + t[valid] + 1)
    return np.stack([key // size**2, key // size % size, key % size - 1])


def _window(moves: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(K,), (K,) the first position and length of the stretch each move changes."""
    s, z, t = moves
    block = t >= 0
    lo = np.where(block, np.minimum(s, t), s)
    return lo, np.where(block, np.maximum(s + z, t) - lo, z)


def _source(moves: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(K, P) the position in the current tour of what each move puts at positions
    p (K, P)."""
    s, z, t = (m[:, None] for m in moves)
    reversed_ = np.where((p >= s) & (p < s + z), 2 * s + z - 1 - p, p)
    earlier = np.where(p < t, p, np.where(p < t + z, s + p - t, np.where(p < s + z, p - z, p)))
    later = np.where(p < s, p, np.where(p < t - z, p + z, np.where(p < t, s + p - t + z, p)))
    return np.where(t < 0, reversed_, np.where(t < s, earlier, later))
