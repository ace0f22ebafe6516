"""Collision and clearance checks along a joint trajectory, samples and between them.

Every unfiltered geometry pair of a :class:`~offline_prog.scene.drake_cell.DrakeCell` is measured
with SceneGraph's signed distance (convex pieces for meshes), grouped by shape name. Pairs
of meshes near or below the clearance are then measured on the original triangle meshes
with python-fcl (:func:`~offline_prog.scene.exact_distance.exact_distance`), which decides.

Motion bound (Schwarzer, Saha & Latombe, "Adaptive dynamic collision checking for single
and multiple articulated robots in complex environments", IEEE T-RO 21(3), 2005): moving
the joints along the straight line from q_a to q_b changes a pair's signed distance by at
most c·M_g(a, b), M_g = Σ_k ρ_k |q_b,k − q_a,k| over the joints between its two sides (its
span, :mod:`~offline_prog.collision.pairs`), c = 1, or 0 for a pair that never moves.
Hence, per geometry pair g (each queried alone, M_g its own cumulative motion bound):

* evaluated at sample i with distance d_g, g is certified (≥ clearance + margin) up to a
  cumulative motion of (d_g − clearance − margin) / c_g and next evaluated at the last
  sample within it (conservative advancement; pruning);
* between two evaluated neighbours a, b, d_g ≥ (d_g(a) + d_g(b) − c_g M(a, b)) / 2; a step
  where this falls below the clearance is bisected (q interpolated linearly) until it
  holds, an end overlaps, or M ≤ the clearance: so no contact is missed between checks
  (no tunnelling) and the clearance is violated unseen by at most c·M/2 ≤ the clearance.
"""

from __future__ import annotations

import time
from bisect import bisect_right
from heapq import heappop, heappush

import numpy as np

from offline_prog.arrays import at_index
from offline_prog.collision.pairs import cell_pairs
from offline_prog.collision.result import (  # noqa: F401  (re-exported)
    CollisionResult,
    CollisionStretch,
    PairMinimum,
    failure_message,
    write_collisions_json,
)
from offline_prog.scene.drake_cell import DrakeCell

# A pair certified above clearance + this is not evaluated (its minimum is then over
# the evaluated points only).
PRUNE_MARGIN_M = 0.02
# Drake (convex pieces) and FCL (original shapes) distances further apart are noted.
EXACT_MISMATCH_TOL_M = 5e-4
N_WORST_PAIRS = 5
MAX_EXACT_CHECKS = 2000  # FCL refinements of mesh pairs per check; beyond: Drake's, noted
MIN_SUBSTEP_M = 1e-4  # bisection stops here even for clearance 0
TOUCH_TOL_M = 1e-9  # a signed distance above −this is touching, not overlapping


