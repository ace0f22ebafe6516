"""A flying seam's leads (path.lead): the flange path run on past both seam ends is as
smooth there as the seam (position, velocity, acceleration; angular velocity and its
rate), starts on the seam's tangent and lifts off the part, and changes nothing on the
seam itself."""

import dataclasses
import pickle

import cloudpickle
import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix

from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.path.lead import (
    MAX_LIFT_RATIO,
    ROTATION_RATE_STEP_M,
    LeadPath,
    path_ends,
)

from conftest import random_flange_path, rotation_log

LEAD_M = 0.03


def _jumps(lead: LeadPath, end: float, h: float = 1e-7) -> dict[str, float]:
    """Each field's change across the seam end over ±h, per metre of path."""
    f = lead(np.array([end - h, end + h]))
    return {
        k: float(np.abs(np.diff(getattr(f, k), axis=0)).max())
        for k in ("p_IE", "dp_IE", "ddp_IE", "w_s", "dw_s")
    }


@pytest.mark.parametrize("closed", [False, True])
def test_the_leads_join_the_seam_smoothly(rng, closed):
    """Across σ = 0 and σ = L the flange's position, its first two σ-derivatives, its
    angular velocity and its rate change no more than a smooth path's do over 2e-7 m
    (the joints' q, q̇ and q̈ are continuous where the plan crosses them at speed)."""
    for _ in range(3):
        flange = random_flange_path(rng, closed=closed)
        lead = LeadPath(flange, lead_in_m=LEAD_M, lead_out_m=LEAD_M)
        for end in (0.0, flange.length):
            f = flange(np.array([end]))
            scale = {
                "p_IE": np.abs(f.dp_IE).max(),
                "dp_IE": np.abs(f.ddp_IE).max() + 1.0,
                "ddp_IE": 1e3,  # the third derivative is not matched (a jerk step)
                "w_s": np.abs(f.dw_s).max() + 1.0,
                "dw_s": 1e3,
            }
            for key, jump in _jumps(lead, end).items():
                assert jump <= 2e-7 * scale[key] * 10, (key, end, jump)


def test_lead_derivatives_match_finite_differences(rng):
    flange = random_flange_path(rng, closed=False)
    lead = LeadPath(flange, lead_in_m=LEAD_M, lead_out_m=LEAD_M)
    h = 1e-6
    for s in (
        rng.uniform(-LEAD_M + 2 * h, -2 * h, 50),
        rng.uniform(2 * h, LEAD_M - 2 * h, 50) + flange.length,
    ):
        f, lo, hi = lead(s), lead(s - h), lead(s + h)
        np.testing.assert_allclose((hi.p_IE - lo.p_IE) / (2 * h), f.dp_IE, atol=1e-7)
        np.testing.assert_allclose((hi.dp_IE - lo.dp_IE) / (2 * h), f.ddp_IE, atol=1e-5)
        w_fd = rotation_log(hi.R_IE @ np.swapaxes(lo.R_IE, 1, 2)) / (2 * h)
        np.testing.assert_allclose(w_fd, f.w_s, atol=1e-6)
        np.testing.assert_allclose((hi.w_s - lo.w_s) / (2 * h), f.dw_s, atol=1e-4)


def test_the_lead_in_starts_on_the_tangent_and_lifts_off_the_part(rng):
    """The tool point T in P: within the lead's first tenth it is off the seam's tangent
    line by at most a thousandth of the lift; at the lead's far end it has backed off
    the surface (against n) by the lift (LIFT_RATIO of its extent along the tangent)."""
    flange = random_flange_path(rng, closed=False)
    lead = LeadPath(flange, lead_in_m=LEAD_M, lead_out_m=0.0)
    start = flange(np.array([0.0]))
    p0, t0, n0 = start.p_PF[0], start.R_PF[0][:, 0], start.R_PF[0][:, 1]
    near = lead(np.linspace(-0.1 * LEAD_M, 0.0, 20)).p_PF - p0
    off_line = near - np.outer(near @ t0, t0)
    lift = lead.lifts_m[0]
    assert np.linalg.norm(off_line, axis=1).max() <= 2e-3 * lift + 0.5 * (0.1 * LEAD_M) ** 2 * 50
    far = lead(np.array([-LEAD_M])).p_PF[0] - p0
    assert far @ t0 < 0.0  # before the start
    assert -(far @ n0) == pytest.approx(lift, rel=0.2)  # backed off against n


def test_leads_of_zero_change_nothing_on_the_seam(rng):
    flange = random_flange_path(rng, closed=True)
    lead = LeadPath(flange, lead_in_m=0.0, lead_out_m=0.0, reason="entry: rest")
    s = np.linspace(0.0, flange.length, 101)
    ours, theirs = lead(s), flange(s)
    for key in ("p_IE", "dp_IE", "ddp_IE", "R_IE", "w_s", "dw_s", "p_PF", "R_PF"):
        np.testing.assert_array_equal(getattr(ours, key), getattr(theirs, key))
    assert path_ends(lead) == (0.0, flange.length) and not lead.flying
    with pytest.raises(ValueError, match="no lead"):
        lead(np.array([-1e-3]))


