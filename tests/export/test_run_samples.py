"""A seam run's samples as the UR move and FANUC writers take them: on a flying seam
each planned pose once, in time order, the leads included."""

import numpy as np
import pytest
from job.test_flying_entry import _planned

from offline_prog.export.job_program import JobProgramData
from offline_prog.export.points import PointRule
from offline_prog.export.record import program_record
from offline_prog.export.run_samples import run_samples


@pytest.fixture(scope="module")
def flying(tmp_path_factory):
    """The sealing demo's seam run flying, planned: its JobProgramData."""
    job, folder = _planned(tmp_path_factory.mktemp("flying"), "flying")
    assert job.chosen[0].plan.entry["entry"] == "flying"
    return JobProgramData.load(folder)


@pytest.mark.slow  # plans a job of its own
def test_a_flying_seams_samples_run_once_in_time_order_through_its_leads(flying):
    record = program_record(flying, PointRule("flange", "X_TP", 5e-5, 1e-3))
    (run,) = record.runs()
    samples = run_samples(flying.job, run)
    assert np.all(np.diff(samples.t) > 0)  # no pose twice (the leads' job rows left out)
    assert np.all(np.diff(samples.path_m) >= 0)
    process = next(g for g in run.segments if g.kind == "process")
    length = flying.job.path_m[process.stop - 1]
    # The seam's start σ = 0 at its process segment's first row's time, and its end.
    at_start = int(np.argmin(np.abs(samples.t - flying.job.t[process.start])))
    assert samples.path_m[at_start] == pytest.approx(0.0, abs=1e-9)
    assert np.abs(samples.path_m - length).min() < 1e-9
    # The leads: on the run's samples before σ = 0 and past L, the job's row times.
    lead_in = (samples.path_m < 0) & (samples.path_m > samples.path_m[0])
    assert lead_in.sum() > 2 and (samples.path_m > length).sum() > 2
    assert samples.t[0] == pytest.approx(flying.job.t[run.rows.start], abs=1e-9)
    assert samples.t[-1] == pytest.approx(flying.job.t[run.rows.stop - 1], abs=1e-9)
