"""True arc-length parameterization: unit speed, inverse, known lengths."""

import numpy as np
import pytest

from offline_prog.path.arc_length import ArcLengthPath
from offline_prog.path.bspline_fit import fit_bspline

from conftest import random_curve_points


@pytest.mark.parametrize("closed", [False, True])
def test_unit_speed_and_inverse(rng, closed):
    path = ArcLengthPath(fit_bspline(random_curve_points(rng, closed=closed), closed=closed))
    s = rng.uniform(0, path.length, 500)
    r, r1, r2, r3 = path(s)
    np.testing.assert_allclose(np.linalg.norm(r1, axis=1), 1.0, atol=1e-12)
    u = path.parameter(s, order=0)[0]
    np.testing.assert_allclose(path.map.s_of_u(u), s, atol=1e-11)
    # r'' ⟂ r' for a unit-speed curve, and derivatives agree with finite differences.
    np.testing.assert_allclose(np.einsum("ij,ij->i", r1, r2), 0.0, atol=1e-8)
    h = 1e-5
    s_in = np.clip(s, 2 * h, path.length - 2 * h)
    for k, (lo, hi) in enumerate(zip(path(s_in - h)[:3], path(s_in + h)[:3], strict=True)):
        fd = (hi - lo) / (2 * h)
        exact = path(s_in)[k + 1]
        assert np.abs(fd - exact).max() <= 1e-5 * max(1.0, np.abs(exact).max())


def test_circle_length_is_true_arc_length_not_polygon():
    radius = 0.25
    phi = np.linspace(0, 2 * np.pi, 24, endpoint=False)  # coarse polygon: eq. 2 is 0.3 % short
    points = radius * np.stack([np.cos(phi), np.sin(phi), 0 * phi], axis=1)
    fit = fit_bspline(points, closed=True, n_control_points=24)
    path = ArcLengthPath(fit)
    assert fit.period < 2 * np.pi * radius * (1 - 2e-3)  # polygon length (eq. 2)
    # The spline interpolates 24 points of the circle; its length is the circle's
    # to within the fit's radial wobble.
    assert path.length == pytest.approx(2 * np.pi * radius, rel=5e-4)
    # Independent check by brute-force polyline on a very fine sampling.
    dense = fit(np.linspace(0, fit.period, 200001))
    polyline = np.linalg.norm(np.diff(dense, axis=0), axis=1).sum()
    assert path.length == pytest.approx(polyline, rel=1e-9)
