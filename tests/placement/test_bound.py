"""The screen's cycle-time bound (``placement.bound``) is a lower bound on the planned
cycle also where the seam flies and its approach and retract run faster than the seam
(``motion.approach_speed``): seeded candidates of the weld torch's placement demo, each
also planned in full."""

import math

import pytest

from offline_prog.config.cell import load_cell
from offline_prog.placement.context import context
from offline_prog.placement.evaluate import evaluate
from offline_prog.placement.payload import cell_payload
from offline_prog.placement.screen import screen
from offline_prog.placement.space import check_place

from conftest import CELLS

WELD = CELLS / "placement" / "weld_torch_irb2400.yaml"


def _fast_approach_weld(tmp_path):
    """The weld torch's demo with its approach and retract at 50 mm/s (the seam: 8)."""
    text = WELD.read_text(encoding="utf-8").replace("../data/", f"{CELLS}/data/")
    text = text.replace("  max_jerk: 5.0\n", "  max_jerk: 5.0\n  approach_speed: 0.05\n", 1)
    file = tmp_path / "weld_fast_approach.yaml"
    file.write_text(text, encoding="utf-8")
    return file


@pytest.mark.slow
def test_no_plan_beats_the_bound_where_the_approach_runs_faster(rng, tmp_path):
    """(~30 s: two candidates planned in full.) Counted at the seam's 8 mm/s, the 50 mm
    approach and retract put the bound at 56.3 s over a 47.5 s plan."""
    file = _fast_approach_weld(tmp_path)
    cell = load_cell(file)
    _, space = check_place(file, cell)
    ctx = context(cell_payload(file, cell))
    planned_any = False
    for x in rng.uniform(0.0, 1.0, size=(3, space.dimensions)):
        candidate = space.candidate(x, 0)
        screened, planned = screen(ctx, candidate), evaluate(ctx, candidate)
        if planned.feasible:
            planned_any = True
            assert math.isfinite(screened.bound_s)
            assert screened.bound_s <= planned.cycle_time_s, (candidate, screened.bound_s)
    assert planned_any
