"""The moves off the seam (issue 37): each demo cell with a process model planned as
it is and with ``motion.approach_speed`` / ``motion.link_speed_percent`` set, in one
process; optionally against a baseline folder of older plans.

Run: ``python scripts/off_seam_speeds.py [--cells NAME ...] [--approach-speed 0.05]
[--link-percent 50] [--baseline /work/baseline_out]``.

Prints per cell and setting: the cycle time, the approach and retract time, the link
time, the gun-on length the process model predicts (approach and retract included) and
the stretches where the gun is open while the tool stands (``standstill``); with
``--baseline``, the cycle time of ``<baseline>/<cell>/report.json`` and the ratio.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

from offline_prog.config.cell import load_cell
from offline_prog.plan import StageTimer, plan_loaded_job
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import load_inputs

REPO = Path(__file__).resolve().parents[1]
CELLS = REPO / "cells"


def with_motion(inputs, **keys):
    """The inputs with the cell's ``motion`` keys replaced (in memory)."""
    motion = dataclasses.replace(inputs.cell.motion, **keys)
    return dataclasses.replace(inputs, cell=dataclasses.replace(inputs.cell, motion=motion))


def figures(job) -> dict:
    """Cycle, approach + retract and link times [s], the dispensed length [m] and the
    gun-on standstill stretches of a planned job."""
    durations = {"approach": 0.0, "retract": 0.0, "link": 0.0}
    for segment in job.samples.segments:
        if segment.kind in durations:
            durations[segment.kind] += segment.t_stop - segment.t_start
    quality = job.quality
    stretches = quality.job.stretches if quality else []
    return {
        "cycle_s": float(job.samples.t[-1]),
        "moves_s": durations["approach"] + durations["retract"],
        "links_s": durations["link"],
        "dispensed_m": quality.job.dispensed_length_m if quality else 0.0,
        "standstill": sum(s.cause == "standstill" for s in stretches),
    }


def main(names: list[str], settings: dict[str, dict], baseline: Path | None) -> None:
    print("cell                   setting                cycle s  approach+retract s  links s")
    print("                                                       dispensed mm  gun-on standstills")
    for name in names:
        inputs = load_inputs(CELLS / f"{name}.yaml", ROBOTS_DIR)
        results = {}
        for label, keys in settings.items():
            job = plan_loaded_job(
                with_motion(inputs, **keys), StageTimer(lambda stage: None), clearance_profile=False
            )
            results[label] = f = figures(job)
            print(
                f"{name:22s} {label:22s} {f['cycle_s']:7.2f} {f['moves_s']:18.2f} "
                f"{f['links_s']:8.2f} {1e3 * f['dispensed_m']:13.1f} {f['standstill']:5d}"
            )
        default = results["default"]["cycle_s"]
        for label, f in results.items():
            print(f"{'':22s} {label:22s} cycle / default {f['cycle_s'] / default:.3f}")
        report = None if baseline is None else baseline / name / "report.json"
        if report is not None and report.is_file():
            before = json.loads(report.read_text(encoding="utf-8"))["job"]
            print(
                f"{'':22s} baseline cycle {before['cycle_time_s']:.2f} s, approach+retract "
                f"{before['approach_retract_time_s']:.2f} s; default / baseline "
                f"{default / before['cycle_time_s']:.3f}"
            )


def process_cells() -> list[str]:
    """The demo cells (cells/*.yaml) with a process model."""
    return [c.stem for c in sorted(CELLS.glob("*.yaml")) if load_cell(c).process is not None]


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", nargs="*", help="cell stems (default: those with process:)")
    parser.add_argument("--approach-speed", type=float, default=0.05, help="m/s (default 0.05)")
    parser.add_argument("--link-percent", type=float, default=50.0, help="%% (default 50)")
    parser.add_argument("--baseline", type=Path, help="a folder of plan folders by cell stem")
    args = parser.parse_args()
    main(
        args.cells or process_cells(),
        {
            "default": {},
            f"approach {args.approach_speed:g} m/s": {"approach_speed": args.approach_speed},
            f"links {args.link_percent:g} %": {"link_speed_percent": args.link_percent},
        },
        args.baseline,
    )
