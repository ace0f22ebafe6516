"""Seam order, direction and branch of a job: a generalised travelling-salesman problem.

Each seam can be run in one of several *options* (direction, IK branch, tool rotation);
an option is entered at q_in (the approach's start) and left at q_out (the retract's
end). The job starts and ends at home. The cost of a link a → b is the duration of a
synchronised rest-to-rest joint move (what a controller's PTP to a fine point does; the
planned link may detour around an obstacle and take longer):

    T(a, b) = max_k T_k,  T_k = 2 √(d_k / a_k)            if d_k ≤ v_k² / a_k (triangle)
                          T_k = d_k / v_k + v_k / a_k      otherwise (trapezoid),

d_k = |b_k − a_k| in the controller's axes, v_k, a_k the joint speed and acceleration
limits. ``order_job`` minimises home → option₁ → … → option_n → home over one option per
seam: ``given`` keeps the seam order and picks the options exactly (a shortest path
through the layers of options); ``auto`` also picks the order, exactly by Held–Karp
dynamic programming over subsets of seams × options up to ``EXACT_MAX_SEAMS`` seams,
beyond by the budgeted local search of :mod:`offline_prog.job.order_search` (each order's
options picked exactly). Deterministic: no random numbers, no clock in the answer.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from offline_prog.job.link_costs import LinkCosts, ptp_time
from offline_prog.job.order_search import (
    MIN_IMPROVEMENT_S,
    SEARCH_BUDGET,
    SearchProgress,
    SearchResult,
    local_search,
)

__all__ = ["EXACT_MAX_SEAMS", "JobOrder", "OrderSearch", "order_job", "ptp_time"]

EXACT_MAX_SEAMS = 12  # Held–Karp: 2^12 subsets × options², well under a second


@dataclasses.dataclass(frozen=True)
class OrderSearch:
    """How the order was found (report.json ``job.order_search``).

    Attributes:
        method: given | exact | heuristic.
        budget: link estimates the heuristic may add up (its work bound; 0 otherwise).
        used: link estimates added up (the heuristic stops before ``budget``).
        orders_evaluated: seam orders whose best options were computed.
        rounds: improving moves applied by the heuristic.
        descents: local descents it ran (from its starting tours, best first).
        stopped: why it stopped: given | exact | no improving move |
            improvement below threshold | budget.
        min_improvement_s: the heuristic stops after a move that gains less [s].
        time_s: wall time of the search [s] (reported, never used in the answer).
        start_air_time_s: the order the search started from [s] (the heuristic's best
            nearest-neighbour tour; the given order for the others).
        lower_bound_s: no order can take less: every seam entered and home re-entered
            by its cheapest link (or left, whichever sum is larger) [s].
        improvements_s: each round's gain [s], in order.
    """

    method: str
    budget: int
    used: int
    orders_evaluated: int
    rounds: int
    descents: int
    stopped: str
    min_improvement_s: float
    time_s: float
    start_air_time_s: float
    lower_bound_s: float
    improvements_s: tuple[float, ...] = ()


@dataclasses.dataclass(frozen=True)
class JobOrder:
    """The chosen run: ``sequence`` option indices in run order; ``air_time_s`` the
    estimated link time home → … → home [s]; ``given_air_time_s`` the same for the seams
    in their given order (options chosen exactly); ``method``: given | exact |
    heuristic; ``links_s`` each link's estimate in run order; ``search`` how."""

    sequence: list[int]
    air_time_s: float
    given_air_time_s: float
    method: str
    links_s: list[float]
    search: OrderSearch | None = None

    @property
    def saved_s(self) -> float:
        return self.given_air_time_s - self.air_time_s


def order_job(
    options,
    q_home,
    *,
    qd_max,
    qdd_max,
    n_seams: int,
    mode: str = "auto",
    controller_joints=None,
    budget: int = SEARCH_BUDGET,
    min_improvement_s: float = MIN_IMPROVEMENT_S,
    progress: SearchProgress | None = None,
) -> JobOrder:
    """Choose one option per seam and the seam order (``mode`` auto) or keep the given
    order (``given``) for the least estimated link time.

    Args:
        options: [(seam index, label, q_in (6,), q_out (6,))] every way to run each seam.
        q_home: (6,) [rad]; qd_max, qdd_max: (6,) joint limits (controller axes).
        n_seams: seams 0 .. n_seams − 1 each have at least one option.
        controller_joints: maps URDF q to the controller's axes (None: the same).
        budget: link estimates the heuristic (beyond EXACT_MAX_SEAMS) may add up.
        min_improvement_s: the heuristic stops after a round that gains less [s].
        progress: called after each of the heuristic's rounds (see order_search).
    """
    started = time.perf_counter()
    costs = LinkCosts(options, q_home, qd_max, qdd_max, controller_joints)
    assert costs.n == n_seams and all(len(o) for o in costs.of_seam)
    given_time, given = costs.layered(list(range(n_seams)))
    method, found = "given", SearchResult(given_time, given, given_time, orders_evaluated=1)
    if mode == "auto" and 1 < n_seams <= EXACT_MAX_SEAMS:
        method = "exact"
        found = SearchResult(*_held_karp(costs, n_seams), given_time, orders_evaluated=1)
    elif mode == "auto" and n_seams > EXACT_MAX_SEAMS:
        method = "heuristic"
        found = local_search(
            costs, budget=budget, min_improvement_s=min_improvement_s, progress=progress
        )
    time_s, sequence = found.air_time_s, found.sequence
    if time_s > given_time:  # never worse than the given order
        time_s, sequence = given_time, given
    search = OrderSearch(
        method=method,
        budget=budget if method == "heuristic" else 0,
        used=found.used,
        orders_evaluated=found.orders_evaluated,
        rounds=found.rounds,
        descents=found.descents,
        stopped=found.stopped or method,
        min_improvement_s=min_improvement_s,
        time_s=time.perf_counter() - started,
        start_air_time_s=found.start_air_time_s,
        lower_bound_s=costs.lower_bound(),
        improvements_s=tuple(found.improvements_s),
    )
    return JobOrder(sequence, time_s, given_time, method, costs.links(sequence), search)


def _held_karp(costs: LinkCosts, n: int) -> tuple[float, list[int]]:
    """Exact: dp[mask, o] = the least time from home through the seams in mask, ending
    with option o (of a seam in mask)."""
    m = len(costs.seam)
    bit = 1 << costs.seam  # (m,) each option's seam bit
    dp = np.full((1 << n, m), np.inf)
    parent = np.full((1 << n, m), -1, dtype=int)
    dp[bit, np.arange(m)] = costs.into
    for mask in range(1, 1 << n):
        inside = (mask & bit) != 0
        ends = np.flatnonzero(inside & np.isfinite(dp[mask]))
        if not len(ends):
            continue
        outside = np.flatnonzero(~inside)
        if not len(outside):
            continue
        total = dp[mask, ends][:, None] + costs.C[np.ix_(ends, outside)]
        best = np.argmin(total, axis=0)
        value = total[best, np.arange(len(outside))]
        targets = mask | bit[outside]
        better = value < dp[targets, outside]
        dp[targets[better], outside[better]] = value[better]
        parent[targets[better], outside[better]] = ends[best[better]]
    full = (1 << n) - 1
    total = dp[full] + costs.out
    o = int(np.argmin(total))
    sequence, mask = [], full
    while o >= 0:
        sequence.append(o)
        o, mask = int(parent[mask, o]), mask & ~int(bit[o])
    return float(total.min()), sequence[::-1]
