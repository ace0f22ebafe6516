"""Link planning benchmark (issue 13): success rate and planning time of link moves
between seeded random collision-free configurations in a cluttered cell.

The cell is the seal demo (KUKA KR 16-2 carrying a 400 x 300 mm plate past a nozzle on
a stand) plus posts, a wall and a shelf around the robot. Start and goal are drawn
uniformly within the joint limits and kept when clear at the cell's clearances.

    python scripts/bench_links.py [--pairs 100] [--seed 0] [--budget 10]

Prints the success rate, how many links needed OMPL, the median and 90th percentile
planning time per link, and the median link duration; targets (issue 13): success
≥ 99 %, median < 2 s on a 2-core machine.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from offline_prog.collision.motion import MotionChecker
from offline_prog.job.links import plan_link
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import build_scene, load_inputs

REPO = Path(__file__).resolve().parents[1]
CLUTTER = """\
  - {name: post_a, shape: cylinder, radius_mm: 60, length_mm: 2000,
     pose: {translation: [0.9, 0.8, 1.0]}}
  - {name: post_b, shape: cylinder, radius_mm: 60, length_mm: 2000,
     pose: {translation: [0.9, -0.8, 1.0]}}
  - {name: post_c, shape: cylinder, radius_mm: 60, length_mm: 2000,
     pose: {translation: [-0.7, 0.9, 1.0]}}
  - {name: wall, shape: box, size_mm: [40, 2400, 1600], pose: {translation: [-1.1, 0.0, 0.8]}}
  - {name: shelf, shape: box, size_mm: [500, 600, 30], pose: {translation: [0.2, -1.1, 0.9]}}
  - {name: beam, shape: box, size_mm: [2000, 80, 80], pose: {translation: [0.6, 0.0, 2.1]}}
"""
CLEARANCE = 0.005


def cluttered_cell(folder: Path) -> Path:
    text = (REPO / "cells" / "seal_plate_kr16.yaml").read_text(encoding="utf-8")
    text = text.replace("obstacles:   # in I\n", "obstacles:   # in I\n" + CLUTTER)
    file = folder / "cluttered.yaml"
    file.write_text(text, encoding="utf-8")
    return file


def clear_configurations(robot, checker, rng, count: int) -> np.ndarray:
    out = []
    while len(out) < count:
        q_c = rng.uniform(robot.q_lower, robot.q_upper)
        q = robot.urdf_joints(q_c)
        if checker.clear(q):
            out.append(q)
    return np.array(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=100, help="start/goal pairs (100)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (0)")
    parser.add_argument("--budget", type=float, default=10.0, help="seconds per link")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        inputs = load_inputs(cluttered_cell(Path(folder)), ROBOTS_DIR)
        scene = build_scene(inputs)
    robot = inputs.robot
    checker = MotionChecker(scene, clearance=CLEARANCE, self_clearance=CLEARANCE)
    rng = np.random.default_rng(args.seed)
    ends = clear_configurations(robot, checker, rng, 2 * args.pairs)
    times, durations, methods, failures = [], [], [], []
    for k in range(args.pairs):
        start = time.perf_counter()
        link = plan_link(
            scene,
            robot,
            ends[2 * k],
            ends[2 * k + 1],
            clearance=CLEARANCE,
            self_clearance=CLEARANCE,
            seed=args.seed + k,
            time_budget_s=args.budget,
            rate_hz=250.0,
            name=f"pair {k}",
            checker=checker,
        )
        times.append(time.perf_counter() - start)
        if link.ok:
            durations.append(link.duration_s)
            methods.append(link.method)
        else:
            failures.append(link.failure.reason)
    n = args.pairs
    ok = n - len(failures)
    print(f"== link planning: {n} seeded start/goal pairs, cluttered seal cell ==")
    print(f"success {ok}/{n} = {100 * ok / n:.1f} % (target >= 99 %)")
    print(f"direct {methods.count('direct')}, planned with OMPL {methods.count('planned')}")
    print(
        f"planning time per link: median {np.median(times):.3f} s (target < 2 s), "
        f"p90 {np.percentile(times, 90):.3f} s, max {np.max(times):.3f} s"
    )
    print(f"link duration: median {np.median(durations):.2f} s")
    for reason in failures[:5]:
        print(f"  failed: {reason}")


if __name__ == "__main__":
    main()
