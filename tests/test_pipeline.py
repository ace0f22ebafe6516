"""The stages are declared once, as data, and every caller runs that declaration: each
stage reads only what exists when it runs, plan's stage timings are the declared names
in order, and a path: cell's process I/O is planned and written (it is a one-seam job)."""

import json
import subprocess
import sys

import numpy as np

from offline_prog.pipeline import JOB_CLEARANCE, JOB_STAGES, SEAM_STAGES

from conftest import CELLS, REPO

CALLER_GIVES = {"inputs", "progress", "seam_planner"}


def test_each_stage_reads_only_what_is_there_when_it_runs():
    for stages in (SEAM_STAGES, (*JOB_STAGES, JOB_CLEARANCE)):
        there = set(CALLER_GIVES)
        for stage in stages:
            assert set(stage.reads) <= there, f"{stage.name} reads {set(stage.reads) - there}"
            assert stage.name not in there, f"{stage.name} declared twice"
            there.add(stage.name)


def test_plan_times_the_declared_stages_in_order(planned_job):
    job, _ = planned_job("seal_plate_kr16")
    declared = ["load", *(s.name for s in (*JOB_STAGES, JOB_CLEARANCE))]
    assert list(job.timings_s) == declared
    seam = job.seams[0]  # its scene is the job's (given, not built again)
    assert list(seam.timings_s) == [s.name for s in SEAM_STAGES if s.name != "scene"]


def test_process_io_of_a_path_cell_is_planned_and_written(tmp_path):
    """tool.process_io on a path: cell was ignored without a word (issue 24): as a
    one-seam job it switches on the path, in trajectory.csv, report.json and the KRL."""
    text = (CELLS / "seal_plate_kr16.yaml").read_text()
    valve = "    on:  {digital_output: 1}\n    off: {digital_output: 1}\n"
    io = "    on:  {digital_output: 3, lead_mm: 5}\n    off: {digital_output: 3, lead_mm: 2}\n"
    cell = tmp_path / "seal_io.yaml"
    assert valve in text  # the demo's gun valve (its flow output: its bead model's)
    cell.write_text(text.replace(valve, io, 1))
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "offline_prog", "plan", str(cell), "--out", str(out)],
        capture_output=True,
        text=True,
        cwd=REPO,
    )
    assert done.returncode == 0, done.stderr
    header = (out / "trajectory.csv").read_text().splitlines()[0].split(",")
    do = np.loadtxt(out / "trajectory.csv", delimiter=",", skiprows=1, usecols=header.index("do3"))
    assert do.max() == 1 and do[0] == do[-1] == 0
    events = json.loads((out / "report.json").read_text())["process_io"]
    assert [(e["state"], e["digital_output"]) for e in events] == [("on", 3), ("off", 3)]
    length = json.loads((out / "report.json").read_text())["path"]["length_m"]
    assert events[0]["path_m"] == -0.005 and abs(events[1]["path_m"] - (length - 0.002)) < 1e-9
    krl = "".join(p.read_text() for p in sorted((out / "programs").glob("*.src")))
    assert "$OUT[3]=TRUE" in krl.replace(" ", "") and "$OUT[3]=FALSE" in krl.replace(" ", "")
