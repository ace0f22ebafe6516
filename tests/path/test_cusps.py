"""Cusps and flange-speed peaks (paper §4) and their bounded-deviation smoothing."""

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw

from offline_prog.path.arc_length import ArcLengthPath
from offline_prog.path.bspline_fit import fit_bspline
from offline_prog.path.cusps import SmoothedFlangePath, find_cusps
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.path.process_frames import constant_normal
from offline_prog.path.sources import arc_points, line_points, resample_polyline
from offline_prog.timing.trajectory import plan_workspace_trajectory


def corner_path(flange_in_P, radius=0.02):
    """Line, quarter arc of ``radius`` about (0, 0), line — with the flange at
    ``flange_in_P`` (in the path's plane; under it by 0.1 m)."""
    arc = arc_points([0, 0, 0], radius, -90, 0, closed=False)
    before = line_points([-0.1, -radius, 0], arc[0])
    after = line_points(arc[-1], [radius, 0.1, 0])
    points = resample_polyline(np.vstack([before, arc[1:], after[1:]]), 5e-4)
    path = ArcLengthPath(fit_bspline(points, closed=False, tolerance_m=2e-5))
    X_IT = RigidTransform(RollPitchYaw(-np.pi / 2, 0, 0), [1.0, 0, 0.5])
    return FlangePath(
        path, constant_normal([0, 0, -1]), X_IT=X_IT, X_PE=RigidTransform(flange_in_P)
    )


def test_flange_at_the_curvature_center_is_a_cusp():
    # On the arc the part turns about the arc's center; a flange there stands still.
    flange = corner_path([0.0, 0.0, 0.0])
    cusps = find_cusps(flange)
    kinds = [c.kind for c in cusps]
    assert "cusp" in kinds
    cusp = cusps[kinds.index("cusp")]
    arc_start, arc_end = 0.1 - 0.02, 0.1 - 0.02 + np.pi * 0.02 / 2
    assert arc_start - 1e-3 <= cusp.sigma_m <= arc_end + 1e-3
    assert cusp.flange_speed_ratio < 0.05
    assert cusp.angular_rate_rad_per_m == pytest.approx(1 / 0.02, rel=0.05)


def test_flange_far_from_the_corner_gives_a_speed_peak():
    flange = corner_path([0.2, -0.2, -0.1])  # far from the arc's axis of rotation
    cusps = find_cusps(flange)
    assert [c.kind for c in cusps] == ["speed_peak"]
    # On the arc the part turns about the arc's axis: flange speed per TCP speed is
    # the flange's distance from that axis times the curvature 1/r.
    lever = np.linalg.norm([0.2, -0.2])
    assert cusps[0].flange_speed_ratio == pytest.approx(lever / 0.02, rel=0.05)


def test_straight_path_has_no_cusps():
    points = line_points([0, 0, 0], [0.2, 0.05, 0])
    path = ArcLengthPath(fit_bspline(points, closed=False))
    flange = FlangePath(
        path, constant_normal([0, 0, -1]), X_IT=RigidTransform(), X_PE=RigidTransform([0, 0, -0.1])
    )
    assert find_cusps(flange) == []


def test_smoothing_bounds_the_deviation_and_lowers_the_peak_acceleration():
    exact = corner_path([0.2, -0.2, -0.1])
    smooth = SmoothedFlangePath(exact, max_deviation_m=2e-3)
    s = np.linspace(0, exact.length, 4001)
    deviation = np.linalg.norm(smooth(s).p_IE - exact(s).p_IE, axis=1)
    assert deviation.max() <= 2e-3 + 1e-9
    assert smooth.max_deviation_m == pytest.approx(deviation.max(), rel=0.05)
    limits = {"v_max": 0.05, "a_max": 1.0, "j_max": 10.0}
    a_exact = plan_workspace_trajectory(exact, **limits).a_IE
    a_smooth = plan_workspace_trajectory(smooth, **limits).a_IE
    assert np.linalg.norm(a_smooth, axis=1).max() < np.linalg.norm(a_exact, axis=1).max()
