"""The ``plan`` command imports what it needs and no more (issue 25: interactive speed).

A fresh interpreter imports the CLI, then plans the seal demo the way ``offline-prog
plan`` does, and reports ``sys.modules`` at both points. The command's start-up must
not load the heavy packages only other commands or outputs use (the preview child
draws meshes with trimesh; sessions use MeshCat; placement uses Dask), and the module
counts stay within the budgets below (measured 297 and 1,172 on this tree, 1,600
before issue 25; a new eager import of trimesh or pydrake.all would cross them).
Counting modules, not seconds: no timed test.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

# Loaded by neither the CLI's import nor the plan in the main process.
NEVER = {"matplotlib", "trimesh", "networkx", "PIL", "meshcat", "dask", "distributed", "coacd"}
# Loaded by the plan where used, never by importing the CLI.
NOT_AT_START = NEVER | {"toppra", "ruckig", "ompl", "fcl", "scipy", "pydrake"}
BUDGET_START = 400  # modules after ``import offline_prog.cli``
BUDGET_PLAN = 1300  # modules after planning and writing the seal demo

PROBE = """
import json, sys
import offline_prog.cli as cli
start = sorted(sys.modules)
code = cli.main(["plan", sys.argv[1], "--out", sys.argv[2]])
print(json.dumps({"code": code, "start": start, "plan": sorted(sys.modules)}))
"""


def _top(modules: list[str]) -> set[str]:
    return {name.split(".")[0] for name in modules}


def test_plan_imports_stay_within_budget(tmp_path):
    cell, out = REPO / "cells" / "seal_plate_kr16.yaml", tmp_path / "plan"
    done = subprocess.run(
        [sys.executable, "-c", PROBE, str(cell), str(out)],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=True,
    )
    seen = json.loads(done.stdout.strip().splitlines()[-1])
    assert seen["code"] == 0 and (out / "trajectory.csv").is_file()
    assert _top(seen["start"]) & NOT_AT_START == set()
    assert _top(seen["plan"]) & NEVER == set()
    assert "scipy.optimize" not in seen["start"] and "pydrake.all" not in seen["plan"]
    assert len(seen["start"]) <= BUDGET_START, len(seen["start"])
    assert len(seen["plan"]) <= BUDGET_PLAN, len(seen["plan"])


TOPPRA_PLOTS = """
import sys
from offline_prog.timing.time_optimal import _toppra_algorithm
algorithm = _toppra_algorithm()
assert "matplotlib" not in sys.modules
import toppra.algorithm.algorithm as module
assert callable(module.plt.subplot)  # the stand-in imports matplotlib.pyplot on use
assert "matplotlib.pyplot" in sys.modules
print("ok")
"""


def test_toppra_loads_without_matplotlib_and_can_still_plot():
    done = subprocess.run(
        [sys.executable, "-c", TOPPRA_PLOTS], cwd=REPO, capture_output=True, text=True, check=True
    )
    assert done.stdout.strip() == "ok"
