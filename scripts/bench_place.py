"""Benchmark: the placement search (issue 16), its acceptance figures.

Run: ``python scripts/bench_place.py [--budget 16] [--seeds 5] [--candidates 32]
[--only demo]`` (``python scripts/bench.py --only place``). On this machine:

0. the README's demo command in a fresh process on 2 workers: wall and CPU time, and
   the load average (the machine may be shared);
1. a poor X_IT (cells/placement/seal_out_of_reach_kr16.yaml: the nozzle beyond reach):
   ``place`` finds a feasible placement and ``plan`` on placed.yaml succeeds;
2. feasible cells: the cut of the cycle time (≥ 15 %, or the report's reason why not)
   on cells/placement/seal_far_kr16.yaml, on the seal demo with a place: block and on
   the whole job cells/placement/seal_job_far_kr16.yaml (budget ≤ 12);
3. five seeds on seal_far: the best objectives' spread (≤ 2 %);
4. candidates per second through the planning pipeline, in this process and on a
   2-worker LocalCluster (after each worker has loaded the cell), the parallel
   efficiency (≥ 0.8), the cost per candidate and the projection for 10⁴ candidates
   on 16 cores;
5. bad input: exit code, stderr lines and wall time of each.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from offline_prog.config.cell import load_cell
from offline_prog.placement.engine import DaskEngine, SerialEngine
from offline_prog.placement.payload import cell_payload
from offline_prog.placement.run import place_cell
from offline_prog.placement.space import check_place
from offline_prog.plan import plan_job

ROOT = Path(__file__).resolve().parents[1]
CELLS = ROOT / "cells"
OUT_OF_REACH = CELLS / "placement" / "seal_out_of_reach_kr16.yaml"
FAR = CELLS / "placement" / "seal_far_kr16.yaml"
JOB = CELLS / "placement" / "seal_job_far_kr16.yaml"
JOB_BUDGET = 12  # a job's candidate is ~4 s
SEEDS = range(5)
THROUGHPUT_CANDIDATES = 32


def seal_with_place(folder: Path) -> Path:
    """The seal demo with the placement demos' place: block (same folder layout)."""
    block = FAR.read_text().split("\nplace:", 1)[1]
    file = folder / "seal_plate_kr16.yaml"
    file.write_text((CELLS / "seal_plate_kr16.yaml").read_text() + "place:" + block)
    return file


def search(file: Path, out: Path, budget: int, seed: int = 0, workers: int = 2) -> dict:
    start = time.perf_counter()
    data = place_cell(file, out, budget=budget, seed=seed, workers=workers)
    data["bench_wall_s"] = time.perf_counter() - start
    return data


def show(name: str, data: dict) -> None:
    best, base, cut = data["best"], data["baseline"], data["cycle_time_cut"]
    given = (
        f"{base['cycle_time_s']:.2f} s" if base["feasible"] else f"infeasible ({base['reason']})"
    )
    found = (
        f"{best['cycle_time_s']:.2f} s" if best["feasible"] else f"infeasible ({best['reason']})"
    )
    print(f"{name:<24} given {given:<28} best {found}", end="")
    if cut["percent"] is not None:
        print(f"  cut {cut['percent']:5.1f} %", end="")
    print(f"  ({data['engine']['candidates_evaluated']} candidates, {data['bench_wall_s']:.0f} s)")
    if cut.get("why_not_more"):
        print(f"{'':<24} why not more: {cut['why_not_more']}")


def throughput(file: Path, candidates: int = THROUGHPUT_CANDIDATES) -> None:
    """Candidates per second, serial vs a 2-worker LocalCluster, same candidates."""
    cell = load_cell(file)
    place, space = check_place(file, cell)
    payload = cell_payload(file, cell)
    import numpy as np

    rng = np.random.default_rng(0)
    batch = [space.candidate(x, 0) for x in rng.uniform(0.1, 0.9, (candidates, 4))]
    rates = {}
    for name, make in (
        ("serial", lambda: SerialEngine(payload)),
        ("LocalCluster 2", lambda: DaskEngine(payload, workers=2)),
    ):
        engine = make()
        try:
            engine.map("screen", batch[:1])  # serial: load the cell (Dask workers have)
            start = time.perf_counter()
            results = engine.map("plan", batch)
            rates[name] = len(batch) / (time.perf_counter() - start)
        finally:
            engine.close()
        feasible = sum(e.feasible for e in results)
        print(f"  {name:<16} {rates[name]:5.2f} candidates/s ({feasible}/{len(batch)} feasible)")
    cost = 1.0 / rates["serial"]
    efficiency = rates["LocalCluster 2"] / (2 * rates["serial"])
    print(f"  parallel efficiency on 2 workers: {efficiency:.2f} (acceptance ≥ 0.8)")
    minutes = 1e4 * cost / (16 * efficiency) / 60
    print(
        f"  cost per candidate {cost:.2f} s; 10⁴ candidates on 16 cores at this efficiency: "
        f"{minutes:.1f} min ({1e4 * cost / 16 / 60:.1f} min at efficiency 1)"
    )


