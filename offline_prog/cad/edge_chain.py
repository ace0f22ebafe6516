"""Chains of connected edges through picked ones, on any model that numbers its edges
and their end vertices (a STEP model's B-rep edges, a mesh's runs of feature edges).

``model.edge_ends[k]`` is (first, last) vertex number of edge k in its own direction,
``model.edge_lengths[k]`` its length [mm]; a closed edge has first == last.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from offline_prog.cad.picking import PickError


def chain(model, picked: list[int], key: str) -> list[tuple[int, bool]]:
    """(edge number, reversed) from the first picked edge to the last through the others,
    each stretch between two picks along the shortest connected route of edges.

    Raises:
        PickError: picked edges that no route of model edges joins, or a route that
            runs an edge twice.
    """
    n_vertices = 1 + max(v for ends in model.edge_ends for v in ends)
    run: list[tuple[int, bool]] = []
    first = picked[0]
    a, b = model.edge_ends[first]
    if len(picked) == 1 or picked[1] == first:
        return [(first, False)]
    for target in picked[1:]:
        if target == (run[-1][0] if run else first):
            continue
        used = {e for e, _ in run} | {first, target}
        graph, via = _graph(model, n_vertices, used)
        starts = [b] if run else [a, b]  # the first edge may run either way
        if run:
            last, backwards = run[-1]
            ends = model.edge_ends[last]
            starts = [ends[0] if backwards else ends[1]]
        best = None
        for start in starts:
            dist, previous = dijkstra(graph, indices=start, return_predecessors=True)
            for entry in model.edge_ends[target]:
                if np.isfinite(dist[entry]) and (best is None or dist[entry] < best[0]):
                    best = (dist[entry], start, entry, previous)
        if best is None:
            raise PickError(
                f"{key}.chain.near_mm",
                f"the chain's edges do not connect: no run of model edges joins edge "
                f"{(run[-1][0] if run else first)} to edge {target}",
            )
        _, start, entry, previous = best
        if not run:
            run.append((first, start == a))
        vertices = [entry]
        while vertices[-1] != start:
            vertices.append(int(previous[vertices[-1]]))
        for u, v in zip(vertices[::-1][:-1], vertices[::-1][1:], strict=True):
            edge = via[(u, v)]
            run.append((edge, model.edge_ends[edge][0] != u))
        target_ends = model.edge_ends[target]
        run.append((target, target_ends[0] != entry))
    numbers = [e for e, _ in run]
    if len(set(numbers)) != len(numbers):
        raise PickError(f"{key}.chain.near_mm", f"the chain runs an edge twice ({numbers})")
    return run


def _graph(model, n: int, excluded: set[int]):
    """Vertices joined by edges (weight: length) not in ``excluded``; the edge of each
    (vertex, vertex) step, the shortest where several join the same two."""
    via: dict[tuple[int, int], int] = {}
    for k, (u, v) in enumerate(model.edge_ends):
        if k in excluded or u == v:
            continue
        for step in ((u, v), (v, u)):
            if step not in via or model.edge_lengths[k] < model.edge_lengths[via[step]]:
                via[step] = k
    rows = [u for u, _ in via] or [0]
    cols = [v for _, v in via] or [0]
    weights = [model.edge_lengths[k] for k in via.values()] or [0.0]
    return csr_matrix((weights, (rows, cols)), shape=(n, n)), via
