"""The time law's joint jerk checked on the output samples with the exact path.

The time laws check each joint's jerk q⃛ = q‴σ̇³ + 3q″σ̇σ̈ + q′σ⃛ with q‴ the
σ-difference of the exact q″ on the joint-rate grid (``limit_use.with_jerk``,
GRID_SPACING_M apart). The path's q‴ is not smooth: it jumps where the flange path's
third derivative does (the processing path's spline knots, the fixed tool's turn at a
corner), and next to a jump it peaks within a grid step, where the difference
smooths it away. A law checked that way can exceed the jerk limit there unseen (the
seal cell with the nozzle's turn fixed and the path jerk capped at 1.5625 m/s³: the
law's check said 0.97 of the wrist's jerk limit, the exact jerk was 1.04).

``verified_timing`` evaluates the exact joint jerk on the trajectory's output
samples (those the grid's q‴ puts at SCREEN_USE of a limit or more; q‴ by a central
difference of the exact q″ over JERK_STEP_M). Where it is over a limit, the grid's q‴
around there is replaced by the envelope of the exact q‴ on a fine grid (so the law's
own check sees the peak) and the path is timed again; where every sample keeps its
limits nothing changes.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.arrays import interp_rows, row_max, true_runs
from offline_prog.constants import TimeLaw
from offline_prog.robot.model import RobotModel
from offline_prog.timing.joint_timing import JointRates
from offline_prog.timing.limit_use import joint_use, with_jerk
from offline_prog.timing.trajectory import sample_times

JERK_STEP_M = 1e-5  # central-difference step of the exact q″ [m]
FINE_PER_STEP = 10  # exact q‴ samples per grid step where an excess is found
REACH_M = 2e-3  # the envelope covers this much σ either side of an excess [m]
MAX_ROUNDS = 4
# Samples whose jerk by the grid's q‴ is below this share of the limit are not checked
# with the exact path: the grid's difference smooths a peak (at most a jump of q‴
# inside a grid step, which it halves), it does not cut it to a third.
SCREEN_USE = 0.3


def exact_jerk_rates(path, robot: RobotModel, sigma: np.ndarray, q_grid, grid) -> np.ndarray:
    """(N, 6) q‴ [rad/m³] at σ (N,) on the controller's axes: a central difference of
    the exact q″ (one-sided at the path's ends).

    Args:
        path: the joint path (``BranchPath`` or ``DrakeIkPath``: ``rates(σ, q_near)``).
        q_grid, grid: (G, 6) URDF q on the σ grid (G,), to pick the branch's 2π turn.
    """
    lo = np.clip(sigma - JERK_STEP_M, grid[0], grid[-1])
    hi = np.clip(sigma + JERK_STEP_M, grid[0], grid[-1])
    ends = np.concatenate([lo, hi])
    (q_near,) = interp_rows(ends, grid, q_grid)
    ddq = robot.controller_joints(path.rates(ends, q_near).ddq)
    return (ddq[len(sigma) :] - ddq[: len(sigma)]) / (hi - lo)[:, None]


def jerk_use(law, t: np.ndarray, rates: JointRates, dddq: np.ndarray, jerk_max) -> np.ndarray:
    """(N, 6) |q⃛| / q⃛_max at times t, with the exact q‴ dddq (N, 6) at the law's σ(t)
    and q′, q″ from ``rates`` at the same σ (exact: ``rates`` is evaluated there)."""
    _, sd, sdd, sddd = (np.asarray(x)[:, None] for x in law(t))
    jerk = dddq * sd**3 + 3.0 * rates.ddq * sd * sdd + rates.dq * sddd
    return np.abs(jerk) / jerk_max


def _signed_peak(values: np.ndarray, axis: int = 0) -> np.ndarray:
    """The entries of largest magnitude along ``axis``, with their sign."""
    index = np.expand_dims(np.argmax(np.abs(values), axis=axis), axis)
    return np.take_along_axis(values, index, axis=axis).squeeze(axis)


def envelope(dddq: np.ndarray, sigma: np.ndarray, fine: np.ndarray, exact: np.ndarray):
    """(G, 6) ``dddq`` on the grid ``sigma`` raised, where ``fine`` (M,) covers it, to
    the exact q‴ ``exact`` (M, 6) of largest magnitude on either grid step next to
    each point: linear interpolation between the points then never falls below the
    exact q‴ there (where q‴ keeps its sign over the two steps)."""
    out = dddq.copy()
    step = np.searchsorted(sigma, fine, side="right") - 1  # fine point ∈ step [i, i + 1)
    for i in np.unique(step):
        if i < 0 or i >= len(sigma) - 1:
            continue
        peak = _signed_peak(exact[step == i])
        for k in (i, i + 1):
            out[k] = _signed_peak(np.stack([out[k], peak]))
    return out


def verified_timing(time, rates: JointRates, path, robot: RobotModel, q_grid, *, rate_hz):
    """``time(rates)`` (a PathTiming), its jerk checked on the output samples at
    ``rate_hz`` with the exact path, re-timed where it was over (module doc).

    Args:
        time: JointRates ↦ PathTiming (``path_timing.time_path`` with the path's limits).
        rates: the controller's joint rates on the grid (GRID_SPACING_M).
        path, q_grid: the joint path and its URDF q on the grid (``exact_jerk_rates``).

    Returns:
        (PathTiming, the JointRates it was timed with). The PathTiming is not
        feasible, with the exact worst use, if the jerk is still over after
        MAX_ROUNDS.
    """
    grid, jerk_max = rates.sigma, robot.jerk_limits
    retiming = time(rates)
    if retiming.law_kind is not TimeLaw.TIME_OPTIMAL:  # sin2 keeps no jerk limit
        return retiming, rates
    for round_ in range(MAX_ROUNDS + 1):
        if not retiming.feasible:
            return retiming, rates
        t = sample_times(retiming.law.duration, rate_hz)
        # The exact path only where the grid's q‴ puts the jerk above SCREEN_USE.
        limits = (robot.qd_max, robot.qdd_max, jerk_max)
        model = joint_use(rates, with_jerk(rates), retiming.law, t, limits)
        t = t[row_max(model["jerk"]) >= SCREEN_USE]
        if len(t) == 0:
            return retiming, rates
        sigma = retiming.law(t)[0]
        (q_near,) = interp_rows(sigma, grid, q_grid)
        exact = path.rates(sigma, q_near)
        exact = JointRates(
            sigma, *(robot.controller_joints(v) for v in (exact.q, exact.dq, exact.ddq))
        )
        dddq = exact_jerk_rates(path, robot, sigma, q_grid, grid)
        use = jerk_use(retiming.law, t, exact, dddq, jerk_max)
        over = row_max(use) > 1.0
        if not over.any():
            return retiming, rates
        if round_ == MAX_ROUNDS:
            break
        dddq = with_jerk(rates)
        for a, b in true_runs(over):
            lo, hi = sigma[a] - REACH_M, sigma[b - 1] + REACH_M
            count = FINE_PER_STEP * (int(np.ceil((hi - lo) / (grid[1] - grid[0]))) + 1)
            fine = np.clip(np.linspace(lo, hi, count), grid[0], grid[-1])
            dddq = envelope(dddq, grid, fine, exact_jerk_rates(path, robot, fine, q_grid, grid))
        rates = dataclasses.replace(rates, dddq=dddq)
        retiming = time(rates)
    k, j = np.unravel_index(np.argmax(use), use.shape)
    worst = (int(j), float(sigma[k]), float(use[k, j]))
    return dataclasses.replace(retiming, feasible=False, worst=worst), rates
