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
beyond by 2-opt and or-opt moves on the seam order, each order's options picked exactly.
Deterministic: no random numbers.
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np

EXACT_MAX_SEAMS = 12  # Held–Karp: 2^12 subsets × options², well under a second
MAX_STARTS = 8  # the heuristic descends from nearest-neighbour tours of this many seams


def ptp_time(q_a, q_b, qd_max, qdd_max) -> np.ndarray:
    """(...) the synchronised rest-to-rest move's duration [s] between (..., 6) joint
    vectors [rad] under joint limits qd_max [rad/s], qdd_max [rad/s²] (see module)."""
    d = np.abs(np.asarray(q_b, dtype=float) - np.asarray(q_a, dtype=float))
    v, a = np.asarray(qd_max, dtype=float), np.asarray(qdd_max, dtype=float)
    triangle = d <= v**2 / a
    t = np.where(triangle, 2.0 * np.sqrt(d / a), d / v + v / a)
    return t.max(axis=-1)


@dataclasses.dataclass(frozen=True)
class JobOrder:
    """The chosen run: ``sequence`` option indices in run order; ``air_time_s`` the
    estimated link time home → … → home [s]; ``given_air_time_s`` the same for the seams
    in their given order (options chosen exactly); ``method``: given | exact |
    heuristic; ``links_s`` each link's estimate in run order."""

    sequence: list[int]
    air_time_s: float
    given_air_time_s: float
    method: str
    links_s: list[float]

    @property
    def saved_s(self) -> float:
        return self.given_air_time_s - self.air_time_s


class _Costs:
    """Link estimates between options: into[j] from home, out[i] to home, C[i, j]."""

    def __init__(self, options, q_home, qd_max, qdd_max, controller_joints):
        to_c = controller_joints or (lambda q: q)
        self.seam = np.array([o[0] for o in options], dtype=int)
        q_in = to_c(np.array([o[2] for o in options], dtype=float))
        q_out = to_c(np.array([o[3] for o in options], dtype=float))
        home = to_c(np.asarray(q_home, dtype=float))
        self.into = ptp_time(home, q_in, qd_max, qdd_max)
        self.out = ptp_time(q_out, home, qd_max, qdd_max)
        self.C = ptp_time(q_out[:, None, :], q_in[None, :, :], qd_max, qdd_max)
        self.of_seam = [np.flatnonzero(self.seam == k) for k in range(self.seam.max() + 1)]

    def layered(self, seams: list[int]) -> tuple[float, list[int]]:
        """The best options for seams run in this order: (air time, option indices)."""
        layer = self.of_seam[seams[0]]
        cost, back = self.into[layer], []
        for k in seams[1:]:
            nxt = self.of_seam[k]
            total = cost[:, None] + self.C[np.ix_(layer, nxt)]
            back.append((layer, np.argmin(total, axis=0)))
            cost, layer = total.min(axis=0), nxt
        total = cost + self.out[layer]
        j = int(np.argmin(total))
        chosen = [int(layer[j])]
        for prev_layer, arg in reversed(back):
            j = int(arg[j])
            chosen.append(int(prev_layer[j]))
        return float(total.min()), chosen[::-1]

    def links(self, sequence: list[int]) -> list[float]:
        first = [float(self.into[sequence[0]])]
        middle = [float(self.C[a, b]) for a, b in zip(sequence[:-1], sequence[1:], strict=True)]
        return first + middle + [float(self.out[sequence[-1]])]


def order_job(
    options, q_home, *, qd_max, qdd_max, n_seams: int, mode: str = "auto",
    controller_joints=None,
) -> JobOrder:  # fmt: skip
    """Choose one option per seam and the seam order (``mode`` auto) or keep the given
    order (``given``) for the least estimated link time.

    Args:
        options: [(seam index, label, q_in (6,), q_out (6,))] every way to run each seam.
        q_home: (6,) [rad]; qd_max, qdd_max: (6,) joint limits (controller axes).
        n_seams: seams 0 .. n_seams − 1 each have at least one option.
        controller_joints: maps URDF q to the controller's axes (None: the same).
    """
    costs = _Costs(options, q_home, qd_max, qdd_max, controller_joints)
    assert len(costs.of_seam) == n_seams and all(len(o) for o in costs.of_seam)
    given_time, given = costs.layered(list(range(n_seams)))
    if mode == "given" or n_seams == 1:
        return JobOrder(given, given_time, given_time, "given", costs.links(given))
    if n_seams <= EXACT_MAX_SEAMS:
        time, sequence, method = *_held_karp(costs, n_seams), "exact"
    else:
        time, sequence, method = *_local_search(costs, n_seams), "heuristic"
    if time > given_time:  # never worse than the given order
        time, sequence = given_time, given
    return JobOrder(sequence, time, given_time, method, costs.links(sequence))


def _held_karp(costs: _Costs, n: int) -> tuple[float, list[int]]:
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


def _local_search(costs: _Costs, n: int) -> tuple[float, list[int]]:
    """From nearest-neighbour tours starting at the first MAX_STARTS seams: 2-opt and
    or-opt moves on the seam order until none improves; each order's options chosen
    exactly (``_Costs.layered``). The best of the descents."""
    seam_cost = np.full((n, n), np.inf)
    for a in range(n):
        for b in range(n):
            if a != b:
                seam_cost[a, b] = costs.C[np.ix_(costs.of_seam[a], costs.of_seam[b])].min()
    best = (np.inf, [])
    for start in range(min(n, MAX_STARTS)):
        order, left = [start], set(range(n)) - {start}
        while left:
            nxt = min(left, key=lambda k: (seam_cost[order[-1], k], k))
            order.append(nxt)
            left.remove(nxt)
        best = min(best, _descend(costs, order), key=lambda r: r[0])
    return best


def _descend(costs: _Costs, order: list[int]) -> tuple[float, list[int]]:
    """First-improvement 2-opt (reverse a stretch) and or-opt (move one seam)."""
    n = len(order)
    best, chosen = costs.layered(order)
    improved = True
    while improved:
        improved = False
        pairs = itertools.combinations(range(n + 1), 2)
        candidates = [order[:i] + order[i:j][::-1] + order[j:] for i, j in pairs if j - i >= 2]
        for i in range(n):
            rest = order[:i] + order[i + 1 :]
            candidates += [rest[:j] + [order[i]] + rest[j:] for j in range(n) if j != i]
        for candidate in candidates:
            time, options = costs.layered(candidate)
            if time < best - 1e-12:
                best, chosen, order, improved = time, options, candidate, True
                break
    return best, chosen


def brute_force_order(options, q_home, *, qd_max, qdd_max, n_seams: int,
                      controller_joints=None) -> tuple[float, list[int]]:  # fmt: skip
    """Every seam order (n!) with the exact options of each: for checking only."""
    costs = _Costs(options, q_home, qd_max, qdd_max, controller_joints)
    best = (np.inf, [])
    for order in itertools.permutations(range(n_seams)):
        time, chosen = costs.layered(list(order))
        if time < best[0]:
            best = (time, chosen)
    return best
