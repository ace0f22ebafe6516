"""Write the documentation's measured figures (docs/figures.md): every demo cell planned,
its cycle time, seams, clearance and verdict, and the whole ``offline-prog plan``
command's wall time in a fresh process, each beside the import floor measured in the
same run (``python -c "import pydrake.all"``), with the machine and the date.

No figure in the documentation is typed by hand: the pages link to this file, and this
command rewrites it::

    python scripts/figures.py [--runs 3] [--cells STEM ...] [--tests] [--out docs/figures.md]
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import subprocess
import sys
from pathlib import Path

from bench_table import import_floor, plan_command

ROOT = Path(__file__).resolve().parents[1]
CELLS = ROOT / "cells"


def machine() -> str:
    """One line: the OS, the CPU, its cores, Python, and the load when measured."""
    cpu = platform.processor() or platform.machine()
    try:
        model = next(
            line.split(":", 1)[1].strip()
            for line in Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines()
            if line.startswith("model name")
        )
    except (OSError, StopIteration):
        model = cpu
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg()) if hasattr(os, "getloadavg") else "?"
    return (
        f"{platform.system()} {platform.release()}, {model}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, load average {load}"
    )


def demo_rows(cells: list[Path], runs: int) -> list[str]:
    """A Markdown row per cell: the plan (API, this process) and the command's time."""
    import offline_prog as op

    rows = []
    for cell in cells:
        plan = op.plan(cell)
        floor = import_floor(runs)
        wall = plan_command(cell, runs)
        verdict = "feasible" if plan.feasible else f"failed: {plan.failure}"
        rows.append(
            f"| `cells/{cell.name}` | {len(plan.seams)} | {plan.cycle_time_s:.2f} | "
            f"{1e3 * plan.min_distance_m:.1f} | {verdict} | {wall:.2f} | {floor:.2f} | "
            f"{wall / floor:.1f}× |"
        )
        print(f"  {cell.stem}: cycle {plan.cycle_time_s:.2f} s, plan command {wall:.2f} s")
    return rows


def test_count() -> str:
    """The default suite's test count (``pytest --collect-only``)."""
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "--collect-only", "-q", "-n", "0"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    last = [line for line in done.stdout.splitlines() if " collected" in line]
    return last[-1].strip() if last else "unknown"


def page(rows: list[str], *, runs: int, tests: str | None) -> str:
    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    lines = [
        "# Measured figures",
        "",
        "Written by `python scripts/figures.py` (do not edit by hand: run it again).",
        "",
        f"- measured: {now}",
        f"- machine: {machine()}",
        f"- timed: medians of {runs} run(s); the import floor is "
        '`python -c "import pydrake.all"`, measured before each command',
        "",
        "## Demo cells",
        "",
        "Each cell planned as `offline-prog plan` plans it (every cell is a job, home to "
        "home); the command's wall time includes Python's start, the imports and writing "
        "the whole plan folder.",
        "",
        "| cell | seams | cycle time [s] | smallest distance [mm] | verdict "
        "| `plan` command [s] | import floor [s] | command / floor |",
        "|---|---|---|---|---|---|---|---|",
        *rows,
    ]
    if tests is not None:
        lines += ["", "## Test suite", "", f"- `python3 -m pytest --collect-only`: {tests}"]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=3, help="runs per timed figure (median)")
    parser.add_argument("--cells", nargs="+", help="demo cell stems (default: every cells/*.yaml)")
    parser.add_argument("--tests", action="store_true", help="also count the default suite")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "figures.md")
    args = parser.parse_args()
    names = args.cells or sorted(p.stem for p in CELLS.glob("*.yaml"))
    cells = [CELLS / f"{name}.yaml" for name in names]
    rows = demo_rows(cells, args.runs)
    text = page(rows, runs=args.runs, tests=test_count() if args.tests else None)
    args.out.write_text(text, encoding="utf-8")
    print(f"wrote {args.out}: {len(rows)} cell(s), median of {args.runs} run(s)")


if __name__ == "__main__":
    main()
