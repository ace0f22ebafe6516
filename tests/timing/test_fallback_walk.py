"""The walk over a flying seam's leads and their fallbacks (``timing.fallback_walk``):
leads with their own lift, then rest, each tried only where the one before missed,
rest named with the first miss's reason, and a path at rest failing as the seam."""

import dataclasses

import pytest

from offline_prog.errors import Failure, PlanFailedError, PlanFailure
from offline_prog.path.lead import LeadPath
from offline_prog.timing.fallback_walk import walk_fallbacks

from conftest import random_flange_path


@dataclasses.dataclass(frozen=True)
class Run:
    flange: LeadPath


def _failed(reason: str) -> PlanFailedError:
    return PlanFailedError(PlanFailure(Failure.JOINT_LIMIT, 0.01, 0.1, reason))


def _walk(first: LeadPath, verdicts: dict[str, str | PlanFailedError]):
    """The walk from ``first`` where a run's check gives ``verdicts`` by the run's kind
    (asked, own lift, rest); the kinds in the order they were checked."""
    checked = []

    def check(run: Run):
        kind = "rest" if not run.flange.flying else ("own" if checked else "asked")
        checked.append(kind)
        if isinstance(verdicts[kind], PlanFailedError):
            raise verdicts[kind]
        return kind, verdicts[kind]

    return walk_fallbacks(Run(first), check, setup=Run), checked


@pytest.fixture
def taken_over(rng) -> LeadPath:
    """Leads that took a 30 mm normal move over (they have an own-lift fallback)."""
    flange = random_flange_path(rng, closed=False)
    return LeadPath(flange, lead_in_m=0.03, lead_out_m=0.03, lifts_m=(0.03, 0.0))


def test_leads_that_serve_are_the_only_run_checked(taken_over):
    walk, checked = _walk(taken_over, {"asked": ""})
    assert checked == ["asked"]
    assert walk.served and walk.last[1] == "asked"


def test_missed_leads_try_their_own_lift_then_rest_named_by_the_first_miss(taken_over):
    walk, checked = _walk(taken_over, {"asked": "slowed", "own": "slowed too", "rest": ""})
    assert checked == ["asked", "own", "rest"]
    run, outcome = walk.last
    assert walk.served and outcome == "rest"
    assert run.flange.reason == "slowed" and run.flange.lifts_m == (0.0, 0.0)
    own = walk.tried[1][0].flange
    assert own.flying and own.asked["lifts_m"] == (0.0, 0.0)


def test_a_flying_path_that_fails_is_a_miss_a_path_at_rest_the_seams_failure(taken_over):
    walk, checked = _walk(
        taken_over, {"asked": _failed("wrist"), "own": "", "rest": _failed("elbow")}
    )
    assert checked == ["asked", "own"]
    assert walk.tried[0][1] is None and "the lead-in or lead-out: wrist" in walk.tried[0][2]
    with pytest.raises(PlanFailedError, match="elbow"):
        _walk(
            taken_over,
            {"asked": _failed("wrist"), "own": _failed("wrist"), "rest": _failed("elbow")},
        )


def test_leads_without_a_lift_fall_to_rest_and_a_path_at_rest_has_no_fallback(rng):
    flange = random_flange_path(rng, closed=False)
    walk, checked = _walk(
        LeadPath(flange, lead_in_m=0.03, lead_out_m=0.0), {"asked": "x", "rest": "y"}
    )
    assert checked == ["asked", "rest"] and not walk.served
    at_rest = LeadPath(flange, lead_in_m=0.0, lead_out_m=0.0, reason="entry: rest")
    walk, checked = _walk(at_rest, {"rest": "missed"})
    assert checked == ["rest"] and not walk.served
