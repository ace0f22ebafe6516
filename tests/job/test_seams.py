"""A ``path:`` cell's seam (``job.seams``): planned alone (``plan.plan_cell``'s inputs,
``stages.load_inputs``) and as a job's one shorthand seam (``seam_inputs``), its leads
may take over the same approach and retract moves."""

import pytest

from offline_prog.job.seams import job_seams, seam_inputs
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import load_inputs

from conftest import CELLS


@pytest.mark.parametrize("name", ["seal_plate_kr16", "weld_seam_irb2400"])
def test_a_path_cells_seam_moves_alone_as_in_its_job(name):
    alone = load_inputs(CELLS / f"{name}.yaml", ROBOTS_DIR)
    seam = job_seams(alone.cell)[0]
    in_job = seam_inputs(alone, 0)
    for inputs in (alone, in_job):
        assert inputs.normal_moves_m == (seam.approach.normal_m, seam.retract.normal_m)
        assert inputs.tangent_moves_m == (seam.approach.tangent_m, seam.retract.tangent_m)
    assert alone.normal_moves_m == (0.05, 0.05)  # the default: 50 mm off the surface
