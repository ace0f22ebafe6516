"""Benchmark: plan the demo cells stage by stage, and compare path IK with references.

Run: ``python scripts/bench.py [--samples 5000] [--drake-samples 300]
[--only PART ...] [--runs 3] [--big-runs 1] [--big-seams 30] [--candidates 5]
[--cells STEM ...]``. The parts, in a full run's order: ``table`` (issue 25's table,
scripts/bench_table.py: each figure with the import floor of the same run),
``command``, ``stages``, ``collision``, ``session``, ``ik`` (path IK), ``timing``
(scripts/bench_timing.py); ``--only place`` runs scripts/bench_place.py (the placement
search, ~10 minutes), ``--only candidate`` scripts/bench_candidate.py (where a
placement candidate's time goes). ``--cells`` picks demo cells by file stem (default:
every cell in cells/); every cell is planned as a job (a ``path:`` cell is a one-seam
job), the path IK on its first seam.

All figures come from the same process on the same machine, so the ratios
hold even where the absolute numbers drift. Path IK is compared on one flange
path of ``--samples`` poses (the demo cell's own path, resampled):

- offline_prog: all eight analytic solutions per pose, branch unwrapping, 2π
  start choice, joint-limit and continuity checks (``path_ik``), vectorized;
- Drake InverseKinematics, one solve per sample seeded with the previous one
  (``drake_ik.solve_path``, the obvious baseline), on the first --drake-samples;
- py-opw-kinematics (Rust) ``batch_inverse`` on the same poses (OPW robots only).

Each reports samples per second and the max pose error of its solution (FK of
the returned joints against the target, by this package's analytic FK, which
tests tie to Drake's FK of the URDF to 1e-15).
"""

from __future__ import annotations

import argparse
import functools
import sys
import time
from pathlib import Path

import numpy as np

# This checkout's package, not an installed one (the subprocess figures run it too); the
# other scripts (bench_table, bench_timing) and their support (py_opw_reference).
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent / "support"))

from bench_table import CELLS, add_table_flags, chosen_cells, table  # noqa: E402


def best_of(repeats: int, function):
    """(smallest wall time [s], last result) over ``repeats`` calls."""
    best, result = np.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        best = min(best, time.perf_counter() - start)
    return best, result


def pose_errors(X_target: np.ndarray, X_got: np.ndarray) -> tuple[float, float]:
    """Max position [m] and angle [rad] error between (N, 4, 4) pose arrays."""
    from scipy.spatial.transform import Rotation

    distance = np.linalg.norm(X_target[:, :3, 3] - X_got[:, :3, 3], axis=1)
    R = np.swapaxes(X_target[:, :3, :3], 1, 2) @ X_got[:, :3, :3]
    ok = ~np.isnan(R).any(axis=(1, 2))
    angle = Rotation.from_matrix(R[ok]).magnitude()  # accurate near 0, unlike arccos
    return float(np.nanmax(distance)), float(angle.max())


def bench_stages(cells: list[Path], runs: int = 3) -> None:
    from offline_prog.plan import plan_job

    print(f"== planning the demo cells (stage times, best of {runs}) ==")
    for file in cells:
        total, job = best_of(runs, lambda file=file: plan_job(file))
        stages = ", ".join(f"{k} {v * 1e3:.0f} ms" for k, v in job.timings_s.items())
        print(f"{file.stem:24s} {len(job.samples.t):6d} samples  total {total:.3f} s  ({stages})")


def bench_command(cell: Path, runs: int = 5) -> None:
    """The whole ``offline-prog plan`` command as a user runs it (a fresh process each
    time, all outputs written), median of ``runs``; then each part's share, measured
    in this process: imports (a fresh interpreter), the plan stages, every output."""
    import statistics
    import subprocess
    import tempfile

    from offline_prog.plan import plan_job

    print(f"== whole command: offline-prog plan {cell.name} (median of {runs}) ==")
    walls = []
    with tempfile.TemporaryDirectory() as out:
        for _ in range(runs):
            start = time.perf_counter()
            subprocess.run(
                [sys.executable, "-m", "offline_prog", "plan", str(cell), "--out", out],
                check=True,
                capture_output=True,
            )
            walls.append(time.perf_counter() - start)
        code = (
            "import time; t = time.perf_counter(); import offline_prog.cli, offline_prog.plan, "
            "offline_prog.results.job_folder; print(time.perf_counter() - t)"
        )
        imports = statistics.median(
            float(
                subprocess.run(
                    [sys.executable, "-c", code], check=True, capture_output=True, text=True
                ).stdout
            )
            for _ in range(3)
        )
        parts = {"interpreter + imports": imports}
        plan = plan_job(cell)  # what the command plans: a path: cell is a one-seam job
        parts.update({f"plan: {k}": v for k, v in plan.timings_s.items()})
        parts.update({f"write: {k}": v for k, v in _output_times(plan, Path(out)).items()})
    wall = statistics.median(walls)
    print(f"wall {wall:.2f} s (runs: {', '.join(f'{w:.2f}' for w in walls)})")
    for name, seconds in parts.items():
        print(f"  {name:28s} {seconds * 1e3:7.0f} ms  {100 * seconds / wall:5.1f} %")
    rest = wall - sum(parts.values())
    print(f"  {'(process start, CLI, rest)':28s} {rest * 1e3:7.0f} ms  {100 * rest / wall:5.1f} %")


