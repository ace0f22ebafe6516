"""The smallest distance per pair group over time (clearance.csv, the report's plot)."""

from __future__ import annotations

import numpy as np

from offline_prog.collision.pairs import Pairs
from offline_prog.scene.drake_cell import DrakeCell

PROFILE_POINTS = 400  # samples of the distance-over-time profile (report plot)


def distance_profile(
    cell: DrakeCell, q: np.ndarray, t: np.ndarray, n_points: int = PROFILE_POINTS
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Smallest signed distance per pair group over time, for plots.

    Args:
        cell: the cell with its shapes; q: (N, 6) joint path [rad]; t: (N,) times [s].
        n_points: how many evenly spaced samples to evaluate.

    Returns:
        (t_k (K,), {group: (K,) smallest Drake signed distance in that group [m]}).
    """
    pairs = Pairs(cell)
    index = np.unique(np.linspace(0, len(q) - 1, min(n_points, len(q))).astype(int))
    profile = {group: np.full(len(index), np.inf) for group in sorted(set(pairs.groups))}
    for k, i in enumerate(index):
        pairs.set(q[i])
        for g in range(len(pairs.ids)):
            group = profile[pairs.groups[pairs.shape_of[g]]]
            group[k] = min(group[k], pairs.distance(g))
    return t[index], profile
