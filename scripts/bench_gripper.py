"""What the gripper costs the collision checks (issue 42): the seal demo with its gripper
against the same cell without it, in this process.

    python scripts/bench_gripper.py [--seeds 3]

Prints, for both cells, the distance queries and time of the trajectory check of the
demo's planned motion, and the planning time of a link around a thin plate across a
60° turn of axis 1 (the cell of tests/job/test_links.py), one per seed; and the ratios.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from offline_prog.collision.check import check_trajectory
from offline_prog.job.links import plan_link
from offline_prog.plan import plan_job
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import build_scene, load_inputs

REPO = Path(__file__).resolve().parents[1]
DEMO = REPO / "cells" / "seal_plate_kr16.yaml"
CLEARANCE = 0.005


def cells(folder: Path, q_a: np.ndarray, q_b: np.ndarray, robot) -> dict[str, Path]:
    """The demo with and without its gripper, a thin plate across the move q_a → q_b."""
    p = robot.forward((0.5 * (q_a + q_b))[None])[0][:3, 3]
    yaw = np.rad2deg(np.arctan2(p[1], p[0]))
    plate = (
        "  - {name: thin_plate, shape: box, size_mm: [600, 10, 600], pose: {translation: "
        f"[{p[0]:.4f}, {p[1]:.4f}, {p[2]:.4f}], rotation: !Rpy {{deg: [0, 0, {yaw:.3f}]}}}}}}\n"
    )
    text = DEMO.read_text(encoding="utf-8")
    start, end = text.index("\ngripper:") + 1, text.index("\npart:\n") + 1
    out = {}
    for name, cell in (("with gripper", text), ("without", text[:start] + text[end:])):
        file = folder / f"{name.split()[0]}.yaml"
        file.write_text(cell.replace("obstacles:   # in I\n", "obstacles:   # in I\n" + plate))
        out[name] = file
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    args = parser.parse_args()
    job = plan_job(DEMO)
    q, t = job.samples.q, job.samples.t
    robot = job.robot
    q_a = robot.urdf_joints(robot.home_c)
    q_b = q_a + np.deg2rad([60.0, 0, 0, 0, 0, 0])
    results = {}
    with tempfile.TemporaryDirectory() as folder:
        for name, file in cells(Path(folder), q_a, q_b, robot).items():
            scene = build_scene(load_inputs(file, ROBOTS_DIR))
            started = time.perf_counter()
            check = check_trajectory(scene, q, t, np.zeros(len(t)), clearance=CLEARANCE)
            check_s = time.perf_counter() - started
            links = []
            for seed in range(args.seeds):
                link = plan_link(
                    scene,
                    robot,
                    q_a,
                    q_b,
                    clearance=CLEARANCE,
                    self_clearance=CLEARANCE,
                    seed=seed,
                    time_budget_s=120.0,
                    rate_hz=250.0,
                    name="bench",
                )
                links.append(link.planning_time_s)
            queries = check.stats["distance_queries"]
            results[name] = (queries, check_s, float(np.median(links)))
            print(
                f"{name:13s} check: {queries:6d} queries, {check_s:6.2f} s; thin-plate link: "
                f"median {np.median(links):6.2f} s ({', '.join(f'{s:.2f}' for s in links)})"
            )
    (qw, cw, lw), (qo, co, lo) = results["with gripper"], results["without"]
    print(f"ratios with/without: queries {qw / qo:.2f}, check {cw / co:.2f}, link {lw / lo:.2f}")


if __name__ == "__main__":
    main()
