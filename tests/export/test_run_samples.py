"""A flying seam's run as the writers take it: its samples (the UR move and FANUC
writers) each planned pose once, in time order, the leads included; its straight
approach and retract meeting the leads at any sample rate."""

import numpy as np
import pytest
from job.test_flying_entry import _planned

from offline_prog.export.job_program import JobProgramData
from offline_prog.export.points import PointRule
from offline_prog.export.record import program_record
from offline_prog.export.run_samples import run_samples

from conftest import CELLS, planned_text


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


@pytest.mark.slow  # plans a job of its own
def test_a_flying_seams_straight_moves_end_at_its_leads_at_any_sample_rate(flying, tmp_path):
    """The approach's straight move ends where the lead-in starts (on the seal demo the
    lead's lift takes the whole approach: it is the approach's start) and the retract's
    starts where the lead-out ends, at 2 samples per second (the job's rows then hold
    neither the leads' ends) as at the demo's rate: the same targets and lengths."""
    text = (CELLS / "seal_plate_kr16.yaml").read_text(encoding="utf-8")
    text = text.replace("  closed: true\n", "  closed: true\n  entry: flying\n")
    text = text.replace("  max_jerk:", "  sample_rate_hz: 2\n  max_jerk:", 1)
    _, slow_rate = planned_text(text, tmp_path)
    rule = PointRule("flange", "X_TP", 5e-5, 1e-3)
    runs = [program_record(d, rule).runs()[0] for d in (flying, slow_rate)]
    for run in runs:
        dense = run.process.data
        np.testing.assert_allclose(run.approach.X_PT, dense.X_PT[0], atol=1e-9)
    np.testing.assert_allclose(runs[1].approach.X_PT, runs[0].approach.X_PT, atol=1e-6)
    np.testing.assert_allclose(runs[1].retract.X_PT, runs[0].retract.X_PT, atol=1e-6)
    assert runs[1].retract.length_m == pytest.approx(runs[0].retract.length_m, abs=1e-6)
