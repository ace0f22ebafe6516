"""Flying seam entry and exit (issue 37): each demo cell with a process model planned
with every seam at rest (``entry: rest``) and flying (``entry: flying``, the default),
in one process.

Run: ``PYTHONPATH=. python scripts/flying_entry_figures.py [--cells NAME ...]
[--approach-speed 0.05] [--baseline FOLDER]``.

Prints per cell and entry: each seam's entry as planned (flying, or rest and why), the
share of the gun-on length whose predicted quality (bead area, heat input, nip
temperature) is within ±5 % of the target (the model's band for heat input and tape:
its own tolerance), the worst gun-on row against the target, the gun-on rows where the
tool stands, the cycle time and the approach + retract time (a flying seam's leads
count as approach and retract), and the leads' top tool speed against the seam's
(at most 1: the process speed holds on the leads too) and each seam's lowest tool speed
against its top (1 where a flying seam runs at one speed from its first millimetre;
``--cells seal_job_kr16``: a cell without a process model prints its motion alone).
``--approach-speed`` adds the weld demo's setting of the issue (approach and retract
under 3 s). ``--baseline FOLDER`` compares each cycle with a plan folder per cell
(``FOLDER/<cell>/report.json``'s ``job.cycle_time_s``, e.g. an older main's). The programs
replay the plan's outputs within 1 % (tests/process/test_replay.py,
tests/robot_import/test_fanuc_job.py), so these are the programs' figures too.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

from off_seam_speeds import process_cells  # scripts/: the script's own folder

sys.path.insert(0, str(Path(__file__).resolve().parent / "support"))  # the figures' rules
from program_replay import BAND, WORST_ALLOWED, acceptance  # noqa: E402

from offline_prog.plan import StageTimer, plan_loaded_job
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import load_inputs

REPO = Path(__file__).resolve().parents[1]
CELLS = REPO / "cells"


def with_keys(inputs, *, entry: str | None = None, **motion):
    """The inputs with every seam's ``entry`` and ``motion`` keys replaced (in memory)."""
    cell = inputs.cell
    if entry is not None:
        cell = dataclasses.replace(
            cell,
            path=None if cell.path is None else dataclasses.replace(cell.path, entry=entry),
            seams=[dataclasses.replace(seam, entry=entry) for seam in cell.seams],
        )
    cell = dataclasses.replace(cell, motion=dataclasses.replace(cell.motion, **motion))
    return dataclasses.replace(inputs, cell=cell)


def figures(job) -> dict:
    """The acceptance figures of a planned job (module docstring)."""
    s, quality = job.samples, job.quality
    moves = sum(g.t_stop - g.t_start for g in s.segments if g.kind in ("approach", "retract"))
    lead_over = [
        float(lead.tcp_speed.max() / o.plan.trajectory.tcp_speed.max())
        for o in job.chosen
        for lead in (o.plan.lead_in, o.plan.lead_out)
        if lead is not None
    ]
    lowest = min(
        float(o.plan.trajectory.tcp_speed.min() / o.plan.trajectory.tcp_speed.max())
        for o in job.chosen
    )
    out = {
        "cycle_s": float(s.t[-1]),
        "moves_s": float(moves),
        "lead_over": max(lead_over, default=float("nan")),
        "seam_lowest": lowest,
        "entries": [
            f"{o.name}: {o.plan.entry['entry']}"
            + (f" ({o.plan.entry['reason']})" if o.plan.entry["reason"] else "")
            for o in job.chosen
        ],
    }
    if quality is None:  # a cell without a process model: its motion alone
        return out
    ratio = quality.values / quality.model.target - 1.0
    accepted = acceptance(job, ratio)
    worst = accepted["worst_row"]
    return out | {
        "share": accepted["share"],
        "worst": float(ratio[worst]),
        "worst_at": (s.labels()[worst], float(s.path_m[worst])),
        "standstill": accepted["standstill"],
    }


def baseline_cycle_s(folder: Path | None, name: str) -> float | None:
    """The cycle time [s] of the cell's plan folder under ``folder`` (None without one)."""
    report = None if folder is None else folder / name / "report.json"
    if report is None or not report.is_file():
        return None
    return float(json.loads(report.read_text(encoding="utf-8"))["job"]["cycle_time_s"])


def main(names: list[str], approach_speed: float | None, baseline: Path | None = None) -> None:
    for name in names:
        inputs = load_inputs(CELLS / f"{name}.yaml", ROBOTS_DIR)
        settings = {"rest": {"entry": "rest"}, "flying": {"entry": "flying"}}
        if approach_speed is not None and name.startswith("weld"):
            settings |= {
                f"rest, approach {approach_speed:g} m/s": {
                    "entry": "rest",
                    "approach_speed": approach_speed,
                },
                f"flying, approach {approach_speed:g} m/s": {
                    "entry": "flying",
                    "approach_speed": approach_speed,
                },
            }
        cycles = {}
        for label, keys in settings.items():
            job = plan_loaded_job(
                with_keys(inputs, **keys), StageTimer(lambda stage: None), clearance_profile=False
            )
            f = figures(job)
            cycles[label] = f["cycle_s"]
            print(f"{name:22s} {label:28s} {'; '.join(f['entries'])}")
            if not job.feasible:  # its figures are of a plan that cannot be run
                print(f"{'':22s} INFEASIBLE: {job.failure}")
            if "share" in f:
                segment, at = f["worst_at"]
                print(
                    f"{'':22s} gun-on within ±{BAND * 100:g} %: {f['share'] * 100:6.2f} %, "
                    f"worst {f['worst'] * 100:+8.2f} % ({segment} at σ = {at * 1e3:.1f} mm; "
                    f"{'ok' if abs(f['worst']) <= WORST_ALLOWED else 'beyond'} ±20 %), "
                    f"gun-on standstill rows {f['standstill']}"
                )
            print(
                f"{'':22s} cycle {f['cycle_s']:.2f} s, approach+retract {f['moves_s']:.2f} s, "
                f"leads' top tool speed / seam's {f['lead_over']:.3f}, "
                f"seams' lowest tool speed / their top {f['seam_lowest']:.3f}"
            )
        print(f"{'':22s} cycle flying / rest {cycles['flying'] / cycles['rest']:.3f}")
        before = baseline_cycle_s(baseline, name)
        if before is not None:
            print(
                f"{'':22s} cycle flying {cycles['flying']:.3f} s against the baseline's "
                f"{before:.3f} s ({cycles['flying'] - before:+.3f} s)"
            )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", nargs="*", help="cell stems (default: those with process:)")
    parser.add_argument("--approach-speed", type=float, default=0.05, help="m/s (weld demo)")
    parser.add_argument("--baseline", type=Path, help="folder of plan folders per cell")
    args = parser.parse_args()
    main(args.cells or process_cells(), args.approach_speed, args.baseline)