@pytest.mark.parametrize("closed", [False, True])
@pytest.mark.parametrize("lift", [0.0, 0.05])
def test_a_lead_is_parameterized_by_the_tools_path_length(rng, closed, lift):
    """On both leads the tool point moves in P by dσ per dσ (|dp_PT/dσ| = 1 within
    1e-4, the chords' shortfall), so the time law's σ̇ ≤ v caps the tool's speed there
    as on the seam, and a lead's tool path is as long as the lead; a lead that takes
    over a 50 mm normal move too."""
    for _ in range(3):
        flange = random_flange_path(rng, closed=closed)
        lead = LeadPath(flange, lead_in_m=LEAD_M, lead_out_m=LEAD_M, lifts_m=(lift, lift))
        for length in (lead.lead_in_m, lead.lead_out_m):  # as asked; longer for the lift
            assert length == pytest.approx(LEAD_M, rel=1e-8) or (lift and length > LEAD_M)
        for s in (
            np.linspace(-LEAD_M, 0.0, 3001),
            np.linspace(0.0, LEAD_M, 3001) + flange.length,
        ):
            p = lead(s).p_PF
            rate = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(s)
            assert np.abs(rate - 1.0).max() <= 1e-4, np.abs(rate - 1.0).max()


def test_a_lead_that_takes_a_normal_move_over_lifts_by_its_distance(rng):
    """Lifted to the approach's 50 mm, the lead's far end is 50 mm off the surface
    (against n) and its extent along the tangent at least MAX_LIFT_RATIO below the
    lift; its first tenth still hugs the tangent."""
    flange = random_flange_path(rng, closed=False)
    lead = LeadPath(flange, lead_in_m=LEAD_M, lead_out_m=0.0, lifts_m=(0.05, 0.0))
    assert lead.lifts_m == (0.05, 0.0)
    start = flange(np.array([0.0]))
    p0, t0, n0 = start.p_PF[0], start.R_PF[0][:, 0], start.R_PF[0][:, 1]
    far = lead(np.array([-lead.lead_in_m])).p_PF[0] - p0
    assert -(far @ n0) == pytest.approx(0.05, rel=0.2)
    assert -(far @ t0) >= 0.05 / MAX_LIFT_RATIO * 0.8
    extent = -(far @ t0)
    near = lead(np.linspace(-0.1 * extent, 0.0, 20)).p_PF - p0
    assert np.abs(near @ n0).max() <= 2e-3 * 0.05 + 0.5 * (0.1 * extent) ** 2 * 50


def test_leads_around_their_own_path_are_the_fresh_ones(rng):
    """``around`` the path they were built on, the leads are kept (their tables are not
    built again) and equal leads built afresh, sample for sample; around another path
    of the seam (the same fit, another tool placement) they are built anew for it and
    differ."""
    flange = random_flange_path(rng, closed=False)
    lead = LeadPath(flange, lead_in_m=LEAD_M, lead_out_m=LEAD_M, lifts_m=(0.05, 0.0))
    s = np.concatenate([np.linspace(-LEAD_M, 0.0, 30), flange.length + np.linspace(0, LEAD_M, 30)])
    fresh = LeadPath(flange, **lead.asked)
    kept = lead.around(flange)
    assert kept is lead
    for field in ("p_IE", "dp_IE", "ddp_IE", "R_IE", "w_s", "dw_s", "p_PF", "R_PF"):
        np.testing.assert_array_equal(getattr(kept(s), field), getattr(fresh(s), field))
    other = FlangePath(flange.path, flange.normal, X_IT=flange.X_IT, X_PE=_turned(flange.X_PE))
    moved = lead.around(other)
    assert moved is not lead and moved.inner is other
    np.testing.assert_array_equal(moved(s).p_IE, LeadPath(other, **lead.asked)(s).p_IE)
    assert np.abs(moved(s).p_IE - lead(s).p_IE).max() > 1e-3


