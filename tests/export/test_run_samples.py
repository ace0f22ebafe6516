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
def test_a_flying_seams_leads_take_its_straight_moves_over_at_any_sample_rate(flying, tmp_path):
    """On the seal demo the leads' lift takes the whole approach and retract (normal
    moves at the process speed): the program record holds no straight approach or
    retract (no 0 mm LIN), and the link before the seam ends where the lead-in starts,
    the one after it starts where the lead-out ends, at 2 samples per second (the job's
    rows then hold neither of the leads' ends) as at the demo's rate."""
    text = (CELLS / "seal_plate_kr16.yaml").read_text(encoding="utf-8")
    text = text.replace("  closed: true\n", "  closed: true\n  entry: flying\n")
    text = text.replace("  max_jerk:", "  sample_rate_hz: 2\n  max_jerk:", 1)
    _, slow_rate = planned_text(text, tmp_path)
    rule = PointRule("flange", "X_TP", 5e-5, 1e-3)
    ends = []
    for data in (flying, slow_rate):
        (run,) = program_record(data, rule).runs()
        assert run.approach is None and run.retract is None
        dense, rows = run.process.data, data.job
        kinds = {s.kind: s for s in run.segments}
        link_end = rows.X_PT[kinds["approach"].start]
        next_link = rows.X_PT[min(kinds["retract"].stop, len(rows.t) - 1)]
        np.testing.assert_allclose(link_end, dense.X_PT[0], atol=1e-9)
        np.testing.assert_allclose(next_link, dense.X_PT[-1], atol=1e-9)
        assert dense.path_m[0] < 0.0 < data.seam_lengths_m[0] < dense.path_m[-1]
        ends.append((dense.X_PT[0], dense.X_PT[-1]))
    np.testing.assert_allclose(ends[1], ends[0], atol=1e-6)
