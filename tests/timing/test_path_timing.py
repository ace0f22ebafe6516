"""The timing façade: one entry point, one record whatever the law (issue 24). An
unknown law or intent is refused at the cell in one line: tests/config/test_cell_errors.py."""

import dataclasses

import numpy as np
import pytest

from offline_prog.constants import PROCESS_INTENTS, TIME_LAWS, ProcessIntent, TimeLaw
from offline_prog.robot.model import load_robot
from offline_prog.timing.joint_timing import JointRates
from offline_prog.timing.path_timing import PathLimits, PathTiming, time_path
from offline_prog.timing.time_law import sin2_time_law

LENGTH_M = 0.2
SPEED = 0.1  # m/s: the joints below allow it on the whole path


def slow_rates() -> JointRates:
    """A 200 mm path on which every joint moves 0.2 rad per metre."""
    sigma = np.linspace(0.0, LENGTH_M, 2001)
    dq = np.full((len(sigma), 6), 0.2)
    return JointRates(sigma, sigma[:, None] * dq[0], dq, np.zeros_like(dq))


@pytest.mark.parametrize("intent", list(ProcessIntent))
def test_both_laws_return_one_record_with_the_documented_fields(intent):
    robot = load_robot("kuka_kr16_2")
    nominal = sin2_time_law(LENGTH_M, v_max=SPEED, a_max=1.0, j_max=10.0)
    limits = PathLimits.of(robot, LENGTH_M, v_process=SPEED, a_max=1.0, j_max=10.0)
    assert limits.nominal.duration == nominal.duration  # the same law, built once:
    assert limits.nominal is limits.nominal
    sin2 = time_path(slow_rates(), limits, TimeLaw.SIN2, intent)
    optimal = time_path(slow_rates(), limits, TimeLaw.TIME_OPTIMAL, intent)
    assert type(sin2) is type(optimal) is PathTiming
    for timing in (sin2, optimal):
        assert timing.feasible and timing.law.duration > LENGTH_M / SPEED
        sigma = timing.law(np.array([0.0, timing.law.duration]))[0]
        assert sigma == pytest.approx([0.0, LENGTH_M], abs=1e-9)
    # The sin² law is the nominal one here (no joint limit binds) and has no TOPP-RA.
    assert sin2.law.duration == pytest.approx(nominal.duration)
    assert (sin2.law_kind, sin2.intent, sin2.slowdowns, sin2.topp) == (TimeLaw.SIN2, None, (), None)
    assert sin2.topp_plain_s is sin2.speed_held is sin2.solve_s is None
    assert (optimal.law_kind, optimal.intent) == (TimeLaw.TIME_OPTIMAL, intent)
    assert optimal.topp is not None and optimal.topp_plain_s <= optimal.law.duration
    assert optimal.solve_s > 0.0 and len(optimal.speed_held) == 2
    assert {f.name for f in dataclasses.fields(PathTiming)} >= {
        "law",
        "reductions",
        "feasible",
        "worst",
        "topp",
        "speed_held",
    }


def test_the_enums_carry_the_cell_files_strings():
    assert TIME_LAWS == ("time_optimal", "sin2")
    assert PROCESS_INTENTS == ("constant_speed", "cycle_time")
    assert f"{TimeLaw.SIN2}" == "sin2" and str(ProcessIntent.CYCLE_TIME) == "cycle_time"
