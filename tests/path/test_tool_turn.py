"""A symmetric tool turned along the path (path.tool_turn): the process pose still
holds (path point on the TCP, surface normal on the tool axis), the derivatives are
exact, the part's turn through a corner is spread out, and the free rotation's bound
holds for every turn the planner tries."""

import numpy as np
import pytest

from offline_prog.joints.joint_plan import tool_rotations
from offline_prog.path.arc_length import ArcLengthPath
from offline_prog.path.bspline_fit import fit_bspline
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.path.process_frames import constant_normal
from offline_prog.path.tool_turn import SmoothTurn, turn_rates
from offline_prog.plan import ROBOTS_DIR
from offline_prog.stages import fit_path, load_inputs

from conftest import CELLS, random_flange_path

Y = np.array([0.0, 1.0, 0.0])


def rounded_rectangle() -> ArcLengthPath:
    """The seal demo's 360 x 260 mm border, corner radius 30 mm, closed [m]."""
    inputs = load_inputs(CELLS / "seal_plate_kr16.yaml", ROBOTS_DIR)
    return fit_path(inputs).path


def flange_turn_rate(flange: FlangePath, s: np.ndarray) -> np.ndarray:
    """(N,) the flange's turn about the tool axis per metre of path [rad/m]."""
    axis_I = flange.X_IT.rotation().matrix() @ flange.axis
    return flange(s).w_s @ axis_I


@pytest.mark.parametrize("closed", [False, True])
def test_process_pose_holds_and_derivatives_are_exact(rng, closed):
    for _ in range(3):
        base = random_flange_path(rng, closed=closed)
        turn = SmoothTurn(base.path, base.normal, axis="y", width_m=0.02, offset_rad=0.3)
        flange = FlangePath(
            base.path, base.normal, X_IT=base.X_IT, X_PE=base.X_PE, tool_turn=turn, axis=Y
        )
        s = rng.uniform(0.01, flange.length - 0.01, 200)
        f = flange(s)
        R_PE, p_PE = flange.X_PE.rotation().matrix(), flange.X_PE.translation()
        R_IP = f.R_IE @ R_PE.T
        p_IP = f.p_IE - np.einsum("nij,j->ni", R_IP, p_PE)
        # The path point is under the TCP and the normal n is on the tool's y axis.
        p_I_path = p_IP + np.einsum("nij,nj->ni", R_IP, f.p_PF)
        np.testing.assert_allclose(p_I_path - flange.X_IT.translation(), 0.0, atol=1e-12)
        R_IT = flange.X_IT.rotation().matrix()
        n_I = np.einsum("nij,nj->ni", R_IP, f.R_PF[:, :, 1])
        np.testing.assert_allclose(n_I, np.tile(R_IT[:, 1], (200, 1)), atol=1e-12)
        # φ′ and φ″ against central differences of φ and φ′.
        h = 1e-5
        phi, dphi, ddphi = turn(s)
        np.testing.assert_allclose(
            dphi, (turn(s + h)[0] - turn(s - h)[0]) / (2 * h), atol=1e-5 * (1 + np.abs(dphi).max())
        )
        np.testing.assert_allclose(
            ddphi,
            (turn(s + h)[1] - turn(s - h)[1]) / (2 * h),
            atol=1e-4 * (1 + np.abs(ddphi).max()),
        )


def test_corner_turn_is_spread_and_the_seam_joins():
    path = rounded_rectangle()
    normal = constant_normal([0.0, 0.0, 1.0])
    turn = SmoothTurn(path, normal, axis="y", width_m=0.03)
    s = np.linspace(0.0, path.length, 6001)
    rate = turn_rates(path, normal, s, 1)[0]
    # Fixed turn: the part turns 90° in each 47 mm corner arc at 1/(30 mm) (more where
    # the fit rounds the step in curvature).
    assert np.abs(rate).max() >= 0.95 / 0.030
    assert abs(np.trapezoid(rate, s)) == pytest.approx(2 * np.pi, rel=1e-4)
    smooth = rate - turn(s)[1]  # the part's turn rate with the tool taking up φ′
    assert np.abs(smooth).max() < 0.7 * np.abs(rate).max()
    assert abs(np.trapezoid(smooth, s)) == pytest.approx(2 * np.pi, rel=1e-4)  # same total
    # The turn's change, which the wrist's acceleration and jerk follow, is 10x gentler.
    assert np.abs(np.gradient(smooth, s)).max() < 0.1 * np.abs(np.gradient(rate, s)).max()
    # Closed: the tool turn joins at the seam (φ, φ′, φ″ agree at 0 and L).
    ends = np.array([v for v in turn(np.array([0.0, path.length]))])
    np.testing.assert_allclose(ends[:, 0], ends[:, 1], atol=1e-6 * (1 + np.abs(ends).max()))


@pytest.mark.parametrize(("bound_deg", "width_mm"), [(90.0, 30.0), (10.0, 30.0), (10.0, 5.0)])
def test_every_turn_tried_stays_within_the_free_rotation(bound_deg, width_mm):
    inputs = load_inputs(CELLS / "seal_plate_kr16.yaml", ROBOTS_DIR)
    fit = fit_path(inputs)
    turn = SmoothTurn(fit.path, fit.normal, axis="y", width_m=width_mm * 1e-3)
    bound = np.deg2rad(bound_deg)
    rotations = tool_rotations(
        inputs.robot,
        inputs.X_IB,
        fit.path,
        fit.normal,
        X_IT=inputs.X_IT,
        X_PE=inputs.X_PE,
        bound_rad=bound,
        smooth_turn=turn,
    )
    # The outermost φ₀ each way, every 12 µm (between the splines' 0.5 mm nodes).
    fine = np.linspace(0.0, fit.path.length, 100_001)
    for _, flange in (min(rotations, key=lambda r: r[0]), max(rotations, key=lambda r: r[0])):
        assert np.abs(flange.tool_turn(fine)[0]).max() <= bound
    s = fine[::50]
    for _, flange in rotations:
        # The part's turn is the same everywhere up to a constant: θ̄ less φ₀.
        rate = flange_turn_rate(flange, s)
        np.testing.assert_allclose(rate, flange_turn_rate(rotations[0][1], s), atol=1e-9)
    # θ − θ̄ spans ~55° on this border at 30 mm, ~18° at 5 mm: where the free
    # rotation is wider φ₀ moves within it, else one φ₀ takes up a share of the turn.
    low, high = turn.span_rad
    assert (len(rotations) > 1) == (high - low < 2 * bound)
    assert (bound_deg, width_mm) != (10.0, 30.0) or len(rotations) == 1


def test_open_path_turn_holds_its_ends(rng):
    points = np.column_stack(
        [np.linspace(0, 0.3, 40), 0.05 * np.sin(np.linspace(0, 6, 40)), np.zeros(40)]
    )
    path = ArcLengthPath(fit_bspline(points, closed=False, tolerance_m=1e-6))
    turn = SmoothTurn(path, constant_normal([0, 0, 1]), axis="y", width_m=0.02)
    phi = turn(np.linspace(0, path.length, 500))[0]
    assert np.isfinite(phi).all() and np.abs(phi).max() < np.pi