def bad_input(folder: Path) -> None:
    text = OUT_OF_REACH.read_text()
    cases = {
        "empty range": text.replace("x: [700, 1900]", "x: [700, 700]"),
        "inverted range": text.replace("x: [700, 1900]", "x: [1900, 700]"),
        "budget 0 (file)": text.replace("budget: 16", "budget: 0"),
    }
    runs = []
    for name, variant in cases.items():
        file = folder / f"{name.split()[0]}.yaml"
        file.write_text(variant)
        runs.append((name, [str(file)]))
    runs.append(("--budget 0", [str(OUT_OF_REACH), "--budget", "0"]))
    runs.append(("unreachable scheduler", [str(OUT_OF_REACH), "--scheduler", "tcp://127.0.0.1:9"]))
    for name, args in runs:
        start = time.perf_counter()
        done = subprocess.run(
            [sys.executable, "-m", "offline_prog", "place", *args, "--out", str(folder / "o")],
            capture_output=True,
            text=True,
            timeout=120,
        )
        lines = done.stderr.strip().splitlines()
        print(
            f"  {name:<22} exit {done.returncode}, {len(lines)} line, "
            f"{time.perf_counter() - start:4.1f} s: {lines[-1] if lines else ''}"
        )


def demo(folder: Path) -> None:
    """The README's demo as a user runs it (a fresh process, 2 workers, output piped):
    its wall time, the CPU time of it and its worker processes, and the machine's
    load average before and after (the machine may be shared)."""
    before = os.getloadavg()
    start_cpu = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    command = [sys.executable, "-m", "offline_prog", "place", str(OUT_OF_REACH)]
    done = subprocess.run(
        [*command, "--out", str(folder / "demo"), "--workers", "2"],
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - start
    end_cpu = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (end_cpu.ru_utime - start_cpu.ru_utime) + (end_cpu.ru_stime - start_cpu.ru_stime)
    after = os.getloadavg()
    print(f"  exit {done.returncode}: {done.stdout.strip().splitlines()[-2]}")
    print(
        f"  wall {wall:.1f} s (acceptance < 60 s), CPU {cpu:.1f} s (the command and its "
        f"workers); load average {before[0]:.2f} before, {after[0]:.2f} after on "
        f"{os.cpu_count()} cores"
    )


def replanned(placed: Path) -> str:
    """``plan`` of a placed.yaml: feasible and cycle time, or why there is none."""
    if not placed.is_file():
        return "no placed.yaml (no feasible placement found)"
    job = plan_job(placed)  # a path: cell: a one-seam job
    return f"feasible {job.feasible}, cycle {job.samples.t[-1]:.2f} s"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--budget", type=int, default=16, help="candidates per search (16)")
    parser.add_argument("--seeds", type=int, default=len(SEEDS), help="seeds on seal_far (5)")
    parser.add_argument(
        "--candidates",
        type=int,
        default=THROUGHPUT_CANDIDATES,
        help=f"candidates of the throughput figure ({THROUGHPUT_CANDIDATES})",
    )
    parser.add_argument("--only", choices=["demo"], help="only the README's demo command")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        print("== the demo: offline-prog place seal_out_of_reach_kr16.yaml, 2 workers ==")
        demo(folder)
        if args.only:
            return
        print(f"== place: budget {args.budget}, 2-worker LocalCluster ==")
        data = search(OUT_OF_REACH, folder / "oor", args.budget)
        show("seal_out_of_reach_kr16", data)
        print(f"{'':<24} plan placed.yaml: {replanned(folder / 'oor' / 'placed.yaml')}")
        show("seal_plate_kr16", search(seal_with_place(folder), folder / "seal", args.budget))
        data = search(JOB, folder / "job", min(args.budget, JOB_BUDGET))
        show("seal_job_far_kr16 (job)", data)
        print(f"{'':<24} plan placed.yaml: {replanned(folder / 'job' / 'placed.yaml')}")
        bests = []
        for seed in range(args.seeds):
            data = search(FAR, folder / f"far{seed}", args.budget, seed=seed)
            show(f"seal_far_kr16 seed {seed}", data)
            if data["best"]["feasible"]:
                bests.append(data["best"]["cycle_time_s"])
        if bests:
            spread = (max(bests) - min(bests)) / min(bests)
            print(
                f"{len(bests)} of {args.seeds} seeds feasible: best cycle {min(bests):.3f} … "
                f"{max(bests):.3f} s, spread {100 * spread:.2f} % (acceptance ≤ 2 %)"
            )
        print(json.dumps(data["engine"]))
        print(f"== throughput (seal_far_kr16, the same {args.candidates} candidates) ==")
        throughput(FAR, args.candidates)
        print("== bad input ==")
        bad_input(folder)


if __name__ == "__main__":
    main()
