"""Short motions merged along the planned path (export.merge): on seeded random pose
paths sampled far closer than 0.5 mm, the merged motions are at least 0.5 mm long
where no pinned point stops them, pinned points stay, and every planned sample a merged
motion passes lies within the path tolerance of what the controller runs, checked here
independently (scipy's Slerp, the tool's curve on the part on a fine grid)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

from offline_prog.export.merge import MIN_MOTION_M, PathCheck, merge_short

CHORD_TOL_M, ANGLE_TOL_RAD = 0.05e-3, np.deg2rad(0.1)
GRID = 200


def random_path(rng, n=300):
    """(n, 4, 4) X_BP: the part moving past a fixed tool along a curve, gentle in its
    first half and turning at radii of about 0.5 mm in its second (where merging to
    0.5 mm breaks the tolerance), samples 0.01 to 0.2 mm apart; X_BT (4, 4)."""
    steps = rng.uniform(0.01e-3, 0.2e-3, n - 1)
    s = np.concatenate([[0.0], np.cumsum(steps)])
    tight = np.where(s > s[-1] / 2, 0.5e-3 * np.sin((s - s[-1] / 2) / 0.5e-3), 0.0)
    X_BP = np.tile(np.eye(4), (n, 1, 1))
    X_BP[:, :3, 3] = np.column_stack([0.8 + s, 0.002 * np.sin(40 * s) + tight, 0.3 + 0.001 * s])
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    X_BP[:, :3, :3] = Rotation.from_rotvec(np.outer(s * 5.0, axis)).as_matrix()
    X_BT = np.eye(4)
    X_BT[:3, 3] = [0.8, 0.0, 0.5]
    return X_BP, X_BT


def tool_on_part(X_BP, X_BT):
    return np.einsum("nji,nj->ni", X_BP[:, :3, :3], X_BT[:3, 3] - X_BP[:, :3, 3])


def independent_deviation(X_BP, X_BT, a, b) -> float:
    """Largest distance [m] of the tool's planned points on the part between samples a
    and b from its curve while the controller moves P linearly (slerp) from a to b."""
    lam = np.linspace(0, 1, GRID + 1)
    R = Slerp([0, 1], Rotation.from_matrix(X_BP[[a, b], :3, :3]))(lam).as_matrix()
    p = X_BP[a, :3, 3] + lam[:, None] * (X_BP[b, :3, 3] - X_BP[a, :3, 3])
    curve = np.einsum("gji,gj->gi", R, X_BT[:3, 3] - p)
    planned = tool_on_part(X_BP[a : b + 1], X_BT)
    return float(np.linalg.norm(planned[:, None] - curve[None], axis=2).min(axis=1).max())


@pytest.mark.parametrize("seed", range(2))
def test_merged_motions_are_long_hold_the_tolerance_and_keep_pinned_points(seed):
    rng = np.random.default_rng(seed)
    X_BP, X_BT = random_path(rng)
    points = list(range(len(X_BP)))
    pinned = set(rng.choice(points[1:-1], 5, replace=False).tolist())
    check = PathCheck(X_BP, X_BT, CHORD_TOL_M, ANGLE_TOL_RAD)
    merged = check.merge(points, pinned)
    assert pinned <= set(merged) and merged[0] == 0 and merged[-1] == len(X_BP) - 1
    p, ends = X_BP[:, :3, 3], [None, *merged, None]
    kept = pinned | {0, len(X_BP) - 1}
    for m in range(1, len(ends) - 2):
        before, a, b, after = ends[m - 1 : m + 3]
        assert independent_deviation(X_BP, X_BT, a, b) <= CHORD_TOL_M + 1e-7
        if np.linalg.norm(p[b] - p[a]) < MIN_MOTION_M:  # only where no merge holds
            for drop, i, j in ((b, a, after), (a, before, b)):
                if drop not in kept:
                    assert independent_deviation(X_BP, X_BT, i, j) > CHORD_TOL_M - 1e-6
    half = np.searchsorted(merged, len(X_BP) // 2)
    assert half < len(X_BP) / 2 / 3  # the gentle half: most merged


def test_nothing_merges_where_the_path_or_the_writer_forbids():
    rng = np.random.default_rng(7)
    X_BP, X_BT = random_path(rng, n=50)
    points = list(range(50))
    check = PathCheck(X_BP, X_BT, 1e-12, 1e-12)  # no merged motion holds this
    assert check.merge(points, set()) == points
    check = PathCheck(X_BP, X_BT, CHORD_TOL_M, ANGLE_TOL_RAD)
    assert check.merge(points, set(), lambda i, k, j: False) == points  # the writer forbids
    p = np.zeros((50, 3))
    assert merge_short(points, p, pinned=set(points), fits=lambda i, k, j: True) == points


def test_a_free_end_slides_away_from_a_pinned_point_where_no_merge_holds():
    """A switch point pinned 0.4 mm after a point on a gentle arc (radius 10 mm, samples
    0.1 mm apart), the motion before 2 mm long: dropping the free point cuts the arc by
    more than the tolerance, so it slides back along the samples instead: every motion
    is then at least 0.5 mm long and holds the tolerance, the pinned point stays."""
    radius, n = 10e-3, 61
    angle = np.arange(n) * 0.1e-3 / radius
    X_BP = np.tile(np.eye(4), (n, 1, 1))
    X_BP[:, :3, 3] = -radius * np.column_stack([np.sin(angle), 1 - np.cos(angle), 0 * angle])
    X_BT = np.eye(4)  # the tool's point on the part: the arc itself
    points, pinned = [0, 20, 24, 60], {24}
    check = PathCheck(X_BP, X_BT, CHORD_TOL_M, ANGLE_TOL_RAD)
    assert independent_deviation(X_BP, X_BT, 0, 24) > CHORD_TOL_M  # 20 may not go
    p = X_BP[:, :3, 3]
    stays = merge_short(points, p, pinned=pinned, fits=lambda i, k, j: check.fits(i, j))
    assert stays == points  # without sliding the 0.4 mm motion stays
    merged = check.merge(points, pinned)
    assert 24 in merged and merged[0] == 0 and merged[-1] == 60 and len(merged) == 4
    for a, b in zip(merged[:-2], merged[1:-1], strict=True):  # the last motion was long
        assert np.linalg.norm(p[b] - p[a]) >= MIN_MOTION_M
        assert independent_deviation(X_BP, X_BT, a, b) <= CHORD_TOL_M + 1e-7
