"""The shared array helpers give numpy's own numbers (seeded property tests)."""

import numpy as np
import pytest

from offline_prog.arrays import interp_rows, row_max, row_min, true_runs


@pytest.mark.parametrize("shape", [(1, 1), (7, 6), (3000, 6), (8, 400, 6), (5, 3), (4, 2, 9)])
def test_row_max_and_min_are_numpys_reductions(rng, shape):
    """Bit for bit, NaN where a row holds one, ±inf kept; the input untouched."""
    for _ in range(5):
        x = rng.normal(size=shape) * 10.0 ** rng.integers(-3, 4)
        x[rng.random(shape) < 0.02] = np.nan
        x[rng.random(shape) < 0.02] = np.inf
        x[rng.random(shape) < 0.02] = -np.inf
        before = x.copy()
        np.testing.assert_array_equal(row_max(x), x.max(axis=-1))
        np.testing.assert_array_equal(row_min(x), x.min(axis=-1))
        np.testing.assert_array_equal(x, before)
    one = rng.normal(size=(4, 1))
    assert not np.shares_memory(row_max(one), one)  # a copy, even of a single column


def test_true_runs_and_interp_rows(rng):
    mask = rng.random(200) < 0.5
    runs = true_runs(mask)
    rebuilt = np.zeros(200, dtype=bool)
    for a, b in runs:
        rebuilt[a:b] = True
    assert np.array_equal(rebuilt, mask)
    xp = np.sort(rng.uniform(0, 1, 50))
    table = rng.normal(size=(50, 3))
    x = rng.uniform(-0.1, 1.1, 300)
    (got,) = interp_rows(x, xp, table)
    want = np.column_stack([np.interp(x, xp, table[:, k]) for k in range(3)])
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-14)
