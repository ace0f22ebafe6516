"""Seam-order benchmark (issue 13): auto order against brute force on a real job.

A job of eight seams on the demo plate (KUKA KR 16-2, fixed nozzle): six holes and two
stripes, each allowed to run either way (``direction: auto``), every seam planned by the
one-seam pipeline in both directions (and on other collision-free IK branches) with its
approach and retract. Brute force tries every order (8! = 40,320) with the best options
for each; ``order: auto`` solves it
exactly (Held–Karp) — both by the synchronised-PTP link estimate (job.order). Then the
exact and heuristic solvers on random instances of 8–14 seams: runtime and the
heuristic's gap.

    python scripts/bench_order.py [--holes 6] [--sizes 8 10 12 14]

``--holes`` takes fewer of the six holes (the job then has that many plus the two
stripes); ``--sizes`` the random instances' seam counts. Target (issue 13): auto air time
within 5 % of brute force.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from offline_prog.job.home import home_pose
from offline_prog.job.link_costs import LinkCosts
from offline_prog.job.order import _held_karp, order_job
from offline_prog.job.order_search import local_search
from offline_prog.job.stages import seam_options
from offline_prog.plan import SeamPlanner
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import build_scene, load_inputs

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent / "support"))  # the brute-force oracle

from order_oracle import brute_force_order  # noqa: E402

HOLES = [(-120, -60), (0, -60), (120, -60), (-120, 40), (0, 40), (120, 40)]


def eight_seam_cell(folder: Path, holes: int = len(HOLES)) -> Path:
    """The demo job's cell with ``holes`` of the six holes and the two stripes."""
    text = (REPO / "cells" / "seal_job_kr16.yaml").read_text(encoding="utf-8")
    head, tail = text[: text.index("\nseams:") + 1], text[text.index("\njob:") + 1 :]
    seams = ["seams:"]
    for k, (x, y) in enumerate(HOLES[:holes]):
        seams.append(
            f"  - {{name: hole_{k}, analytic: {{kind: arc, center: [{x}, {y}, 0], radius: 20,"
            f" start_deg: 0, end_deg: 360}}, units: mm, closed: true, normal: [0, 0, 1],"
            f" direction: auto}}"
        )
    for k, y in enumerate((-110, 110)):
        seams.append(
            f"  - {{name: stripe_{k}, analytic: {{kind: line, start: [-150, {y}, 0], "
            f"end: [150, {y}, 0]}}, units: mm, normal: [0, 0, 1], direction: auto}}"
        )
    file = folder / "eight_seams.yaml"
    file.write_text(head + "\n".join(seams) + "\n" + tail, encoding="utf-8")
    return file


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--holes", type=int, default=len(HOLES), choices=range(len(HOLES) + 1), help="(6)"
    )
    parser.add_argument(
        "--sizes", type=int, nargs="+", default=[8, 10, 12, 14], help="random instances' seams"
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        inputs = load_inputs(eight_seam_cell(Path(folder), args.holes), ROBOTS_DIR)
        scene = build_scene(inputs)
        q_home = home_pose(inputs, scene)
        start = time.perf_counter()
        # The job's own seam planner (one process: the figures are this process's).
        planner = SeamPlanner(lambda _: None, {}, parallel=False)
        options = seam_options(inputs, scene, planner, lambda _: None).options
        planning = time.perf_counter() - start
    flat = [(o.seam, o.label, o.q_in, o.q_out) for seam in options for o in seam]
    robot, n = inputs.robot, len(options)
    limits = {
        "qd_max": robot.qd_max,
        "qdd_max": robot.qdd_max,
        "n_seams": n,
        "controller_joints": robot.controller_joints,
    }
    start = time.perf_counter()
    brute, _ = brute_force_order(flat, q_home, **limits)
    t_brute = time.perf_counter() - start
    start = time.perf_counter()
    auto = order_job(flat, q_home, mode="auto", **limits)
    t_auto = time.perf_counter() - start
    print(f"== seam order: {n} seams, {len(flat)} options (directions, branches), KR 16-2 ==")
    print(f"planning the seam options: {planning:.1f} s")
    print(f"brute force ({n}! orders x best options): air {brute:.3f} s in {t_brute:.2f} s")
    print(f"order: auto ({auto.method}): air {auto.air_time_s:.3f} s in {t_auto * 1e3:.1f} ms")
    print(f"ratio auto / brute force: {auto.air_time_s / brute:.4f} (target <= 1.05)")
    print(
        f"given order: air {auto.given_air_time_s:.3f} s; auto saves {auto.saved_s:.3f} s "
        f"({100 * auto.saved_s / auto.given_air_time_s:.1f} %)"
    )
    print("== exact (Held-Karp) vs heuristic on random instances, 2 options per seam ==")
    rng = np.random.default_rng(0)
    for n in args.sizes:
        options = [
            (k, "", rng.uniform(-2, 2, 6), rng.uniform(-2, 2, 6))
            for k in range(n)
            for _ in range(2)
        ]
        costs = LinkCosts(options, np.zeros(6), robot.qd_max, robot.qdd_max)
        start = time.perf_counter()
        exact, _ = _held_karp(costs, n)
        t_exact = time.perf_counter() - start
        start = time.perf_counter()
        heuristic = local_search(costs).air_time_s
        t_heuristic = time.perf_counter() - start
        print(
            f"n = {n:2d}: exact {t_exact:.3f} s, heuristic {t_heuristic:.3f} s, "
            f"heuristic / exact {heuristic / exact:.4f}"
        )


if __name__ == "__main__":
    main()
