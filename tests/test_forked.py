"""The map on this process and a forked child (offline_prog.forked): the outcomes of a
serial loop, the objects both hold coming back as themselves, and a job planned on two
processes equal to the job planned on one."""

import dataclasses
import os
import pickle
import threading
import time

import numpy as np
import pytest

import offline_prog.forked as forked
from offline_prog.errors import Failure, InputError, PlanFailure
from offline_prog.forked import forked_map, reachable
from offline_prog.joints.joint_plan import JointPlanError
from offline_prog.plan import StageTimer, plan_loaded_job
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import load_inputs

from conftest import CELLS

TWO = forked._workers() == 2
needs_two = pytest.mark.skipif(not TWO, reason="one core or no fork: the items run here")


class Shared:
    def __init__(self):
        self.table = np.arange(10.0)
        self.lock = threading.Lock()  # cannot be pickled: it must travel as a reference


def _item(shared: Shared, i: int):
    time.sleep(0.02)  # both processes take items
    if i % 4 == 3:
        raise ValueError(f"item {i} refused")
    return {"i": i, "square": shared.table[i] ** 2, "shared": shared, "pid": os.getpid()}


def test_outcomes_are_the_serial_loops_with_the_shared_objects_as_themselves():
    shared = Shared()
    outcomes = forked_map(lambda i: _item(shared, i), list(range(10)), shared=[shared])
    for i, outcome in enumerate(outcomes):
        if i % 4 == 3:
            with pytest.raises(ValueError, match=f"item {i} refused"):
                outcome.result()
            continue
        value = outcome.result()
        assert value["i"] == i and value["square"] == float(i) ** 2
        assert value["shared"] is shared  # a reference, not a copy
    if TWO:
        pids = {o.value["pid"] for o in outcomes if o.error is None}
        assert len(pids) == 2 and os.getpid() in pids  # the child computed some
        assert outcomes[0].value["pid"] == os.getpid()  # the first item: the progress's


@needs_two
def test_an_outcome_that_cannot_travel_is_computed_here():
    def item(i: int):
        return threading.Lock(), os.getpid()  # a new lock: not picklable, not shared

    outcomes = forked_map(item, list(range(6)), shared=[])
    assert {o.result()[1] for o in outcomes} == {os.getpid()}


@needs_two
def test_the_packages_errors_come_back_from_the_child_intact():
    """An InputError or a PlanFailedError raised in the child is the parent's: class,
    file, key, reason, failure record (it was exit 3 on two cores, exit 2 on one)."""
    failure = PlanFailure(Failure.COLLISION, 0.25, 2.0, "tool_body hits the floor")

    def item(i: int):
        time.sleep(0.02)  # both processes take items
        if i % 2:
            raise InputError(f"cell{i}.yaml", f"seams[{i}].cad", "two edges")
        raise JointPlanError(0.25, 2.0, "tool_body hits the floor", Failure.COLLISION)

    outcomes = forked_map(item, list(range(8)), shared=[])
    for i, outcome in enumerate(outcomes):
        if i % 2:
            assert type(outcome.error) is InputError
            assert (outcome.error.file, outcome.error.key, outcome.error.reason) == (
                f"cell{i}.yaml",
                f"seams[{i}].cad",
                "two edges",
            )
        else:
            assert type(outcome.error) is JointPlanError and outcome.error.failure == failure


@needs_two
def test_an_outcome_this_process_cannot_read_back_is_computed_here():
    def item(i: int):
        time.sleep(0.02)  # both processes take items
        return Unreadable(os.getpid())

    outcomes = forked_map(item, list(range(6)), shared=[])
    assert {o.result().pid for o in outcomes} == {os.getpid()}


class Unreadable:
    """Pickles, but its ``__init__`` needs what the pickle does not give back."""

    def __init__(self, pid: int):
        self.pid = pid

    def __reduce__(self):
        return Unreadable, ()


def test_reachable_enters_containers_and_objects_not_arrays():
    shared = Shared()
    found = reachable([{"a": [shared, (shared.table,)]}])
    assert any(o is shared for o in found) and any(o is shared.table for o in found)
    assert any(o is shared.lock for o in found)
    assert not any(isinstance(o, np.float64) for o in found)  # arrays are not entered


@needs_two
def test_a_job_planned_on_two_processes_is_the_job_planned_on_one():
    def job(parallel: bool):
        inputs = load_inputs(CELLS / "seal_job_kr16.yaml", ROBOTS_DIR)
        return plan_loaded_job(inputs, StageTimer(lambda s: None), parallel=parallel)

    one, two = job(False), job(True)
    assert [len(s) for s in two.options] == [len(s) for s in one.options]
    assert [o.label for o in two.chosen] == [o.label for o in one.chosen]
    assert two.order.sequence == one.order.sequence
    np.testing.assert_array_equal(two.samples.t, one.samples.t)
    np.testing.assert_array_equal(two.samples.q, one.samples.q)
    for mine, theirs in zip(two.chosen, one.chosen, strict=True):
        np.testing.assert_array_equal(mine.plan.joints.qd, theirs.plan.joints.qd)
        assert mine.plan.timings_s.keys() == theirs.plan.timings_s.keys()
    assert two.collisions.min_distance_m == one.collisions.min_distance_m
    # The check and the clearance profile ran side by side: the same results (bit for
    # bit: pickled alike) and stages.
    mine, theirs = (dataclasses.asdict(job.collisions) for job in (two, one))
    assert mine.pop("stats").keys() == theirs.pop("stats").keys()  # with run times
    assert pickle.dumps(mine) == pickle.dumps(theirs)
    assert pickle.dumps(two.clearance_profile) == pickle.dumps(one.clearance_profile)
    assert two.timings_s.keys() == one.timings_s.keys()
