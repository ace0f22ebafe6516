"""Where a placement candidate's time goes (issue 25's one figure not met).

Run: ``python scripts/bench_candidate.py [--rounds 3] [--candidates 5]``. In one
process: the feasible ones of issue 25's seeded candidates of the seal job's placement
demo (cells/placement/seal_job_far_kr16.yaml, ``bench_table.place_batch``) through
``place``'s serial engine, after the cell is loaded, as a worker runs them:

1. their CPU time, median over ``--rounds``;
2. each stage's share of it, by cProfile's cumulative time (the profiler slows
   Python-heavy code more than numpy and Drake: the shares are approximate);
3. a what-if that is not an option of the product: the same candidates with the time
   law's averaged-profile stage skipped (``path_timing._cannot_win`` made true, so the
   staircase law stands): CPU time as a ratio of (1), and how much longer the
   candidates' cycle times are. It bounds what any speed-up of that stage alone can
   give.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's package
sys.path.insert(0, str(Path(__file__).resolve().parent))  # bench_table

from bench_table import place_batch  # noqa: E402

from offline_prog.placement.engine import SerialEngine  # noqa: E402
from offline_prog.timing import path_timing  # noqa: E402

# (label, module path suffix, function): the stages of a job candidate, nested as
# they call each other (``plan.plan_loaded_job``), then what runs inside several.
STAGES = (
    ("seam options, every seam both ways", "job/stages.py", "seam_options"),
    ("  tool rotations ranked (analytic IK)", "joints/joint_plan.py", "tool_rotations"),
    ("  untimed options (path IK, collision verdict)", "job/untimed.py", "untimed_options"),
    ("order, and the chosen seams timed", "job/untimed.py", "timed_order"),
    ("  time law with its jerk check", "joints/jerk_check.py", "verified_timing"),
    ("    averaged-profile stage", "timing/filtered_stage.py", "filtered_timing"),
    ("    staircase stage", "timing/jerk_stage.py", "jerk_limited_law"),
    ("  timed collision checks", "offline_prog/stages.py", "check_attempt"),
    ("links from home and back", "job/stages.py", "link_job"),
    ("the whole job's collision check", "job/stages.py", "check_job"),
    ("in all stages: TOPP-RA solves", "timing/time_optimal.py", "topp_profile"),
    ("in all stages: collision checks", "collision/check.py", "check_trajectory"),
    ("in all stages: analytic IK", "robot/kinematics_opw.py", "_solutions"),
)


def run(engine, candidates) -> tuple[list[float], list]:
    """(CPU seconds of each candidate, their evaluations)."""
    seconds, evaluations = [], []
    for candidate in candidates:
        start = time.process_time()
        (evaluation,) = engine.map("plan", [candidate])
        seconds.append(time.process_time() - start)
        evaluations.append(evaluation)
    return seconds, evaluations


def measured(engine, candidates, rounds: int) -> tuple[float, list[float]]:
    """(median CPU seconds of a candidate over ``rounds``, their cycle times [s])."""
    seconds = []
    for _ in range(rounds):
        each, evaluations = run(engine, candidates)
        seconds += each
    return statistics.median(seconds), [e.cycle_time_s for e in evaluations]


def shares(engine, candidates) -> list[tuple[str, float]]:
    """Each STAGES entry's share of the candidates' time under cProfile."""
    profile = cProfile.Profile()
    profile.enable()
    run(engine, candidates)
    profile.disable()
    stats = pstats.Stats(profile).stats
    total = sum(entry[2] for entry in stats.values())  # every function's own time
    cumulative = {}
    for (file, _, name), (_, _, _, ct, _) in stats.items():
        for label, suffix, function in STAGES:
            if name == function and file.endswith(suffix):
                cumulative[label] = cumulative.get(label, 0.0) + ct
    return [(label, cumulative.get(label, 0.0) / total) for label, _, _ in STAGES]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3, help="rounds of the CPU time (3)")
    parser.add_argument(
        "--candidates", type=int, default=5, help="seeded candidates, the feasible timed (5)"
    )
    args = parser.parse_args()
    payload, batch = place_batch(args.candidates)
    engine = SerialEngine(payload)
    try:
        engine.map("screen", batch[:1])  # loads the cell, as a worker has
        _, evaluations = run(engine, batch)
        feasible = [e.candidate for e in evaluations if e.feasible]
        if not feasible:
            print(f"== none of the {len(batch)} seeded candidates is feasible: nothing to time ==")
            return
        base, base_cycle = measured(engine, feasible, args.rounds)
        print(f"== one feasible seal-job candidate ({len(feasible)} of {len(batch)} seeded) ==")
        print(f"  CPU time, median of {args.rounds} rounds × {len(feasible)}: {base:.2f} s")
        print("  shares (cProfile, cumulative):")
        for label, share in shares(engine, feasible):
            print(f"    {label:48s} {share * 100:5.1f} %")
        cannot_win = path_timing._cannot_win
        path_timing._cannot_win = lambda *args, **kwargs: True
        try:
            alone, cycle = measured(engine, feasible, args.rounds)
        finally:
            path_timing._cannot_win = cannot_win
        longer = max(c / b - 1.0 for c, b in zip(cycle, base_cycle, strict=True))
        print(
            "  what-if (not a product option): the averaged-profile stage skipped:"
            f" {alone:.2f} s ({alone / base:.2f}× the above), cycle times up to"
            f" {longer * 100:.1f} % longer"
        )
    finally:
        engine.close()


if __name__ == "__main__":
    main()
