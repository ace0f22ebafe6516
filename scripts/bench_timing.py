"""Benchmark: the time-optimal process law (issue 14) on every one-seam demo cell.

Run: ``python scripts/bench_timing.py [CELL_STEM ...]`` (default: the one-seam demo
cells; also ``python scripts/bench.py --only timing``).

For each cell, in one process: the sin² plan and the time-optimal plan of the same
cell (both intents), and TOPP-RA's own duration without the jerk stage. Prints

- cycle times and the ratios time_optimal / TOPP-RA (acceptance ≤ 1.05) and
  time_optimal / sin² (≤ 1);
- constant_speed: the share of the path length where the TCP speed is within ±0.5 %
  of the commanded speed (≥ 90 % where the speed is feasible);
- the largest joint velocity, acceleration and jerk use on trajectory.csv, by finite
  differences of its qd columns (≤ 1.01);
- the solve time of the whole time-optimal law (``timing.path_timing``: TOPP-RA, the
  jerk stage, the averaged profile where it may win) on a 5,000-sample path, per
  intent (< 100 ms), and of TOPP-RA alone;
- the CPU time of that cycle_time law with TOPP-RA's lean passes
  (``timing.toppra_passes``) against toppra's own, and whether both laws are the same.
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import time
from pathlib import Path

import numpy as np

from offline_prog.plan import StageTimer, plan_seam
from offline_prog.results.plan_folder import trajectory_csv
from offline_prog.stages import build_scene, load_inputs
from offline_prog.timing.joint_timing import JointRates
from offline_prog.timing.speed_hold import SpeedHold
from offline_prog.timing.time_optimal import topp_profile

ROOT = Path(__file__).resolve().parents[1]
ONE_SEAM_CELLS = ["seal_plate_kr16", "tape_cylinder_ur10e", "weld_seam_irb2400"]
HOLD = 0.005  # ±0.5 % of the commanded speed


def plan_with(inputs, scene, **motion):
    """The one-seam plan of ``inputs`` with motion keys replaced."""
    cell = dataclasses.replace(
        inputs.cell, motion=dataclasses.replace(inputs.cell.motion, **motion)
    )
    stage = StageTimer(lambda s: None)
    return plan_seam(dataclasses.replace(inputs, cell=cell), stage, results={"scene": scene})


def csv_limit_use(plan) -> tuple[float, float, float]:
    """Largest joint velocity, acceleration and jerk use on trajectory.csv, from its
    qd columns by finite differences (controller axes)."""
    table = np.genfromtxt(io.StringIO(trajectory_csv(plan)), delimiter=",", names=True)
    t = table["t"]
    qd = np.column_stack([table[f"qd{k + 1}"] for k in range(6)])
    robot = plan.robot
    qd = robot.controller_joints(qd)
    qdd = np.diff(qd, axis=0) / np.diff(t)[:, None]
    t_mid = 0.5 * (t[1:] + t[:-1])
    qddd = np.diff(qdd, axis=0) / np.diff(t_mid)[:, None]
    return (
        float((np.abs(qd) / robot.qd_max).max()),
        float((np.abs(qdd) / robot.qdd_max).max()),
        float((np.abs(qddd) / robot.jerk_limits).max()),
    )


def held_share(plan) -> float:
    """Share of the path length where the TCP speed is within ±HOLD of the command."""
    tr = plan.trajectory
    v = plan.process_speed.v_m_s
    held = np.abs(tr.tcp_speed - v) <= HOLD * v
    ds = np.abs(np.diff(tr.s))
    return float(np.sum(ds * (held[1:] & held[:-1])) / np.sum(ds))


def held_where_feasible(plan) -> tuple[float, float]:
    """``timing.speed_hold`` measured on the plan's own samples (the TCP speed of
    trajectory.csv's rows), not on its time law: (share of the feasible length held
    within ±0.5 %, feasible share of the path)."""
    robot, tr, motion = plan.robot, plan.trajectory, plan.cell.motion
    hold = SpeedHold(
        path_rates(plan, 5000),
        v_process=plan.process_speed.v_m_s,
        a_max=motion.max_acceleration,
        j_max=motion.max_jerk,
        limits=(robot.qd_max, robot.qdd_max, robot.jerk_limits),
    )
    return hold.on_samples(tr.law_position, tr.tcp_speed)


def path_rates(plan, n: int) -> JointRates:
    """The plan's q, q′, q″ (controller axes) on n σ samples of its path, exactly
    (``BranchPath.rates``)."""
    from offline_prog.joints.joint_plan import BranchPath
    from offline_prog.timing.trajectory import TimeLawParameter

    robot, tr = plan.robot, plan.trajectory
    sigma = np.linspace(0.0, tr.law.length, n)
    parameter = TimeLawParameter(plan.flange, plan.cell.motion.speed_reference)
    path = BranchPath(robot, _X_IB(plan), plan.flange, parameter, plan.joints.branch)
    q_near = np.column_stack(
        [np.interp(sigma, tr.law_position, plan.joints.q[:, k]) for k in range(6)]
    )
    r = path.rates(sigma, q_near)
    return JointRates(sigma, *(robot.controller_joints(x) for x in (r.q, r.dq, r.ddq)))


def solve_time_5000(plan) -> tuple[float, float, float]:
    """(best wall time [s] of TOPP-RA alone, of the whole time-optimal law for
    constant_speed, for cycle_time): ``time_path`` as the plan runs it (TOPP-RA,
    the jerk stage, the averaged profile where it may win) on rates resampled to
    5,000 samples of the plan's path; best of 5."""
    from offline_prog.timing.path_timing import PathLimits, time_path

    robot, motion = plan.robot, plan.cell.motion
    rates = path_rates(plan, 5000)
    limits = PathLimits.of(
        robot,
        rates.sigma[-1],
        v_process=plan.process_speed.v_m_s,
        a_max=motion.max_acceleration,
        j_max=motion.max_jerk,
    )
    best = {}
    for _ in range(5):
        for process in ("constant_speed", "cycle_time"):
            start = time.perf_counter()
            timing = time_path(rates, limits, "time_optimal", process)
            elapsed = time.perf_counter() - start
            best[process] = min(best.get(process, np.inf), elapsed)
            assert timing.feasible
        profile = topp_profile(
            rates,
            qd_max=robot.qd_max,
            qdd_max=robot.qdd_max,
            v_cap=plan.process_speed.v_m_s,
            a_path=motion.max_acceleration,
        )
        best["topp"] = min(best.get("topp", np.inf), profile.solve_s)
    return best["topp"], best["constant_speed"], best["cycle_time"]


