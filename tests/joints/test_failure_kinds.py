"""Failure kinds are set where a failure is found, never read back from its words.

Reproduction (issue 24): a failed TOPP-RA solve ended with exit 3 (an internal error),
because the kind was looked up from the first words of the reason and "TOPP-RA found
no parameterization" matched none. Now it is a plan failure (exit 1) saying where
(σ, t) and why.
"""

import argparse
import dataclasses

import numpy as np
import pytest

from offline_prog.cli import exit_code
from offline_prog.constants import ProcessIntent, TimeLaw
from offline_prog.errors import Failure, PlanFailedError
from offline_prog.joints.path_ik import branch_results
from offline_prog.robot.model import load_robot
from offline_prog.timing.joint_timing import JointRates
from offline_prog.timing.path_timing import PathLimits, time_path
from offline_prog.timing.time_law import sin2_time_law
from offline_prog.timing.time_optimal import topp_profile

LENGTH_M = 0.2


def straight_rates() -> JointRates:
    """A 200 mm path on which every joint moves at a constant rate per metre."""
    sigma = np.linspace(0.0, LENGTH_M, 2001)
    dq = np.tile([1.0, 0.5, 0.2, 0.1, 0.1, 0.1], (len(sigma), 1))
    return JointRates(sigma, sigma[:, None] * dq[0], dq, np.zeros_like(dq))


def test_a_failed_topp_ra_solve_is_a_plan_failure_with_where_and_why():
    """TOPP-RA always finds the rest-to-rest profile under real limits (standing still
    is feasible everywhere); acceleration limits no robot has make it fail for real."""
    robot = load_robot("kuka_kr16_2")
    impossible = dataclasses.replace(robot, qdd_max=-robot.qdd_max)
    limits = PathLimits.of(impossible, LENGTH_M, v_process=0.1, a_max=1.0, j_max=10.0)
    nominal = sin2_time_law(LENGTH_M, v_max=0.1, a_max=1.0, j_max=10.0)
    with pytest.raises(PlanFailedError) as raised:
        time_path(
            straight_rates(),
            limits,
            TimeLaw.TIME_OPTIMAL,
            ProcessIntent.CONSTANT_SPEED,
        )
    failure = raised.value.failure
    assert failure.kind is Failure.JOINT_RATE_LIMIT
    assert 0.0 <= failure.sigma_m <= LENGTH_M and 0.0 < failure.t_s <= nominal.duration
    assert "TOPP-RA found no parameterization" in failure.reason
    args = argparse.Namespace(command="plan", cell="cell.yaml")
    code, line = exit_code(raised.value, args)
    assert code == 1 and line.count("\n") == 0 and f"σ = {failure.sigma_m:.4f} m" in line


def test_topp_profile_says_where_it_failed():
    """Starting at 1 m/s where the process cap is 0.1 m/s: not controllable at σ = 0."""
    limits = dict(qd_max=np.full(6, 2.0), qdd_max=np.full(6, 5.0), v_cap=0.1, a_path=1.0)
    profile = topp_profile(straight_rates(), **limits, ends=(1.0, 0.0))
    assert not profile.ok and profile.failed_at_m == 0.0 and "not controllable" in profile.reason
    assert np.isnan(topp_profile(straight_rates(), **limits).failed_at_m)


def test_branch_failures_carry_their_kind():
    """Every infeasible branch says its kind itself (out of reach far away)."""
    robot = load_robot("kuka_kr16_2")
    X_BE = np.tile(np.eye(4), (5, 1, 1))
    X_BE[:, :3, 3] = [5.0, 0.0, 1.0]  # 5 m away: beyond the KR 16's reach
    results = branch_results(robot, X_BE)
    assert {r.kind for r in results} == {Failure.OUT_OF_REACH}
    assert not hasattr(Failure, "of")  # no lookup of a kind from a message's words
