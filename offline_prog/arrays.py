"""Small array helpers shared by the planning stages."""

import numpy as np


def true_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Half-open index ranges [start, stop) where a 1-D boolean mask is True."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], np.asarray(mask, dtype=int), [0]])))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def at_index(values: np.ndarray, x: float):
    """values (N, ...) linearly interpolated at the fractional sample index x."""
    i = min(int(x), len(values) - 2) if len(values) > 1 else 0
    return values[i] + (x - i) * (values[i + 1] - values[i]) if x != i else values[i]
