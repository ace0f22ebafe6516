"""Small array helpers shared by the planning stages and the writers."""

import itertools

import numpy as np


def true_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Half-open index ranges [start, stop) where a 1-D boolean mask is True."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], np.asarray(mask, dtype=int), [0]])))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _fold_columns(ufunc: np.ufunc, x: np.ndarray) -> np.ndarray:
    """(...) ``ufunc`` applied across the last axis of x (..., K), K ≥ 1, one column at
    a time into a new array."""
    x = np.asarray(x)
    out = np.array(x[..., 0])
    for k in range(1, x.shape[-1]):
        ufunc(out, x[..., k], out=out)
    return out


def row_max(x: np.ndarray) -> np.ndarray:
    """(...) the largest entry along the last axis of x (..., K), K ≥ 1: the numbers of
    ``x.max(axis=-1)`` (NaN where a row holds one), several times faster for a short
    axis such as a robot's six joints, which numpy reduces element by element."""
    return _fold_columns(np.maximum, x)


def row_min(x: np.ndarray) -> np.ndarray:
    """(...) the smallest entry along the last axis of x (..., K): ``x.min(axis=-1)``'s
    numbers, as :func:`row_max` gives ``x.max(axis=-1)``'s."""
    return _fold_columns(np.minimum, x)


def at_index(values: np.ndarray, x: float):
    """values (N, ...) linearly interpolated at the fractional sample index x."""
    i = min(int(x), len(values) - 2) if len(values) > 1 else 0
    return values[i] + (x - i) * (values[i + 1] - values[i]) if x != i else values[i]


def interp_rows(x: np.ndarray, xp: np.ndarray, *tables: np.ndarray) -> list[np.ndarray]:
    """Each table (G, K) linearly interpolated at x (N,) over the strictly increasing
    grid xp (G ≥ 2), held at its ends like ``np.interp``; one index search for all
    columns.

    Returns:
        [(N, K), ...], one per table.
    """
    i = np.clip(np.searchsorted(xp, x, side="right") - 1, 0, len(xp) - 2)
    w = np.clip((x - xp[i]) / (xp[i + 1] - xp[i]), 0.0, 1.0)[:, None]
    # t[i + 1] − t[i] taken from the grid's differences (G − 1 rows, usually far fewer
    # than N): the same numbers, one gather less per table.
    return [np.take(t, i, axis=0) + w * np.take(np.diff(t, axis=0), i, axis=0) for t in tables]


def csv_text(
    header: list[str], columns: list[np.ndarray], formats: list[str] | None = None, *, nan="nan"
) -> str:
    """CSV text: the header line, then one line per row of ``columns`` (each (N,)).

    Number columns are printed with their ``formats`` entry (default ``%.10g``; NaN as
    ``nan``, or as the given text, e.g. empty), text (object or str) columns as they
    are. One %-format over the whole table: the same text as formatting each cell with
    ``np.char.mod`` and joining, in a fifth of the time (7,000 rows × 36 columns).
    """
    formats = formats or ["%.10g"] * len(columns)
    cells, line = [], []
    for column, fmt in zip(columns, formats, strict=True):
        column = np.asarray(column)
        if column.dtype.kind in "OUS":
            cells.append(column.astype(str).tolist())
            line.append("%s")
            continue
        missing = np.isnan(column) if column.dtype.kind == "f" else np.zeros(0, dtype=bool)
        if nan != "nan" and missing.any():
            values = column.tolist()
            cells.append([nan if m else fmt % v for v, m in zip(values, missing, strict=True)])
            line.append("%s")
        else:
            cells.append(column.tolist())
            line.append(fmt)
    rows = len(cells[0]) if cells else 0
    body = ((",".join(line) + "\n") * rows) % tuple(
        itertools.chain.from_iterable(zip(*cells, strict=True))
    )
    return ",".join(header) + "\n" + body