def lean_passes_ratio(plan) -> tuple[float, float, bool]:
    """(CPU time [s] of the cycle_time law on the 5,000-sample path with TOPP-RA's lean
    passes, with toppra's own passes, whether both laws have the same duration); best
    of 5 each, in turn."""
    from offline_prog.timing import time_optimal
    from offline_prog.timing.path_timing import PathLimits, time_path

    robot, motion = plan.robot, plan.cell.motion
    rates = path_rates(plan, 5000)
    limits = PathLimits.of(
        robot,
        rates.sigma[-1],
        v_process=plan.process_speed.v_m_s,
        a_max=motion.max_acceleration,
        j_max=motion.max_jerk,
    )
    lean = time_optimal.lean_toppra
    toppras = {"lean": lean, "toppra": lambda algorithm: algorithm.TOPPRA}
    best, durations = {}, {}
    try:
        for _ in range(5):
            for name, solver in toppras.items():
                time_optimal.lean_toppra = solver
                start = time.process_time()
                durations[name] = time_path(
                    rates, limits, "time_optimal", "cycle_time"
                ).law.duration
                best[name] = min(best.get(name, np.inf), time.process_time() - start)
    finally:
        time_optimal.lean_toppra = lean
    return best["lean"], best["toppra"], durations["lean"] == durations["toppra"]


def _X_IB(plan):
    from offline_prog.config.cell import transform

    return transform(plan.cell.robot.X_IB)


def fixed_turn(inputs):
    """``inputs`` with the tool's turn fixed along the path (tool.turn_smoothing_mm 0)."""
    tool = dataclasses.replace(inputs.cell.tool, turn_smoothing_mm=0.0)
    return dataclasses.replace(inputs, cell=dataclasses.replace(inputs.cell, tool=tool))


