"""Jobs beyond the exact order's size, end to end through the command: a generated
job of 14 seams (tests/job/many_seams.py) plans with the budgeted order search, runs
every seam once, and says how the order was found (report.json, the summary)."""

import json
import subprocess
import sys

import pytest
from many_seams import REPO, many_seam_cell

from offline_prog.job.order import EXACT_MAX_SEAMS
from offline_prog.job.order_search import SEARCH_BUDGET


@pytest.mark.slow
def test_a_job_beyond_the_exact_size_plans_end_to_end(tmp_path):
    n = EXACT_MAX_SEAMS + 2
    cell, out = many_seam_cell(tmp_path, n), tmp_path / "out"
    command = [sys.executable, "-m", "offline_prog", "plan", str(cell), "--out", str(out)]
    done = subprocess.run(command, cwd=REPO, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    report = json.loads((out / "report.json").read_text())
    job, search = report["job"], report["job"]["order_search"]
    assert sorted(o["seam"] for o in job["order"]) == sorted(f"s{k}" for k in range(n))
    assert search["method"] == "heuristic" and search["budget_link_estimates"] == SEARCH_BUDGET
    assert 0 < search["used_link_estimates"] <= SEARCH_BUDGET
    assert search["lower_bound_s"] <= search["air_time_s"] <= search["start_air_time_s"]
    assert job["estimated_air_time_given_order_s"] >= search["air_time_s"]
    lines = done.stdout.splitlines()
    assert any(line.startswith("  search ") and "link estimates" in line for line in lines)
    assert any(line.startswith("  time ") and "seams" in line for line in lines)
    assert lines[-1].startswith("done in")
