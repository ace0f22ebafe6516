"""Jobs of any size (issue 23): the whole ``offline-prog plan`` command on generated jobs
of 30 and 100 seams, and the share of it the seam-order search takes.

The jobs: n short seams on the demo plate (scripts/support/many_seams.py: stripes and circles
on a grid, each allowed to run either way), order auto. Each command is a fresh process
as a user runs it (stdout piped: no progress display); its wall time includes imports
and writing the plan folder, its CPU time (user + system, both of its processes) says
more on a busy machine. The stage times and the order search's counters come from
the command's own report.json.

    python scripts/bench_job_size.py [--seams 30 100]
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent / "support"))  # the job generator

from many_seams import many_seam_cell  # noqa: E402


def bench(n: int, folder: Path) -> None:
    cell = many_seam_cell(folder, n)
    out = folder / f"out_{n}"
    before, start = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
    command = [sys.executable, "-m", "offline_prog", "plan", str(cell), "--out", str(out)]
    done = subprocess.run(command, cwd=REPO, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    if done.returncode not in (0, 1):
        print(f"{n} seams: exit {done.returncode}: {done.stderr.strip()}")
        return
    report = json.loads((out / "report.json").read_text(encoding="utf-8"))
    job, search = report["job"], report["job"]["order_search"]
    stages = ", ".join(f"{k} {v:.1f} s" for k, v in report["timings_s"].items())
    print(f"== {n} seams ({sum(job['options_per_seam'])} options), exit {done.returncode} ==")
    print(f"whole command: {wall:.1f} s wall, {cpu:.1f} s CPU (stages: {stages})")
    if not report["feasible"]:
        print(f"not feasible: {report['failure']}")
    print(
        f"order search: {search['method']}, {search['time_s']:.2f} s = "
        f"{100 * search['time_s'] / wall:.1f} % of the command; {search['rounds']} rounds in "
        f"{search['descents']} descents, {search['used_link_estimates'] / 1e6:.1f} of "
        f"{search['budget_link_estimates'] / 1e6:.0f} M link estimates, stopped: "
        f"{search['stopped']}"
    )
    print(
        f"estimated air time {search['air_time_s']:.2f} s (start {search['start_air_time_s']:.2f}"
        f" s, given order {job['estimated_air_time_given_order_s']:.2f} s, lower bound "
        f"{search['lower_bound_s']:.2f} s); cycle {job['cycle_time_s']:.1f} s"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--seams", type=int, nargs="+", default=[30, 100], help="job sizes (30 100)"
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        for n in args.seams:
            bench(n, Path(folder))


if __name__ == "__main__":
    main()
