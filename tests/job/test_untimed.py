"""Seam options decided before their time law (job.untimed): the job planned that way is
the job planned with every option timed, also where a chosen option fails its timing."""

import numpy as np
import pytest

import offline_prog.job.untimed as untimed
import offline_prog.stages as stages
from offline_prog.errors import Failure
from offline_prog.joints.joint_plan import JointPlanError
from offline_prog.plan import plan_job

from conftest import CELLS

JOB = CELLS / "seal_job_kr16.yaml"


def _every_option_timed(monkeypatch):
    """Plan every seam option in full (the job's seams stage before job.untimed)."""
    monkeypatch.setattr("offline_prog.job.stages.untimed_options", lambda *a, **k: None)


def _assert_same_job(job, reference):
    """The same seams run the same way: order, direction, branch, samples, checks."""
    assert [o.label for o in job.chosen] == [o.label for o in reference.chosen]
    np.testing.assert_array_equal(job.samples.t, reference.samples.t)
    np.testing.assert_array_equal(job.samples.q, reference.samples.q)
    for mine, theirs in zip(job.chosen, reference.chosen, strict=True):
        np.testing.assert_array_equal(mine.plan.joints.qd, theirs.plan.joints.qd)
        assert mine.plan.collisions.min_distance_m == theirs.plan.collisions.min_distance_m
    assert job.collisions.min_distance_m == reference.collisions.min_distance_m


def test_only_the_chosen_options_are_timed_and_the_job_is_the_fully_timed_one(
    planned_job, monkeypatch
):
    job, _ = planned_job("seal_job_kr16")
    flat = [option for seam in job.options for option in seam]
    assert all(option.plan is not None for option in job.chosen)
    assert sum(option.plan is None for option in flat) > 0  # never timed
    _every_option_timed(monkeypatch)
    reference = plan_job(JOB)
    # Where every option can be timed, the same options are offered, in the same order.
    assert [len(s) for s in job.options] == [len(s) for s in reference.options]
    assert job.order.sequence == reference.order.sequence
    _assert_same_job(job, reference)


def _failing_branch(monkeypatch, branch: int):
    """The time law fails on IK branch ``branch`` whenever it is asked for by number
    (the other branches a direction offers), as a joint-rate failure would."""
    original = stages.plan_motion

    def plan_motion(inputs, rotation, flange, asked=None, **known):  # known: run, branches
        if asked == branch:
            raise JointPlanError(0.0, 0.0, "injected: no time law", Failure.JOINT_RATE_LIMIT)
        return original(inputs, rotation, flange, asked, **known)

    monkeypatch.setattr(stages, "plan_motion", plan_motion)
    monkeypatch.setattr(untimed, "plan_motion", plan_motion)


@pytest.fixture(scope="module")
def rest_job(tmp_path_factory):
    """The demo job with every seam at rest (``entry: rest``): there it chooses another
    branch than its direction's first for a seam (flying, each direction's first)."""
    text = JOB.read_text(encoding="utf-8").replace(
        "    units: mm\n", "    units: mm\n    entry: rest\n"
    )
    assert text.count("entry: rest") == 4
    file = tmp_path_factory.mktemp("rest_job") / JOB.name
    file.write_text(text.replace(": data/", f": {CELLS}/data/"), encoding="utf-8")
    return file


@pytest.mark.slow
def test_a_chosen_branch_that_cannot_be_timed_is_dropped_and_the_order_searched_again(
    rest_job, monkeypatch
):
    job = plan_job(rest_job)
    # A chosen option that is another branch than its direction's first (timed with
    # its branch asked for by number).
    variants = [
        o
        for o in job.chosen
        if next(f for f in job.options[o.seam] if f.reverse == o.reverse) is not o
    ]
    assert variants, "the demo job chooses another branch for some seam"
    _failing_branch(monkeypatch, variants[0].branch)
    lazy = plan_job(rest_job)
    assert variants[0].label not in [o.label for o in lazy.chosen]
    _every_option_timed(monkeypatch)
    _assert_same_job(lazy, plan_job(rest_job))
