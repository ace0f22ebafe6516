"""The batched point selection (export.deviation, density.select_points,
points.process_points) chooses the same program points, with the same stated
deviations, as asking one segment at a time did (tests/selection_reference.py,
the code before it was batched): on the demo job's seams and on seeded random pose
paths with straight runs, pure reorientations and turns through π."""

import dataclasses

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from offline_prog.export.densify import densify
from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M, select_points
from offline_prog.export.deviation import segment_deviations
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.points import PointRule, process_points

from selection_reference import (
    reference_process_points,
    reference_select_points,
    segment_deviation,
)

RELATIVE = 1e-12  # deviations may differ in the last bits of a float sum, no more
# Angles come from arccos of a trace (both codes): a last-bit change of the trace moves
# a small angle a by ~1e-16 / a [rad].
ANGLE_ABS = 1e-10


def random_poses(rng, n: int, *, turns: float) -> np.ndarray:
    """(n, 4, 4) a smooth random pose path [m] with straight runs, standstills (pure
    reorientation) and ``turns`` full turns of orientation over its length."""
    step = rng.normal(scale=2e-4, size=(n, 3)) + np.sin(np.linspace(0, 9, n))[:, None] * 1e-3
    step[rng.random(n) < 0.1] = 0.0  # standstills: the orientation alone moves
    straight = slice(n // 3, n // 3 + n // 8)
    step[straight] = step[straight.start]  # a straight run
    axis = np.cumsum(rng.normal(scale=0.05, size=(n, 3)), axis=0) + [0.0, 0.0, 1.0]
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    angle = np.linspace(0.0, 2 * np.pi * turns, n) + rng.normal(scale=1e-3, size=n)
    X = np.tile(np.eye(4), (n, 1, 1))
    X[:, :3, :3] = Rotation.from_rotvec(axis * angle[:, None]).as_matrix()
    X[:, :3, 3] = np.cumsum(step, axis=0)
    return X


@pytest.mark.parametrize("seed", range(4))
def test_segment_deviations_are_those_of_one_segment_at_a_time(seed):
    rng = np.random.default_rng(seed)
    X = random_poses(rng, 400, turns=1.5)
    p, R = X[:, :3, 3], X[:, :3, :3]
    i = rng.integers(0, 390, size=200)
    j = np.minimum(i + rng.integers(0, 200, size=200), 399)
    d, a = segment_deviations(p, R, i, j)
    want = np.array([segment_deviation(p, R, int(x), int(y)) for x, y in zip(i, j, strict=True)])
    np.testing.assert_allclose(d, want[:, 0], rtol=RELATIVE, atol=1e-15)
    np.testing.assert_allclose(a, want[:, 1], rtol=RELATIVE, atol=ANGLE_ABS)
    assert (d[j - i < 2] == 0).all() and (a[j - i < 2] == 0).all()


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("tolerance", [1.0, 0.2, 5.0])
def test_select_points_chooses_the_points_of_one_segment_at_a_time(seed, tolerance):
    rng = np.random.default_rng(seed)
    X = random_poses(rng, int(rng.integers(50, 900)), turns=float(rng.uniform(0, 3)))
    p, R = X[:, :3, 3], X[:, :3, :3]
    tol = {"chord_tol_m": tolerance * 1e-4, "angle_tol_rad": tolerance * np.deg2rad(0.5)}
    got, want = select_points(p, R, **tol), reference_select_points(p, R, **tol)
    np.testing.assert_array_equal(got.indices, want.indices)
    assert got.max_chord_m == pytest.approx(want.max_chord_m, rel=RELATIVE, abs=1e-15)
    assert got.max_angle_rad == pytest.approx(want.max_angle_rad, rel=RELATIVE, abs=ANGLE_ABS)
    assert got.max_chord_m <= tol["chord_tol_m"] and got.max_angle_rad <= tol["angle_tol_rad"]


@pytest.fixture(scope="module")
def seal_job(planned_job):
    """The demo job's data as the writers read it (its plan folder)."""
    _, folder = planned_job("seal_job_kr16")
    return JobProgramData.load(folder)


STYLES = [("external_tcp", "X_TP"), ("external_tcp", "X_PF"), ("flange", "X_TP")]


@pytest.mark.parametrize(("style", "convention"), STYLES)
def test_process_points_of_the_demo_seams_are_unchanged(seal_job, style, convention):
    for seam in seal_job.seams:
        dense = densify(seam, DEFAULT_CHORD_TOL_M, DEFAULT_ANGLE_TOL_RAD)
        tol = dense.selection_tolerances(DEFAULT_CHORD_TOL_M, DEFAULT_ANGLE_TOL_RAD)
        got = process_points(dense.data, PointRule(style, convention), *tol)
        want = reference_process_points(dense.data, style, *tol, convention)
        np.testing.assert_array_equal(got[0], want[0])
        assert got[1] == pytest.approx(want[1], rel=RELATIVE, abs=1e-15)
        assert got[2] == pytest.approx(want[2], rel=RELATIVE, abs=ANGLE_ABS)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize(("style", "convention"), STYLES)
def test_process_points_of_random_paths_are_unchanged(seal_job, seed, style, convention):
    """A demo seam's record carrying a random path of tool frames X_PT (and the flange
    poses X_BE = X_BT X_PT⁻¹ X_EP⁻¹ that go with them)."""
    rng = np.random.default_rng(seed)
    seam = seal_job.seams[0]
    X_PT = random_poses(rng, int(rng.integers(50, 700)), turns=float(rng.uniform(0, 2)))
    X_BE = seam.X_BT @ np.linalg.inv(X_PT) @ np.linalg.inv(seam.X_EP)
    data = dataclasses.replace(seam, X_PT=X_PT, X_BE=X_BE)
    got = process_points(data, PointRule(style, convention), 1e-4, np.deg2rad(0.5))
    want = reference_process_points(data, style, 1e-4, np.deg2rad(0.5), convention)
    np.testing.assert_array_equal(got[0], want[0])
    assert got[1] == pytest.approx(want[1], rel=RELATIVE, abs=1e-15)
    assert got[2] == pytest.approx(want[2], rel=RELATIVE, abs=ANGLE_ABS)
