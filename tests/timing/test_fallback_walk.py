"""The walk over a flying seam's leads and their fallbacks (``timing.fallback_walk``):
leads with their own lift, then rest, each tried only where the one before missed,
rest named with the first miss's reason, and a path at rest failing as the seam."""

import dataclasses
import re

import pytest
from job.bead_job import bead_job
from job.test_flying_entry import _gun_on_figures

from offline_prog.errors import Failure, PlanFailedError, PlanFailure
from offline_prog.path.lead import LeadPath
from offline_prog.plan import StageTimer, plan_loaded_job
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import load_inputs
from offline_prog.timing.fallback_walk import walk_fallbacks

from conftest import random_flange_path


@dataclasses.dataclass(frozen=True)
class Run:
    flange: LeadPath


def _failed(reason: str) -> PlanFailedError:
    return PlanFailedError(PlanFailure(Failure.JOINT_LIMIT, 0.01, 0.1, reason))


def _walk(first: LeadPath, verdicts: dict[str, str | PlanFailedError], rank=None):
    """The walk from ``first`` where a run's check gives ``verdicts`` by the run's kind
    (asked, own lift, rest); the kinds in the order they were checked."""
    checked = []

    def check(run: Run):
        kind = "rest" if not run.flange.flying else ("own" if checked else "asked")
        checked.append(kind)
        if isinstance(verdicts[kind], PlanFailedError):
            raise verdicts[kind]
        return kind, verdicts[kind]

    return walk_fallbacks(Run(first), check, setup=Run, rank=rank), checked


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


def test_a_ranked_walk_keeps_the_best_flying_run_that_ran_rather_than_rest(taken_over):
    """With ``rank`` (a bead: the slowest led end's speed), slowed leads are kept: the
    better of the asked and own-lift runs, rest never checked; one that failed is not
    ranked, and where none ran the walk still ends at rest."""
    speeds = {"asked": 0.01, "own": 0.03}
    walk, checked = _walk(
        taken_over,
        {"asked": "slowed", "own": "slowed", "rest": ""},
        rank=lambda run, out: speeds[out],
    )
    assert checked == ["asked", "own"] and walk.last[1] == "own" and walk.missed == "slowed"
    walk, checked = _walk(
        taken_over,
        {"asked": "slowed", "own": _failed("wrist"), "rest": ""},
        rank=lambda run, out: speeds[out],
    )
    assert checked == ["asked", "own"] and walk.last[1] == "asked" and not walk.served
    walk, checked = _walk(
        taken_over,
        {"asked": _failed("wrist"), "own": _failed("wrist"), "rest": ""},
        rank=lambda run, out: speeds[out],
    )
    assert checked == ["asked", "own", "rest"] and walk.served


def test_leads_without_a_lift_fall_to_rest_and_a_path_at_rest_has_no_fallback(rng):
    flange = random_flange_path(rng, closed=False)
    walk, checked = _walk(
        LeadPath(flange, lead_in_m=0.03, lead_out_m=0.0), {"asked": "x", "rest": "y"}
    )
    assert checked == ["asked", "rest"] and not walk.served
    at_rest = LeadPath(flange, lead_in_m=0.0, lead_out_m=0.0, reason="entry: rest")
    walk, checked = _walk(at_rest, {"rest": "missed"})
    assert checked == ["rest"] and not walk.served


def _bead_circle(tmp_path, entry: str):
    """A 20 mm circle on the sealing job's plate with a bead model (12 mm², lag 0.08 s),
    planned with ``entry``: flying, its takeover leads turn the wrist so fast that the
    joints hold the seam's start at 10 % of the process speed."""
    text = bead_job()
    head, tail = text[: text.index("\nseams:") + 1], text[text.index("\njob:") + 1 :]
    circle = "{kind: arc, center: [104.6, -12.5, 0], radius: 20, start_deg: 0, end_deg: 360}"
    seam = f"{{name: dot, analytic: {circle}, closed: true, units: mm, normal: [0, 0, 1]"
    cell = tmp_path / f"{entry}.yaml"
    cell.write_text(f"{head}seams:\n  - {seam}, entry: {entry}}}\n{tail}", encoding="utf-8")
    inputs = load_inputs(cell, ROBOTS_DIR)
    job = plan_loaded_job(inputs, StageTimer(lambda stage: None), clearance_profile=False)
    assert job.feasible, job.failure
    return job


@pytest.mark.slow
def test_a_bead_seam_whose_start_the_joints_slow_keeps_flying(tmp_path):
    """Where the process model judges a bead, a seam end the joint limits slow keeps its
    leads, run slowed, rather than rest: no gun-on standstill and no blob at the ends
    (at rest the first rows are thousands of percent over), and report.json names the
    end and the share of the process speed."""
    flying = _bead_circle(tmp_path, "flying")
    entry = flying.chosen[0].plan.entry
    assert entry["entry"] == "flying", entry
    assert re.search(r"hold the seam's (start|end) at \d+ % of the process speed", entry["reason"])
    assert "kept flying" in entry["reason"]
    share, worst, standstill = _gun_on_figures(flying)
    rest = _bead_circle(tmp_path, "rest")
    rest_share, rest_worst, rest_standstill = _gun_on_figures(rest)
    assert standstill == 0 and rest_standstill > 0
    assert worst <= 0.25 and rest_worst > 10.0
    assert share >= rest_share
