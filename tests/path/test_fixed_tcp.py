"""The flange path X_IE = X_IT · X_PF⁻¹ · X_PE (paper §3), checked as a user would:
the part point under the fixed TCP is the path point, with the tool axes on [t n b]."""

import numpy as np
import pytest

from offline_prog.path.process_frames import NormalTangentError, constant_normal, process_frames

from conftest import random_flange_path, rotation_log


@pytest.mark.parametrize("closed", [False, True])
def test_part_point_under_tcp_stays_on_path(rng, closed):
    for _ in range(5):
        flange = random_flange_path(rng, closed=closed)
        s = rng.uniform(0, flange.length, 300)
        f = flange(s)
        R_PE = flange.X_PE.rotation().matrix()
        p_PE = flange.X_PE.translation()
        # X_IP = X_IE · X_PE⁻¹ from the flange pose alone.
        R_IP = f.R_IE @ R_PE.T
        p_IP = f.p_IE - np.einsum("nij,j->ni", R_IP, p_PE)
        p_I_path = p_IP + np.einsum("nij,nj->ni", R_IP, f.p_PF)
        np.testing.assert_allclose(
            p_I_path, np.broadcast_to(flange.X_IT.translation(), p_I_path.shape), atol=1e-12
        )
        # Tool axes match [t n b] of the process frame, expressed in I.
        R_IT = flange.X_IT.rotation().matrix()
        np.testing.assert_allclose(R_IP @ f.R_PF, np.broadcast_to(R_IT, f.R_PF.shape), atol=1e-12)


def test_process_frames_are_right_handed_tnb(rng):
    flange = random_flange_path(rng, closed=True)
    s = np.linspace(0, flange.length, 400)
    R, _, _ = process_frames(flange.path, flange.normal, s)
    np.testing.assert_allclose(
        R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape), atol=1e-12
    )
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    _, t, _, _ = flange.path(s)
    np.testing.assert_allclose(R[:, :, 0], t, atol=1e-12)
    # n is the given normal with its tangential part removed.
    n_given = np.array([0.1, -0.2, -1.0]) / np.linalg.norm([0.1, -0.2, -1.0])
    expected = n_given - np.einsum("ij,j->i", t, n_given)[:, None] * t
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    np.testing.assert_allclose(R[:, :, 1], expected, atol=1e-12)


@pytest.mark.parametrize("closed", [False, True])
def test_s_derivatives_match_finite_differences(rng, closed):
    flange = random_flange_path(rng, closed=closed)
    h = 1e-5
    s = rng.uniform(2 * h, flange.length - 2 * h, 200)
    f, lo, hi = flange(s), flange(s - h), flange(s + h)
    scale = np.abs(f.dp_IE).max()
    assert np.abs((hi.p_IE - lo.p_IE) / (2 * h) - f.dp_IE).max() <= 1e-6 * scale
    assert np.abs((hi.dp_IE - lo.dp_IE) / (2 * h) - f.ddp_IE).max() <= 1e-5 * np.abs(f.ddp_IE).max()
    # Angular velocity per metre from the rotation change over ±h, in I.
    w_fd = rotation_log(hi.R_IE @ np.swapaxes(lo.R_IE, 1, 2)) / (2 * h)
    assert np.abs(w_fd - f.w_s).max() <= 1e-5 * np.abs(f.w_s).max()
    assert np.abs((hi.w_s - lo.w_s) / (2 * h) - f.dw_s).max() <= 1e-5 * np.abs(f.dw_s).max()


def test_normal_parallel_to_tangent_is_rejected(rng):
    flange = random_flange_path(rng, closed=False)
    s = np.linspace(0, flange.length, 50)
    _, t, _, _ = flange.path(s)
    with pytest.raises(NormalTangentError, match="of the path tangent at s ="):
        process_frames(flange.path, constant_normal(-t[10]), s)


