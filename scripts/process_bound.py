"""The dispenser's jerk bound (issue 28's feedback into timing) on a bead cell: the job
planned with the bound and without it, the bead predicted by the model from each plan.

Run: ``python scripts/process_bound.py [CELL]`` (default: cells/seal_job_kr16.yaml with
a bead model, 12 mm² ± 5 %, 250 mm³/s per unit, lag 0.08 s, written to a temporary
folder with the flow keys the bead sets removed).

Prints per seam: the path jerk cap, the worst relative bead error where the tool runs
at least half the seam's speed (off the ramps from rest, where no jerk holds a bead),
and the share of the seam's length within the tolerance, with and without the bound;
then the cycle times of both plans and report.json's ``quality.timing_bound`` figures.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import tempfile
from pathlib import Path

import numpy as np

from offline_prog.plan import StageTimer, plan_loaded_job
from offline_prog.process.registry import process_model
from offline_prog.results.timing_bound import timing_bound_report
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import load_inputs

REPO = Path(__file__).resolve().parents[1]
BEAD = (
    "process:\n  model: bead\n  bead: {area_mm2: 12.0, tolerance_pct: 5, "
    "flow_mm3_s_per_unit: 250.0, lag_s: 0.08}\n"
)
CRUISE_SHARE = 0.5


def demo_cell(folder: Path) -> Path:
    """The sealing job with BEAD (replacing a model it may have), its flow output
    reduced to its number and limits (the bead sets the rest)."""
    text = (REPO / "cells" / "seal_job_kr16.yaml").read_text()
    text = re.sub(r"(?ms)^process:.*?(?=^\S|\Z)", "", text)
    flow = "    flow: {analog_output: 1, min: 0.0, max: 10.0}"
    text = re.sub(r"(?m)^    flow: \{.*\}$", flow, text)
    cell = folder / "seal_job_kr16_bead.yaml"
    cell.write_text(text + BEAD)
    return cell


def bead_figures(job) -> dict[str, tuple[float, float]]:
    """Per seam: (worst |A/A* − 1| where v ≥ CRUISE_SHARE · the seam's speed, share of
    the process length within the tolerance), from the model, the plan's speed and its
    flow output column."""
    model = process_model(job.cell.process)
    samples = job.samples
    error = np.abs(model.predict(samples.t, job.tcp_speed, job.io.analog) / model.area_m2 - 1)
    out = {}
    for option in job.chosen:
        g = next(g for g in samples.segments if g.kind == "process" and g.seam == option.name)
        rows = slice(g.start, g.stop)
        v, e = job.tcp_speed[rows], error[rows]
        length = v * np.gradient(samples.t[rows])
        within = np.nan_to_num(e, nan=np.inf) <= model.tolerance
        worst = float(e[v >= CRUISE_SHARE * option.plan.process_speed.v_m_s].max())
        out[option.name] = (worst, float(length[within].sum() / length.sum()))
    return out


def main(cell: Path) -> None:
    inputs = load_inputs(cell, ROBOTS_DIR)
    jobs = {
        bound: plan_loaded_job(
            dataclasses.replace(inputs, process_bound=bound),
            StageTimer(lambda stage: None),
            clearance_profile=False,
        )
        for bound in (True, False)
    }
    figures = {bound: bead_figures(job) for bound, job in jobs.items()}
    print(f"{cell.name}: worst bead error where v >= {CRUISE_SHARE:g} x the seam's speed")
    print("seam         jerk cap   worst with  worst without  within with  within without")
    for option in jobs[True].chosen:
        name, caps = option.name, option.plan.joints.process_caps
        (w, s), (w0, s0) = figures[True][name], figures[False][name]
        print(
            f"{name:12s} {caps.j_max:6.3f} m/s³ {100 * w:8.2f} % {100 * w0:10.2f} %"
            f" {100 * s:10.1f} % {100 * s0:11.1f} %"
        )
    cycle, cycle0 = (float(jobs[b].samples.t[-1]) for b in (True, False))
    print(f"cycle time: {cycle:.3f} s with the bound, {cycle0:.3f} s without (planned twice)")
    report = timing_bound_report(jobs[True])
    print(
        f"report.json quality.timing_bound: cycle_time_s {report['cycle_time_s']:.3f}, "
        f"cycle_time_without_bound_s {report['cycle_time_without_bound_s']:.3f}, "
        f"difference_s {report['difference_s']:.3f}"
    )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "cell", nargs="?", type=Path, help="a job cell with a bead model (default: the demo)"
    )
    cell = parser.parse_args().cell
    if cell is not None:
        main(cell)
    else:
        with tempfile.TemporaryDirectory() as folder:
            main(demo_cell(Path(folder)))
