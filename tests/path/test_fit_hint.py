"""The fit's control-point count kept between runs (path.fit_hint): the same spline, bit
for bit, from one fit instead of the search; a bad or missing hint costs the search."""

import numpy as np
import pytest

from offline_prog.path import bspline_fit
from offline_prog.path.bspline_fit import fit_bspline

from conftest import random_curve_points


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("OFFLINE_PROG_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache" / "fits"


@pytest.fixture
def fits_made(monkeypatch):
    """How many least-squares fits fit_bspline computes (trials of its search)."""
    made = []
    original = bspline_fit.fit_on_knots

    def counted(*args, **kwargs):
        made.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(bspline_fit, "fit_on_knots", counted)
    return made


def assert_same(a, b):
    np.testing.assert_array_equal(a.spline.t, b.spline.t)
    np.testing.assert_array_equal(a.spline.c, b.spline.c)
    assert (a.max_error_m, a.rms_error_m, a.closed, a.period) == (
        b.max_error_m,
        b.rms_error_m,
        b.closed,
        b.period,
    )


@pytest.mark.parametrize("closed", [False, True])
def test_a_kept_count_gives_the_searched_spline_from_one_fit(rng, cache, fits_made, closed):
    for tolerance_m in (1e-4, 1e-5):
        points = random_curve_points(rng, closed=closed)
        searched = fit_bspline(points, closed=closed, tolerance_m=tolerance_m)
        trials = len(fits_made)
        assert trials > 3 and len(list(cache.iterdir())) >= 1
        again = fit_bspline(points, closed=closed, tolerance_m=tolerance_m)
        assert len(fits_made) == trials + 1  # the kept count's fit alone
        assert_same(again, searched)
        fits_made.clear()


def test_another_tolerance_or_point_is_another_search(rng, cache, fits_made):
    points = random_curve_points(rng, closed=False)
    fit_bspline(points, closed=False, tolerance_m=1e-4)
    for tolerance_m, moved in ((1e-5, 0.0), (1e-4, 1e-9)):
        fits_made.clear()
        changed = points.copy()
        changed[7, 0] += moved
        fresh = fit_bspline(changed, closed=False, tolerance_m=tolerance_m)
        assert len(fits_made) > 1  # searched
        assert fresh.max_error_m <= tolerance_m
    assert len(list(cache.iterdir())) == 3


@pytest.mark.parametrize("kept", ["6", "100000", "not a number", ""])
def test_a_count_that_does_not_hold_is_searched_again(rng, cache, kept):
    """A count below the tolerance's (degree + 1 control points), out of range, or
    unreadable: the search's answer all the same."""
    points = random_curve_points(rng, closed=True)
    searched = fit_bspline(points, closed=True, tolerance_m=1e-5)
    (entry,) = cache.iterdir()
    entry.write_text(kept)
    assert_same(fit_bspline(points, closed=True, tolerance_m=1e-5), searched)
    assert entry.read_text() == str(searched.n_control_points)  # kept again


def test_a_cache_that_cannot_be_written_still_fits(rng, tmp_path, monkeypatch):
    blocked = tmp_path / "blocked"
    blocked.write_text("a file where the cache folder would be")
    monkeypatch.setenv("OFFLINE_PROG_CACHE", str(blocked))
    points = random_curve_points(rng, closed=False)
    fit = fit_bspline(points, closed=False, tolerance_m=1e-4)
    assert fit.max_error_m <= 1e-4
    assert [p.name for p in tmp_path.iterdir()] == ["blocked"]  # no temporary file left