def bench_timing(cells: list[str] = ONE_SEAM_CELLS) -> None:
    print("time-optimal process law vs sin² and TOPP-RA (same process, same cells)")
    runs = []
    for name in cells:
        inputs = load_inputs(ROOT / "cells" / f"{name}.yaml", ROOT / "offline_prog" / "robots")
        runs.append((name, inputs))
        if inputs.cell.tool.turn_smoothing_mm > 0:  # for reference: the wrist takes the turns
            runs.append((f"{name} with the tool turn fixed", fixed_turn(inputs)))
    for name, inputs in runs:
        scene = build_scene(inputs)
        sin2 = plan_with(inputs, scene, time_law="sin2")
        held = plan_with(inputs, scene, time_law="time_optimal", process="constant_speed")
        fast = plan_with(inputs, scene, time_law="time_optimal", process="cycle_time")
        topp = held.joints.retiming.topp_plain_s
        topp_jerk = held.joints.retiming.topp.duration  # with the steady jerk limit
        print(f"\n{name}: path {held.path.length * 1e3:.0f} mm at {inputs.speed.v_m_s} m/s")
        print(
            f"  {'law':<28} {'cycle [s]':>9} {'/TOPP-RA':>9} {'/sin²':>7} {'held ±0.5%':>11} "
            f"{'vel use':>8} {'acc use':>8} {'jerk use':>8}"
        )
        print(f"  {'TOPP-RA (no jerk stage)':<28} {topp:9.3f}")
        print(f"  {'TOPP-RA + steady jerk limit':<28} {topp_jerk:9.3f} {topp_jerk / topp:9.3f}")
        for label, plan in (
            ("sin² (paper)", sin2),
            ("time_optimal constant_speed", held),
            ("time_optimal cycle_time", fast),
        ):
            uses = csv_limit_use(plan)
            duration = plan.trajectory.duration
            print(
                f"  {label:<28} {duration:9.3f} {duration / topp:9.3f} "
                f"{duration / sin2.trajectory.duration:7.3f} {100 * held_share(plan):10.1f}% "
                + " ".join(f"{u:8.3f}" for u in uses)
            )
        for slow in held.joints.retiming.slowdowns:
            print(
                f"    slowdown σ {slow.sigma_m[0] * 1e3:7.1f}–{slow.sigma_m[1] * 1e3:7.1f} mm, "
                f"t {slow.t_s[0]:6.2f}–{slow.t_s[1]:6.2f} s, min {slow.speed_min_m_s * 1e3:6.1f} "
                f"mm/s: {slow.constraint}" + (f" of axis {slow.joint}" if slow.joint else "")
            )
        share, room = held_where_feasible(held)
        reported = held.joints.retiming.speed_held[0]
        print(
            f"  constant_speed: held ±0.5 % on {100 * share:.1f} % of the length where the "
            f"process speed is feasible ({100 * room:.1f} % of the path; acceptance ≥ 90 %; "
            f"report.json: {100 * reported:.1f} %)"
        )
        alone, held_s, fast_s = solve_time_5000(held)
        print(
            f"  solve on a 5,000-sample path (best of 5; acceptance < 100 ms): the whole "
            f"time-optimal law {held_s * 1e3:.0f} ms (constant_speed), {fast_s * 1e3:.0f} ms "
            f"(cycle_time); TOPP-RA alone {alone * 1e3:.1f} ms"
        )
        lean_s, toppra_s, same = lean_passes_ratio(held)
        print(
            f"  cycle_time law, CPU (best of 5): TOPP-RA's lean passes {lean_s * 1e3:.0f} ms, "
            f"toppra's own {toppra_s * 1e3:.0f} ms, ratio {lean_s / toppra_s:.2f}; "
            f"same law: {'yes' if same else 'NO'}"
        )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "cells", nargs="*", metavar="CELL_STEM", help="one-seam cells of cells/ by file stem"
    )
    bench_timing(parser.parse_args().cells or ONE_SEAM_CELLS)