def test_the_rotation_rate_is_the_central_difference_of_the_rotations_rate(rng):
    """On a real lead, the rotation, its rate w_s and the rate's rate evaluated at u and
    u ± ROTATION_RATE_STEP_M in one go are, bit for bit, those evaluated one point set
    at a time (the central difference of w_s over the step), and the rate's rate is a
    five-point difference of w_s over a wider step to 1e-9 of its scale."""
    flange = random_flange_path(rng, closed=False)
    lead = LeadPath(flange, lead_in_m=LEAD_M, lead_out_m=LEAD_M, lifts_m=(0.05, 0.0))
    step = ROTATION_RATE_STEP_M
    for end in lead._ends:
        u = end.side * end.extent * np.linspace(0.0, 1.0, 257)
        R_IE, w_u, dw_u = lead._rotation(end, u)
        alone = [lead._rotation(end, x[None]) for x in (*u, *(u + step), *(u - step))]
        rotations, rates = np.array([a[0][0] for a in alone]), np.array([a[1][0] for a in alone])
        np.testing.assert_array_equal(R_IE, rotations[: len(u)])
        np.testing.assert_array_equal(w_u, rates[: len(u)])
        np.testing.assert_array_equal(
            dw_u, (rates[len(u) : 2 * len(u)] - rates[2 * len(u) :]) / (2 * step)
        )
        untimed = lead._rotation(end, u, pose=False)
        assert untimed[0] is None
        np.testing.assert_array_equal(untimed[1], w_u)
        np.testing.assert_array_equal(untimed[2], dw_u)
        h = 1e-3  # the five-point difference (error ∝ h⁴): the rate's rate is smooth in u
        w = [lead._rotation(end, u + k * h)[1] for k in (-2, -1, 1, 2)]
        fd = (w[0] - 8.0 * w[1] + 8.0 * w[2] - w[3]) / (12.0 * h)
        assert np.abs(fd - dw_u).max() <= 1e-9 * np.abs(dw_u).max()


def test_joined_leads_are_the_ones_asked_for(rng):
    """The lead-in of one LeadPath and the lead-out of another around the same flange
    path, joined: their tables are kept (not built again) and the path equals the one
    built afresh for those two leads, sample for sample; around two paths: refused."""
    flange = random_flange_path(rng, closed=False)
    plain = LeadPath(flange, lead_in_m=LEAD_M, lead_out_m=LEAD_M)
    lifted = LeadPath(flange, lead_in_m=0.04, lead_out_m=0.05, lifts_m=(0.05, 0.05))
    s = np.concatenate([np.linspace(-0.04, 0.0, 40), flange.length + np.linspace(0, LEAD_M, 30)])
    for first, second in ((lifted, plain), (plain, lifted)):
        joined = LeadPath.joined(first, second)
        assert joined._ends[0] is first._ends[0] and joined._ends[1] is second._ends[1]
        asked = {
            "lead_in_m": first.asked["lead_in_m"],
            "lead_out_m": second.asked["lead_out_m"],
            "lifts_m": (first.asked["lifts_m"][0], second.asked["lifts_m"][1]),
        }
        fresh = LeadPath(flange, **asked)
        assert joined.asked == fresh.asked and joined.reason == fresh.reason == ""
        assert (joined.lead_in_m, joined.lead_out_m) == (fresh.lead_in_m, fresh.lead_out_m)
        assert joined.lifts_m == fresh.lifts_m
        at = s[s >= joined.start] if first is plain else s
        for field in ("p_IE", "dp_IE", "ddp_IE", "R_IE", "w_s", "dw_s", "p_PF", "R_PF"):
            np.testing.assert_array_equal(getattr(joined(at), field), getattr(fresh(at), field))
    other = FlangePath(flange.path, flange.normal, X_IT=flange.X_IT, X_PE=_turned(flange.X_PE))
    with pytest.raises(ValueError, match="two flange paths"):
        LeadPath.joined(plain, LeadPath(other, lead_in_m=LEAD_M, lead_out_m=LEAD_M))


def test_an_evaluation_at_the_same_sigma_is_kept_read_only(rng):
    """Asked again at the same σ (bit for bit), a path with leads returns the samples it
    returned (read-only), equal to a fresh path's; at other σ it evaluates them; pickled,
    it leaves the kept samples out and evaluates the same."""
    flange = random_flange_path(rng, closed=False)
    lead = LeadPath(flange, lead_in_m=LEAD_M, lead_out_m=LEAD_M, lifts_m=(0.05, 0.0))
    s = np.linspace(lead.start, lead.end, 301)
    first = lead(s)
    assert lead(s.copy()) is first
    fresh = LeadPath(flange, **lead.asked)(s)
    for field in dataclasses.fields(first):
        value = getattr(first, field.name)
        assert not value.flags.writeable, field.name
        np.testing.assert_array_equal(value, getattr(fresh, field.name))
    other = lead(s[::2])
    assert other is not first and len(other.s) == len(s[::2])
    np.testing.assert_array_equal(lead(s).p_IE, first.p_IE)
    copied = pickle.loads(cloudpickle.dumps(lead))  # as a forked child sends it back
    assert "_last" not in copied.__dict__
    np.testing.assert_array_equal(copied(s).R_IE, first.R_IE)


def _turned(X_PE: RigidTransform) -> RigidTransform:
    """X_PE turned 0.3 rad about P's z and shifted 5 cm: another placement of E on P."""
    return RigidTransform(RotationMatrix.MakeZRotation(0.3), [0.05, 0.0, 0.0]) @ X_PE
