"""How far the planned path on the part moves: a tool moved by d moves every path point
by |d| (and tilts nothing), a grasp turned about the tool's tip moves nothing at the tip
where it turns, and the calibrated flange path is the one the plan's own FlangePath
gives for the calibrated frames."""

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw

from offline_prog.calibration.path_shift import moved_flange, shift_along
from offline_prog.path.arc_length import ArcLengthPath
from offline_prog.path.bspline_fit import fit_bspline
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.path.process_frames import constant_normal, process_frames

from conftest import random_curve_points, random_transform


def seam(rng):
    points = random_curve_points(rng, closed=False)
    points[:, 2] = 0.0
    path = ArcLengthPath(fit_bspline(points, closed=False, tolerance_m=1e-5))
    normal = constant_normal([0.0, 0.0, -1.0])
    s = np.linspace(0.0, path.length, 400)
    return path, normal, s, path(s, order=0)[0], process_frames(path, normal, s)[0]


def test_a_moved_tool_moves_the_path_by_as_much(rng):
    path, normal, s, p_PF, R_PF = seam(rng)
    X_IT, X_PE = random_transform(rng), random_transform(rng, 0.3)
    d = np.array([0.0012, -0.0005, 0.0009])
    move, tilt = shift_along(
        p_PF,
        R_PF,
        X_IT=X_IT,
        X_PE=X_PE,
        X_IT_new=RigidTransform(X_IT.rotation(), X_IT.translation() + d),
        X_PE_new=X_PE,
    )
    assert np.allclose(move, np.linalg.norm(d), atol=1e-12) and np.allclose(tilt, 0.0, atol=1e-7)
    same = shift_along(p_PF, R_PF, X_IT=X_IT, X_PE=X_PE, X_IT_new=X_IT, X_PE_new=X_PE)
    assert np.allclose(same[0], 0.0, atol=1e-12) and np.allclose(same[1], 0.0, atol=1e-7)


def test_a_part_turned_about_a_path_point_keeps_that_point(rng):
    """X_PE' = X_PE turned by 1° about the path's point k (in P): the path point there
    stays, the others move by up to 1° times their distance from it."""
    path, normal, s, p_PF, R_PF = seam(rng)
    X_IT, X_PE = random_transform(rng), random_transform(rng, 0.3)
    k = 150
    turn = RigidTransform(p_PF[k]) @ RigidTransform(RollPitchYaw(0, 0, np.radians(1.0)), [0, 0, 0])
    X_PE_new = turn @ RigidTransform(-p_PF[k]) @ X_PE
    move, tilt = shift_along(p_PF, R_PF, X_IT=X_IT, X_PE=X_PE, X_IT_new=X_IT, X_PE_new=X_PE_new)
    assert move[k] < 1e-12
    assert np.allclose(move, 2 * np.sin(np.radians(0.5)) * np.linalg.norm(p_PF - p_PF[k], axis=1))
    assert np.allclose(np.degrees(tilt), 1.0)


def test_the_calibrated_flange_path_is_the_plans_for_the_calibrated_frames(rng):
    path, normal, s, _, _ = seam(rng)
    X_IT, X_PE = random_transform(rng), random_transform(rng, 0.3)
    X_IT_new = X_IT @ RigidTransform(RollPitchYaw(0.01, -0.02, 0.005), [0.002, 0.001, -0.003])
    X_PE_new = RigidTransform(RollPitchYaw(0.0, 0.01, 0.02), [0.001, 0.0, 0.002]) @ X_PE
    p_IE, R_IE = FlangePath(path, normal, X_IT=X_IT, X_PE=X_PE).poses(s)
    expected = FlangePath(path, normal, X_IT=X_IT_new, X_PE=X_PE_new).poses(s)[0]
    moved = moved_flange(p_IE, R_IE, X_IT=X_IT, X_PE=X_PE, X_IT_new=X_IT_new, X_PE_new=X_PE_new)
    assert np.abs(moved - expected).max() < 1e-12