def _output_times(job, out: Path) -> dict[str, float]:
    """Seconds of ``write_job_outputs`` (all outputs; preview.html on the second core)."""
    from offline_prog.results.job_folder import write_job_outputs

    start = time.perf_counter()
    write_job_outputs(job, out / "outputs")
    return {"every output": time.perf_counter() - start}


def bench_collision(cells: list[Path], runs: int = 3) -> None:
    """Collision checking of each demo job with the vendor meshes (what plans use) and
    with the primitive stand-ins (<robot>_primitives.urdf), same motion, same process:
    the whole job's check (every sample of home, links, seams), as ``plan`` runs it."""
    import dataclasses

    from offline_prog.collision.check import check_trajectory
    from offline_prog.plan import plan_job
    from offline_prog.scene.drake_cell import build_cell_model

    print("\n== collision check along the planned job (full cell geometry) ==")
    for file in cells:
        job = plan_job(file)
        samples, motion = job.samples, job.cell.motion
        q = samples.q
        rates = {}
        stand_in = job.robot.urdf_path.with_name(f"{job.robot.name}_primitives.urdf")
        for model, robot in (
            ("meshes", job.robot),
            ("stand-ins", dataclasses.replace(job.robot, urdf_path=stand_in)),
        ):
            drake = build_cell_model(job.cell, file, robot)
            check = functools.partial(
                check_trajectory,
                drake,
                q,
                samples.t,
                np.nan_to_num(samples.path_m),
                clearance=motion.clearance,
                self_clearance=motion.self_clearance,
            )
            seconds, result = best_of(runs, check)
            rates[model] = len(q) / seconds
            print(
                f"{file.stem:24s} {model:9s} {len(q):6d} samples  {seconds * 1e3:7.1f} ms  "
                f"{rates[model]:10.0f} samples/s  min distance "
                f"{result.min_distance_m * 1e3:.1f} mm"
            )
        print(f"{'':24s} meshes / stand-ins: {rates['meshes'] / rates['stand-ins']:.2f}×")


def py_opw_robot(robot):
    """py-opw-kinematics for an OPW robot, or None when it is not installed."""
    try:
        from py_opw_reference import py_opw_robot as reference

        return reference(robot.params)
    except ImportError:
        return None


def bench_path_ik(file: Path, n_samples: int, n_drake: int) -> None:
    """Path IK on the cell's first seam (its plan in the job)."""
    from pydrake.math import RigidTransform, RotationMatrix

    from offline_prog.config.cell import transform
    from offline_prog.joints.drake_ik import solve_path, solve_pose
    from offline_prog.joints.path_ik import base_poses, branch_results, choose_branch
    from offline_prog.plan import plan_job
    from offline_prog.scene.drake_cell import build_drake_cell

    plan = plan_job(file).seams[0]
    robot, cell = plan.robot, plan.cell
    X_IB = transform(cell.robot.X_IB)
    f = plan.flange(np.linspace(0.0, plan.flange.length, n_samples))
    X_BE = base_poses(X_IB, f.p_IE, f.R_IE)
    print(f"\n== path IK, {file.stem} ({robot.name}), {n_samples} poses ==")

    seconds, chosen = best_of(5, lambda: choose_branch(branch_results(robot, X_BE)))
    ours_rate = n_samples / seconds
    errors = pose_errors(X_BE, robot.forward(chosen.q))
    print(
        f"offline_prog path IK : {seconds * 1e3:8.2f} ms  {ours_rate:12.0f} samples/s  "
        f"max error {errors[0]:.1e} m / {errors[1]:.1e} rad  (all branches, limits, 2π start)"
    )

    drake = build_drake_cell(
        robot, X_IB=X_IB, X_IT=transform(cell.tool.X_IT), X_PE=transform(cell.part.X_PE)
    )
    n = min(n_drake, n_samples)
    start = time.perf_counter()
    result = solve_path(drake, f.p_IE[:n], f.R_IE[:n], chosen.q[0])
    drake_seconds = time.perf_counter() - start
    drake_rate = n / drake_seconds
    drake_errors = pose_errors(X_BE[:n], robot.forward(result.q))
    print(
        f"Drake IK per sample  : {drake_seconds / n * 1e3:8.3f} ms/sample "
        f"{drake_rate:10.0f} samples/s  max error {drake_errors[0]:.1e} m / "
        f"{drake_errors[1]:.1e} rad  ({int(result.success.sum())}/{n} solved)"
    )
    print(f"  ratio offline_prog / Drake (program reused): {ours_rate / drake_rate:8.0f}x")
    n_fresh = min(100, n)
    start = time.perf_counter()
    q_seed = chosen.q[0]
    for i in range(n_fresh):  # the obvious baseline: a new InverseKinematics per sample
        q_seed, _ = solve_pose(drake, RigidTransform(RotationMatrix(f.R_IE[i]), f.p_IE[i]), q_seed)
    fresh_rate = n_fresh / (time.perf_counter() - start)
    print(
        f"Drake IK, new program per sample: {1e3 / fresh_rate:8.3f} ms/sample "
        f"{fresh_rate:10.0f} samples/s  ratio offline_prog / it: {ours_rate / fresh_rate:6.0f}x"
    )

    other = py_opw_robot(robot) if robot.family == "opw" else None
    if other is None:
        print("py-opw-kinematics    : not applicable (UR kinematics) or not installed")
        return
    from scipy.spatial.transform import RigidTransform as ScipyTransform

    poses = ScipyTransform.from_matrix(X_BE)
    opw_seconds, q_opw = best_of(5, lambda: other.batch_inverse(poses, current_joints=chosen.q[0]))
    q_opw = np.asarray(q_opw, dtype=float)
    opw_rate = n_samples / opw_seconds
    opw_errors = pose_errors(X_BE, robot.forward(q_opw))
    print(
        f"py-opw-kinematics    : {opw_seconds * 1e3:8.2f} ms  {opw_rate:12.0f} samples/s  "
        f"max error {opw_errors[0]:.1e} m / {opw_errors[1]:.1e} rad  (batch_inverse, "
        "nearest solution only)"
    )
    print(f"  per-sample cost offline_prog / py-opw-kinematics: {opw_rate / ours_rate:6.2f}x")


