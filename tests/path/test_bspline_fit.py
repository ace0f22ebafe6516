"""B-spline fit (paper §2): tolerance, seam continuity, control-point choice."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from offline_prog.path.bspline_fit import chord_length_parameter, fit_bspline

from conftest import random_curve_points


@pytest.mark.parametrize("closed", [False, True])
@pytest.mark.parametrize("tolerance_m", [1e-4, 1e-5])
def test_every_point_within_tolerance(rng, closed, tolerance_m):
    for _ in range(5):
        points = random_curve_points(rng, closed=closed)
        fit = fit_bspline(points, closed=closed, tolerance_m=tolerance_m)
        assert fit.degree == 5
        assert fit.max_error_m <= tolerance_m
        assert fit.rms_error_m <= fit.max_error_m
        # Independent check: distance to a dense sampling of the curve.
        dense = fit(np.linspace(0, fit.period, 400001))
        dist, _ = cKDTree(dense).query(points)
        gap = np.linalg.norm(np.diff(dense, axis=0), axis=1).max() / 2
        assert dist.max() <= tolerance_m + gap


def test_fewest_control_points_chosen(rng):
    points = random_curve_points(rng, closed=False)
    fit = fit_bspline(points, closed=False, tolerance_m=1e-4)
    fewer = fit_bspline(points, closed=False, n_control_points=fit.n_control_points - 1)
    assert fewer.max_error_m > 1e-4


def test_explicit_control_points(rng):
    points = random_curve_points(rng, closed=True)
    fit = fit_bspline(points, closed=True, n_control_points=40)
    assert fit.n_control_points == 40
    assert len(fit.spline.c) == 40 + fit.degree


def test_closed_spline_is_seamless_up_to_degree_minus_one(rng):
    points = random_curve_points(rng, closed=True)
    fit = fit_bspline(points, closed=True, degree=6)
    scale = fit.period
    for nu in range(fit.degree):  # derivatives 0 .. p−1 continuous
        left = fit(np.array([fit.period - 1e-9]), nu)
        right = fit(np.array([0.0]), nu)
        magnitude = np.abs(fit(np.linspace(0, fit.period, 500), nu)).max()
        assert np.abs(left - right).max() <= 1e-6 * magnitude * max(1.0, scale)


def test_open_spline_interpolates_ends_closely(rng):
    points = random_curve_points(rng, closed=False)
    fit = fit_bspline(points, closed=False)
    assert np.linalg.norm(fit(np.array([0.0]))[0] - points[0]) <= 1e-4
    assert np.linalg.norm(fit(np.array([fit.period]))[0] - points[-1]) <= 1e-4


def test_chord_length_parameter_matches_paper_eq_2():
    points = np.array([[0, 0, 0], [3, 4, 0], [3, 4, 12.0]])
    u, period = chord_length_parameter(points, closed=False)
    np.testing.assert_allclose(u, [0, 5, 17])
    assert period == 17
    _, closed_period = chord_length_parameter(points, closed=True)
    assert closed_period == pytest.approx(30.0)


def test_rejects_low_degree_and_too_few_points(rng):
    points = random_curve_points(rng, closed=False)
    with pytest.raises(ValueError, match="degree 3 < 5"):
        fit_bspline(points, closed=False, degree=3)
    with pytest.raises(ValueError, match="at least 6"):
        fit_bspline(points[:4], closed=False)
    with pytest.raises(ValueError, match="n_control_points"):
        fit_bspline(points, closed=False, n_control_points=2)


def test_points_no_spline_can_follow_get_a_plain_reason_not_an_absurd_error(rng):
    """Scattered or back-and-forth points made the fit diverge and the message quote
    'best 2.22e+87 mm'; now it says what is wrong with the points."""
    import warnings

    scattered = rng.uniform(0.0, 0.2, size=(300, 3))
    zigzag = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]] * 100) + rng.normal(0, 1e-6, (200, 3))
    for points in (scattered, zigzag):
        with warnings.catch_warnings(), pytest.raises(ValueError) as error:
            warnings.simplefilter("ignore", RuntimeWarning)
            fit_bspline(points, closed=False, tolerance_m=1e-4)
        message = str(error.value)
        assert "do not trace a curve" in message and "e+" not in message