def check_trajectory(
    cell: DrakeCell,
    q: np.ndarray,
    t: np.ndarray,
    sigma: np.ndarray,
    *,
    clearance: float,
    self_clearance: float | None = None,
    margin: float = PRUNE_MARGIN_M,
    n_worst: int = N_WORST_PAIRS,
) -> CollisionResult:
    """Check every unfiltered shape pair along a joint trajectory, samples and between.

    Args:
        cell: the cell with its shapes (:func:`~offline_prog.scene.drake_cell.build_cell_model`).
        q: (N, 6) joint positions [rad], one row per sample; linear in between.
        t: (N,) sample times [s].
        sigma: (N,) path parameter σ at the samples [m].
        clearance: smallest allowed signed distance of any checked pair [m].
        self_clearance: the same for robot link vs robot link pairs (default: clearance).
        margin: pruning margin [m] (see PRUNE_MARGIN_M).
        n_worst: how many closest pairs get FCL's exact distance as a cross-check.

    Raises:
        ValueError: q, t or sigma of the wrong shape, or a negative clearance.
    """
    q, t, sigma = (np.asarray(a, dtype=float) for a in (q, t, sigma))
    n = len(q)
    if q.ndim != 2 or q.shape[1] != 6 or n < 1 or not np.all(np.isfinite(q)):
        raise ValueError(f"q: expected (N, 6) finite joint positions, got shape {q.shape}")
    if t.shape != (n,) or sigma.shape != (n,):
        raise ValueError(f"t, sigma: expected shape ({n},), got {t.shape} and {sigma.shape}")
    self_clearance = clearance if self_clearance is None else self_clearance
    for name, value in (("clearance", clearance), ("self_clearance", self_clearance)):
        if not (np.isfinite(value) and value >= 0):
            raise ValueError(f"{name}: expected a distance >= 0 m, got {value!r}")
    start = time.perf_counter()
    pairs, rho = cell_pairs(cell, fixed_layout=True), cell.motion_radii()
    clear_s = np.where(pairs.is_self, self_clearance, clearance)  # (S,) per shape pair [m]
    clear_s = np.where(pairs.is_fixed, 0.0, clear_s)  # a base on its floor touches it
    clear_g = clear_s[pairs.shape_of]  # (G,) per geometry pair [m]
    # (N - 1, n_spans) motion bound of each step, per span of joints [m], and its sums.
    step = np.abs(np.diff(q, axis=0)) @ pairs.span_radii(rho).T
    cumulative = np.vstack([np.zeros((1, len(pairs.spans))), np.cumsum(step, axis=0)])
    # (geometry pair g, point x, Drake distance) of each evaluation, in order.
    found_g: list[int] = []
    found_x: list[float] = []
    found_d: list[float] = []
    distance, c_list, clear_list = pairs.distance, pairs.c.tolist(), clear_g.tolist()

    def bisect(g: int, xa: float, da: float, xb: float, db: float, motion: float) -> None:
        if (da + db - c_list[g] * motion) / 2 >= clear_list[g] or min(da, db) < -TOUCH_TOL_M:
            return  # certified, or an overlap already found at an end
        if motion <= max(clear_list[g], MIN_SUBSTEP_M):
            return
        xm = (xa + xb) / 2
        pairs.set(at_index(q, xm))
        dm = distance(g)
        found_g.append(g)
        found_x.append(xm)
        found_d.append(dm)
        bisect(g, xa, da, xm, dm, motion / 2)
        bisect(g, xm, dm, xb, db, motion / 2)

    # In Python floats and a heap (numpy's per-call cost dominates arrays of a few
    # elements: usually a pair or two near an obstacle are due at a sample), the
    # sample loop's calls bound once: most of a long seam is one pair at every sample.
    by_span = [(c.tolist(), s.tolist()) for c, s in zip(cumulative.T, step.T, strict=True)]
    motion_g, rows = [by_span[k] for k in pairs.span_of], list(q)  # g's (cumulative, step)
    set_positions, context = pairs._set_positions, pairs.plant_context
    query, ids = pairs.query.ComputeSignedDistancePairClosestPoints, pairs.ids
    # (next sample to evaluate, g) of each pair not yet certified to the end; pairs due
    # at the same sample pop in the order of g.
    heap = [(0, g) for g in range(len(pairs.ids))]
    last_i, last_d = [-2] * len(heap), [0.0] * len(heap)
    evaluated = 0  # evaluations at samples (bisections count in pairs.distance)

    def _run_alone(g: int, i: int, other: int) -> None:
        """Pair g due alone at sample i, while no other pair falls due before
        ``other``: the loop's own steps for one pair, sample after sample (most of a
        seam with a tool near the part), without the heap in between."""
        nonlocal evaluated
        pair, c, clear = ids[g], c_list[g], clear_list[g]
        cumulative_list, step_list = motion_g[g]
        while True:
            set_positions(context, rows[i])
            d = query(*pair).distance
            found_g.append(g)
            found_x.append(float(i))
            found_d.append(d)
            evaluated += 1
            reach = bisect_right(cumulative_list, cumulative_list[i] + (d - clear - margin) / c)
            due = n if reach - 1 >= n - 1 else max(reach - 1, i + 1)
            if i and last_i[g] == i - 1 and (last_d[g] + d - c * step_list[i - 1]) / 2 < clear:
                bisect(g, i - 1.0, last_d[g], float(i), d, step_list[i - 1])
            last_i[g], last_d[g] = i, d
            if due >= other:  # certified to the end, or another pair is due by then
                if due < n:
                    heappush(heap, (due, g))
                return
            i = due

    while heap and (i := heap[0][0]) < n:
        now = [heappop(heap)[1]]
        while heap and heap[0][0] == i:
            now.append(heappop(heap)[1])
        if len(now) == 1 and c_list[now[0]] != 0.0:  # one moving pair alone: a run
            _run_alone(now[0], i, heap[0][0] if heap else n)
            continue
        set_positions(context, rows[i])
        x = float(i)
        d_now = [query(*ids[g]).distance for g in now]  # all at q[i] before bisections
        evaluated += len(now)
        found_g += now
        found_x += [x] * len(now)
        found_d += d_now
        split = []
        for g, d in zip(now, d_now, strict=True):
            c, clear = c_list[g], clear_list[g]
            cumulative_list, step_list = motion_g[g]
            if c != 0.0:  # nothing moves (c = 0): measured once
                # The last sample the distance budget reaches (searchsorted, right).
                reach = bisect_right(cumulative_list, cumulative_list[i] + (d - clear - margin) / c)
                if reach - 1 < n - 1:
                    heappush(heap, (max(reach - 1, i + 1), g))
            if i and last_i[g] == i - 1 and (last_d[g] + d - c * step_list[i - 1]) / 2 < clear:
                split.append((g, d))
            last_i[g] = i
        for g, d in split:
            bisect(g, i - 1.0, last_d[g], x, d, motion_g[g][1][i - 1])
        for g, d in zip(now, d_now, strict=True):
            last_d[g] = d
    pairs.evaluations += evaluated
    g = np.array(found_g, dtype=int)
    x, d = np.array(found_x, dtype=float), np.array(found_d, dtype=float)
    s = pairs.shape_of[g]
    order = np.lexsort((x, s))  # one row per (shape pair, point): its closest pieces
    s, x, d = s[order], x[order], d[order]
    rows = np.flatnonzero(np.r_[True, (s[1:] != s[:-1]) | (x[1:] != x[:-1])])
    s, x, d = s[rows], x[rows], np.minimum.reduceat(d, rows)
    clearances = (clearance, self_clearance, clear_s)
    return _result(cell, pairs, (s, x, d), q, t, sigma, clearances, n_worst, rho, start, margin)


