"""The screen is sound: what it rules out no plan makes feasible, and no plan is
faster than its lower bound (seeded candidates, each also planned in full); the
planner's first tool turn is the one the screen predicts; the cheaper law ranks."""

import math

import numpy as np
import pytest

from offline_prog.config.cell import load_cell
from offline_prog.job.seams import job_seams
from offline_prog.placement.context import context, rigid
from offline_prog.placement.evaluate import evaluate
from offline_prog.placement.payload import cell_payload
from offline_prog.placement.screen import rank, screen
from offline_prog.placement.space import check_place
from offline_prog.placement.variants import seam_variants

from conftest import CELLS

DEMO = CELLS / "placement" / "seal_out_of_reach_kr16.yaml"
JOB = CELLS / "placement" / "seal_job_far_kr16.yaml"


def _space(file):
    cell = load_cell(file)
    _, space = check_place(file, cell)
    return space, context(cell_payload(file, cell))


def _judge_against_plans(file, xs, grasps):
    space, ctx = _space(file)
    judged = []
    for x, grasp in zip(xs, grasps, strict=True):
        candidate = space.candidate(x, grasp)
        screened, planned = screen(ctx, candidate), evaluate(ctx, candidate)
        if screened.screened_out:  # sound: no plan follows what the screen rules out
            assert not planned.feasible, (candidate, screened.reason)
            assert planned.failure in ("out_of_reach", "joint_limit", "stand")
        if planned.feasible:  # sound: no plan beats the bound
            assert screened.bound_s <= planned.cycle_time_s, (candidate, screened.bound_s)
            assert math.isfinite(screened.bound_s)
        judged.append((screened, planned))
    return judged


def test_what_the_screen_rules_out_no_plan_follows_and_no_plan_beats_its_bound():
    judged = _judge_against_plans(DEMO, [[0.3, 0.5, 0.6, 0.5], [0.97, 0.9, 0.2, 0.5]], [0, 1])
    assert [s.screened_out for s, _ in judged] == ["", "reach"]
    assert judged[0][1].feasible


@pytest.mark.slow  # ~60 s: 16 one-seam and 4 job candidates planned in full
def test_the_screen_is_sound_on_seeded_candidates(rng):
    for file, n in ((DEMO, 16), (JOB, 4)):
        space, _ = _space(file)
        xs = rng.uniform(0.0, 1.0, size=(n, space.dimensions))
        grasps = rng.integers(0, len(space.grasps), size=n)
        judged = _judge_against_plans(file, xs, grasps)
        assert any(p.feasible for _, p in judged)


def test_the_screen_predicts_the_planners_tool_turn():
    """The tool turn φ₀ the screen's variants rank first is the one the plan takes."""
    space, ctx = _space(DEMO)
    seam = job_seams(ctx.inputs.cell)[0]
    for x in ([0.3, 0.5, 0.6, 0.5], [0.5, 0.2, 0.9, 0.1]):
        candidate = space.candidate(x, 0)
        variants = seam_variants(ctx.seams[0], seam, rigid(candidate.X_IT), rigid(candidate.X_PE))
        a, _ = variants.planner_choice()
        planned = evaluate(ctx, candidate)
        assert planned.feasible
        assert np.rad2deg(variants.angles[a]) == pytest.approx(planned.tool_rotation_deg)


def test_rank_gives_the_cheaper_law_and_keeps_the_bound():
    space, ctx = _space(DEMO)
    candidate = space.candidate([0.3, 0.5, 0.6, 0.5], 0)
    screened, ranked = screen(ctx, candidate), rank(ctx, candidate)
    assert ranked.stage == "rank" and ranked.feasible and not ranked.collides
    assert ranked.bound_s == screened.bound_s
    # TOPP-RA on the planner's variant: above the bound, below the plan's jerk-limited law.
    assert screened.bound_s < ranked.cycle_time_s < evaluate(ctx, candidate).cycle_time_s
