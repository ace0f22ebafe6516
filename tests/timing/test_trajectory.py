"""Workspace trajectory (paper §4, eq. 9): TCP speed, velocities, angles, seams."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from offline_prog.timing.trajectory import plan_workspace_trajectory, tait_bryan_xyz

from conftest import random_flange_path, rotation_log

SPEED = 0.1
LIMITS = {"v_max": SPEED, "a_max": 1.0, "j_max": 10.0}


@pytest.mark.parametrize("closed", [False, True])
def test_tcp_speed_follows_the_profile(rng, closed):
    flange = random_flange_path(rng, closed=closed)
    tr = plan_workspace_trajectory(flange, rate_hz=2000.0, **LIMITS)
    # Rigid-body speed of the part point under the TCP equals the commanded σ̇.
    np.testing.assert_allclose(tr.tcp_speed, tr.s_dot, atol=1e-9 * SPEED)
    # From positions alone: the path point moves at σ̇ (better than 0.05 %).
    chord = np.linalg.norm(np.diff(tr.flange.p_PF, axis=0), axis=1) / np.diff(tr.t)
    at_speed = tr.s_dot >= SPEED * (1 - 1e-12)
    cruise = at_speed[:-1] & at_speed[1:]
    assert cruise.sum() > 100
    assert np.abs(chord[cruise] - SPEED).max() <= 5e-4 * SPEED
    assert tr.s[-1] == pytest.approx(flange.length, abs=1e-12)


def test_velocities_match_finite_differences_of_poses(rng):
    flange = random_flange_path(rng, closed=False)
    tr = plan_workspace_trajectory(flange, rate_hz=1000.0, **LIMITS)
    dt = np.diff(tr.t)[:-1]
    mid = slice(1, -1)
    v_fd = (tr.flange.p_IE[2:] - tr.flange.p_IE[:-2]) / (2 * dt[:, None])
    assert np.abs(v_fd - tr.v_IE[mid]).max() <= 1e-3 * np.abs(tr.v_IE).max()
    a_fd = (tr.v_IE[2:] - tr.v_IE[:-2]) / (2 * dt[:, None])
    assert np.abs(a_fd - tr.a_IE[mid]).max() <= 1e-2 * np.abs(tr.a_IE).max()
    R = tr.flange.R_IE
    w_fd = rotation_log(R[2:] @ np.swapaxes(R[:-2], 1, 2)) / (2 * dt[:, None])
    assert np.abs(w_fd - tr.w_IE_I[mid]).max() <= 1e-3 * np.abs(tr.w_IE_I).max()
    dw_fd = (tr.w_IE_I[2:] - tr.w_IE_I[:-2]) / (2 * dt[:, None])
    assert np.abs(dw_fd - tr.dw_IE_I[mid]).max() <= 1e-2 * np.abs(tr.dw_IE_I).max()
    # Rest to rest.
    for v in (tr.v_IE, tr.w_IE_I):
        assert np.abs(v[[0, -1]]).max() == 0.0


def test_tait_bryan_xyz_convention_and_unwrap(rng):
    angles = np.cumsum(rng.normal(scale=0.3, size=(400, 3)), axis=0)
    angles[:, 1] = np.clip(angles[:, 1], -1.4, 1.4)
    R = Rotation.from_euler("XYZ", angles).as_matrix()  # intrinsic X-Y-Z: Rx·Ry·Rz
    np.testing.assert_allclose(
        R[5],
        Rotation.from_euler("x", angles[5, 0]).as_matrix()
        @ Rotation.from_euler("y", angles[5, 1]).as_matrix()
        @ Rotation.from_euler("z", angles[5, 2]).as_matrix(),
        atol=1e-12,
    )
    recovered = tait_bryan_xyz(R)
    offset = np.round((recovered[0] - angles[0]) / (2 * np.pi)) * 2 * np.pi
    np.testing.assert_allclose(recovered - offset, angles, atol=1e-9)


def test_closed_path_is_seamless_and_turns_once(rng):
    flange = random_flange_path(rng, closed=True, planar=True)
    tr = plan_workspace_trajectory(flange, **LIMITS)
    f0, f1 = flange(np.array([0.0])), flange(np.array([flange.length]))
    np.testing.assert_allclose(f0.p_IE, f1.p_IE, atol=1e-9)
    np.testing.assert_allclose(f0.R_IE, f1.R_IE, atol=1e-9)
    np.testing.assert_allclose(f0.dp_IE, f1.dp_IE, atol=1e-6)
    np.testing.assert_allclose(f0.w_s, f1.w_s, atol=1e-5)
    # The surface normal of a planar contour stays on the tool's y axis, so the part turns about
    # y_T only, and a closed contour makes exactly one full turn: ∫ w·y_T dt = ±2π.
    y_T = flange.X_IT.rotation().matrix()[:, 1]
    np.testing.assert_allclose(np.cross(tr.w_IE_I, y_T), 0.0, atol=1e-9)
    turn = np.trapezoid(tr.w_IE_I @ y_T, tr.t)
    assert abs(turn) == pytest.approx(2 * np.pi, rel=1e-3)


def test_flange_speed_reference_holds_flange_speed(rng):
    flange = random_flange_path(rng, closed=False)
    tr = plan_workspace_trajectory(flange, reference="flange", rate_hz=1000.0, **LIMITS)
    _, lam_dot, _, _ = tr.law(tr.t)
    np.testing.assert_allclose(np.linalg.norm(tr.v_IE, axis=1), lam_dot, atol=1e-9)
    chord = np.linalg.norm(np.diff(tr.flange.p_IE, axis=0), axis=1) / np.diff(tr.t)
    at_speed = lam_dot >= SPEED * (1 - 1e-12)
    cruise = at_speed[:-1] & at_speed[1:]
    assert cruise.sum() > 100
    assert np.abs(chord[cruise] - SPEED).max() <= 5e-4 * SPEED


def test_sample_rate_and_duration(rng):
    flange = random_flange_path(rng, closed=False)
    tr = plan_workspace_trajectory(flange, rate_hz=250.0, **LIMITS)
    assert np.allclose(np.diff(tr.t)[:-1], 1 / 250)
    assert tr.t[-1] == pytest.approx(tr.law.duration)