def _result(cell, pairs, table, q, t, sigma, clearances, n_worst, rho, start, margin):
    """The CollisionResult of the evaluated table (mesh pairs refined with FCL)."""
    s, x, drake = table
    clearance, self_clearance, clear_s = clearances
    limit = clear_s[s]  # (K,) each evaluated point's clearance [m]
    dist, exact = drake.copy(), np.full(len(x), np.nan)
    notes = []
    refine = np.flatnonzero((drake < limit) & pairs.has_mesh[s])
    if len(refine) > MAX_EXACT_CHECKS:
        notes.append(f"{len(refine) - MAX_EXACT_CHECKS} mesh-pair points kept Drake's distance")
    for k in refine[:MAX_EXACT_CHECKS]:
        exact[k] = pairs.exact(at_index(q, x[k]), s[k])
        dist[k] = exact[k] if exact[k] > 0 else min(drake[k], 0.0)

    def entry(k: int) -> PairMinimum:
        a, b = pairs.names[s[k]]
        e = None if np.isnan(exact[k]) else float(exact[k])
        return PairMinimum(
            a,
            b,
            pairs.groups[s[k]],
            float(dist[k]),
            float(at_index(sigma, x[k])),
            float(at_index(t, x[k])),
            float(x[k]),
            float(drake[k]),
            max(0.0, -float(dist[k])),
            e,
        )

    # Per shape pair (s sorted, each pair's rows together): its closest row (the first
    # of equals) and its runs of rows below its clearance, for all pairs at once.
    lo = np.flatnonzero(np.r_[True, s[1:] != s[:-1]]) if len(s) else np.zeros(0, dtype=int)
    closest_rows = np.lexsort((dist, s))[lo]
    minima = [entry(k) for k in closest_rows.tolist()]
    below_clearance = dist < limit
    first_row, last_row = np.zeros(len(s), dtype=bool), np.zeros(len(s), dtype=bool)
    first_row[lo], last_row[lo[1:] - 1] = True, True
    last_row[-1:] = True
    starts = np.flatnonzero(below_clearance & (first_row | ~np.r_[False, below_clearance[:-1]]))
    stops = np.flatnonzero(below_clearance & (last_row | ~np.r_[below_clearance[1:], False])) + 1
    stretches = []
    for a, b in zip(starts.tolist(), stops.tolist(), strict=True):
        worst = entry(a + int(np.argmin(dist[a:b])))
        first, last = entry(a), entry(b - 1)
        stretches.append(
            CollisionStretch(
                worst.a,
                worst.b,
                worst.group,
                first.sample,
                last.sample,
                first.sigma_m,
                last.sigma_m,
                first.t_s,
                last.t_s,
                worst,
            )
        )
    measured = np.bincount(s[x == np.floor(x)], minlength=len(pairs.names))  # per pair
    index_of = {pair: index for index, pair in enumerate(pairs.names)}
    for pair in minima:  # a pair pruned somewhere: its minimum there is only bounded
        index = index_of[pair.a, pair.b]
        if measured[index] < len(t) and not pairs.is_fixed[index]:
            pair.lower_bound_m = float(clear_s[index] + margin)
    minima.sort(key=lambda pair: pair.distance_m)
    stretches.sort(key=lambda stretch: stretch.sample_start)
    for pair in minima[:n_worst]:
        if pair.exact_distance_m is None:
            index = index_of[pair.a, pair.b]
            pair.exact_distance_m = pairs.exact(at_index(q, pair.sample), index)
        e, d = pair.exact_distance_m, pair.drake_distance_m
        if not (e == 0.0 and d <= 0.0) and abs(e - d) > EXACT_MISMATCH_TOL_M:
            pair.note = f"Drake {d * 1e3:.2f} mm, exact {e * 1e3:.2f} mm"
            notes.append(f"{pair.a} vs {pair.b} at σ = {pair.sigma_m:.4f} m: {pair.note}")
    by_point = np.lexsort((dist, x))  # by point, the closest first
    overlaps = by_point[dist[by_point] < -TOUCH_TOL_M]
    first = entry(int(overlaps[0])) if len(overlaps) else None
    stretch = next(
        (
            r
            for r in stretches
            if first
            and (r.a, r.b) == (first.a, first.b)
            and r.sample_start <= first.sample <= r.sample_end
        ),
        None,
    )
    # The closest approach of what moves; the fixed layout (a base on its floor) is
    # listed with the pairs and fails only by overlapping.
    moving = [m for m in minima if not pairs.is_fixed[index_of[m.a, m.b]]]
    closest = moving[0] if moving else (minima[0] if minima else None)
    min_distance = closest.distance_m if closest else np.inf
    evaluated = np.unique(x)
    samples = int(np.sum(evaluated == np.floor(evaluated)))
    stats = {
        "samples": len(t),
        "checked_samples": samples,
        "pruned_samples": len(t) - samples,
        "substeps": len(evaluated) - samples,
        "distance_queries": pairs.evaluations,
        "exact_checks": pairs.exact_checks,
        "motion_radii_m": rho.tolist(),
        "elapsed_s": time.perf_counter() - start,
    }
    below = np.unique(np.floor(x[dist < limit]).astype(int)).tolist()
    margin = {(p.a, p.b): p.distance_m - clear_s[index_of[p.a, p.b]] for p in minima}
    violation = min(minima, key=lambda p: margin[(p.a, p.b)], default=None)
    violated = violation is not None and margin[(violation.a, violation.b)] < 0
    violation_clearance = clear_s[index_of[violation.a, violation.b]] if violated else 0
    return CollisionResult(
        clearance,
        not violated,
        float(min_distance),
        closest,
        minima,
        minima[:n_worst],
        stretches,
        below,
        first,
        list(cell.allowed_contact),
        failure_message(first, stretch, violation if violated else None, violation_clearance),
        notes,
        stats,
        self_clearance,
        cell.skipped_self_pairs,
        cell.held_contacts,
    )