def bench_session(cells: list[Path], repeats: int = 3) -> None:
    """Re-plan latency of ``offline-prog session``: a tool-pose change (X_IT x ± 5 mm) and
    a speed change (± 10 %) after the first plan, each a fresh value (no cache hit); the
    median and the slowest of ``repeats``, and the stages that ran."""
    from offline_prog.session.replan import Replanner
    from offline_prog.session.state import values, with_value

    print(f"\n== session: re-plan latency (median / slowest of {repeats}) ==")
    for file in cells:
        planner = Replanner(file)
        first = planner.plan(planner.initial)
        line = f"{file.stem:24s} first {first.seconds:5.2f} s"
        for name, key, steps in (
            ("tool pose", "X_IT.x", [5.0, -5.0] * repeats),
            ("speed", "speed", [1.1, 0.9] * repeats),
        ):
            state, seconds, ran = planner.initial, [], None
            planner.plan(state)
            for step in steps[:repeats]:
                value = values(planner.initial)[key]
                state = with_value(state, key, value + step if key == "X_IT.x" else value * step)
                result = planner.plan(state)
                seconds.append(result.seconds)
                ran = result.ran
            line += f"  {name} {np.median(seconds):5.2f} / {max(seconds):5.2f} s ({', '.join(ran)})"
        print(line)


# The parts of a full run, in order (place and candidate only when asked: minutes).
PARTS = ("table", "command", "stages", "collision", "session", "ik", "timing")
OWN_SCRIPTS = ("place", "candidate")  # scripts/bench_place.py, scripts/bench_candidate.py


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=5000, help="path IK poses (5000)")
    parser.add_argument("--drake-samples", type=int, default=300, help="Drake IK poses (300)")
    parser.add_argument(
        "--only",
        nargs="+",
        choices=PARTS + OWN_SCRIPTS,
        help=f"run these parts (default: {' '.join(PARTS)})",
    )
    add_table_flags(parser)  # --runs, --big-runs, --big-seams, --candidates, --cells
    args = parser.parse_args()
    cells = chosen_cells(parser, args)
    one_seam = [c.stem for c in cells if "\nseams:" not in c.read_text(encoding="utf-8")]
    for part in args.only or PARTS:
        if part == "table":
            table(args, cells)
        elif part == "command":
            bench_command(cells[0] if args.cells else CELLS / "seal_plate_kr16.yaml", args.runs)
        elif part == "stages":
            bench_stages(cells, args.runs)
        elif part == "collision":
            bench_collision(cells, args.runs)
        elif part == "session":
            bench_session(cells, args.runs)
        elif part == "ik":
            for file in cells:
                bench_path_ik(file, args.samples, args.drake_samples)
        elif part == "timing":
            from bench_timing import bench_timing

            bench_timing(one_seam)
        else:  # its own script, with its own defaults (place: ~10 minutes)
            import importlib

            sys.argv = sys.argv[:1]
            importlib.import_module(f"bench_{part}").main()


if __name__ == "__main__":
    main()