def test_tool_turn_about_the_symmetry_axis(rng):
    """With φ(s) about y of T the part point stays under the TCP, the normal stays on
    the tool axis, and the analytic s-derivatives match finite differences."""
    from offline_prog.path.fixed_tcp import FlangePath

    base = random_flange_path(rng, closed=False)

    def turn(s):
        return 0.4 * np.sin(5 * s), 2.0 * np.cos(5 * s), -10.0 * np.sin(5 * s)

    flange = FlangePath(base.path, base.normal, X_IT=base.X_IT, X_PE=base.X_PE, tool_turn=turn)
    h = 1e-5
    s = rng.uniform(2 * h, flange.length - 2 * h, 150)
    f, lo, hi = flange(s), flange(s - h), flange(s + h)
    R_IP = f.R_IE @ base.X_PE.rotation().matrix().T
    p_IP = f.p_IE - np.einsum("nij,j->ni", R_IP, base.X_PE.translation())
    np.testing.assert_allclose(
        p_IP + np.einsum("nij,nj->ni", R_IP, f.p_PF),
        np.broadcast_to(base.X_IT.translation(), f.p_PF.shape),
        atol=1e-12,
    )
    y_T = base.X_IT.rotation().matrix()[:, 1]
    np.testing.assert_allclose(
        (R_IP @ f.R_PF)[:, :, 1], np.broadcast_to(y_T, (len(s), 3)), atol=1e-12
    )
    angle = np.arctan2(
        np.cross(base.X_IT.rotation().matrix()[:, 0], (R_IP @ f.R_PF)[:, :, 0]) @ y_T,
        (R_IP @ f.R_PF)[:, :, 0] @ base.X_IT.rotation().matrix()[:, 0],
    )
    np.testing.assert_allclose(angle, turn(s)[0], atol=1e-12)
    assert np.abs((hi.p_IE - lo.p_IE) / (2 * h) - f.dp_IE).max() <= 1e-6 * np.abs(f.dp_IE).max()
    assert np.abs((hi.dp_IE - lo.dp_IE) / (2 * h) - f.ddp_IE).max() <= 1e-5 * np.abs(f.ddp_IE).max()
    w_fd = rotation_log(hi.R_IE @ np.swapaxes(lo.R_IE, 1, 2)) / (2 * h)
    assert np.abs(w_fd - f.w_s).max() <= 1e-5 * np.abs(f.w_s).max()
    assert np.abs((hi.w_s - lo.w_s) / (2 * h) - f.dw_s).max() <= 1e-5 * np.abs(f.dw_s).max()


def _fresh(flange, s):
    """The flange samples with nothing kept from earlier evaluations."""
    from offline_prog.path import fixed_tcp

    fixed_tcp._part_samples.clear()
    fixed_tcp._part_in_tool.clear()
    return flange(s)


@pytest.mark.parametrize("closed", [False, True])
def test_kept_part_values_give_the_same_flange_poses(rng, closed):
    """Tool rotations, session edits and placement candidates evaluate one path on one σ
    grid with other X_IT, X_PE and tool-turn offsets: each answer is the one computed
    from scratch, bit for bit, and no caller can change a kept array."""
    from offline_prog.path.fixed_tcp import FlangePath
    from offline_prog.path.tool_turn import SmoothTurn

    from conftest import random_transform

    base = random_flange_path(rng, closed=closed)
    s = np.linspace(0.0, base.length, 400)
    turn = SmoothTurn(base.path, base.normal, axis="y", width_m=0.02)
    variants = [
        FlangePath(base.path, base.normal, X_IT=X_IT, X_PE=X_PE, tool_turn=t, axis=(0, 1, 0))
        for X_PE in (base.X_PE, random_transform(rng, 0.3))
        for X_IT in (base.X_IT, random_transform(rng))
        for t in (None, turn, turn.with_offset(0.2), turn.with_offset(-0.4, 0.5))
    ]
    grids = [s, np.sort(rng.uniform(0.0, base.length, 300))]
    expected = [[_fresh(flange, grid) for grid in grids] for flange in variants]
    for _ in range(2):  # kept values are reused on the second pass and later
        for flange, wanted in zip(variants, expected, strict=True):
            for grid, want in zip(grids, wanted, strict=True):
                got = flange(grid)
                for name in ("p_PF", "R_PF", "p_IE", "dp_IE", "ddp_IE", "R_IE", "w_s", "dw_s"):
                    np.testing.assert_array_equal(getattr(got, name), getattr(want, name))
    with pytest.raises(ValueError, match="read-only"):
        variants[0](s).p_PF[0, 0] = 1.0


def test_kept_part_values_stay_within_their_bytes(rng, monkeypatch):
    """The kept evaluations are the last used ones, PART_CACHE_BYTES in all: a grid used
    again is kept (the same arrays), the oldest goes first."""
    from offline_prog.path import fixed_tcp

    base = random_flange_path(rng, closed=False)
    grids = [np.linspace(0.0, base.length, n) for n in (300, 301, 302, 303)]
    one = sum(v.nbytes for v in fixed_tcp.part_samples(base.path, base.normal, grids[3]))
    monkeypatch.setattr(fixed_tcp, "PART_CACHE_BYTES", 3 * one)  # three entries fit
    fixed_tcp._part_samples.clear()
    first = fixed_tcp.part_samples(base.path, base.normal, grids[0])
    for grid in grids[1:3]:
        fixed_tcp.part_samples(base.path, base.normal, grid)
    assert fixed_tcp.part_samples(base.path, base.normal, grids[0])[0] is first[0]  # kept
    fixed_tcp.part_samples(base.path, base.normal, grids[3])  # grids[1] is the oldest now
    assert sum(entry[1] for entry in fixed_tcp._part_samples.values()) <= 3 * one
    assert fixed_tcp.part_samples(base.path, base.normal, grids[0])[0] is first[0]
    again = fixed_tcp.part_samples(base.path, base.normal, grids[1])
    np.testing.assert_array_equal(again[0], base.path(grids[1], order=2)[0])
    assert len(fixed_tcp._part_samples) == 3
    kept = fixed_tcp._part_samples
    assert kept.nbytes == sum(entry[1] for entry in kept.values())  # the running sum
