"""Time-optimal path parameterization under the joint limits (the paper's outlook).

TOPP-RA (Pham & Pham 2018, the ``toppra`` package) finds the fastest σ̇(σ) along
the joint path q(σ) from the path IK, rest to rest, subject to

    |q′_k σ̇| ≤ q̇_max,k                      joint velocity,
    |q″_k σ̇² + q′_k σ̈| ≤ q̈_max,k             joint acceleration,
    σ̇ ≤ v_cap                                the process speed (TCP or flange),
    |σ̈| ≤ a_path                             the path acceleration limit.

The last two enter as a seventh, virtual joint q_7 = σ (q′_7 = 1, q″_7 = 0) with
velocity limit v_cap and acceleration limit a_path. q′ and q″ are exact (the Jacobian,
``robot.jacobian``). The result has piecewise-constant σ̈, so its acceleration
jumps: ``jerk_stage`` turns it into a jerk-limited law. An expected failure is a
return value with a reason (``ToppProfile.ok``), as in toppra itself.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
import sys
import time
import types

import numpy as np

from offline_prog.timing.joint_timing import JointRates
from offline_prog.timing.toppra_passes import lean_toppra

# TOPP-RA's grid: the joint rates' grid thinned to about this spacing [m], within
# these many points. The solve time grows linearly with them (~18 µs a point here);
# 1.5 mm costs the demo laws ≤ 0.1 % of cycle time against 0.5-1.2 mm (1,000 points).
TOPP_GRID_SPACING_M = 1.5e-3
TOPP_MIN_GRID_POINTS = 300
TOPP_GRID_POINTS = 1000
RAMP_POINTS = 16
START_TOL = 1e-6  # resolve_locally: a local solve starts at the old speed within this share


@dataclasses.dataclass(frozen=True)
class ToppProfile:
    """TOPP-RA's answer on its grid.

    Attributes:
        sigma: (G,) grid [m].
        speed: (G,) time-optimal σ̇ [m/s] (0 at both ends).
        duration: rest-to-rest time of that profile [s] (no jerk limit).
        solve_s: wall time of the solve [s].
        ok: TOPP-RA found a parameterization; reason: why not (else "").
        failed_at_m: where it failed [m]: the grid point whose controllable set is
            empty or where the forward pass stopped (NaN when ok).
    """

    sigma: np.ndarray
    speed: np.ndarray
    duration: float
    solve_s: float
    ok: bool
    reason: str = ""
    failed_at_m: float = float("nan")


class _GridPath:
    """toppra's geometric-path interface over precomputed exact values on a grid
    (TOPP-RA evaluates the path at its grid points only)."""

    def __init__(self, sigma, q, dq, ddq):
        self.sigma, self._values = sigma, (q, dq, ddq)

    def __call__(self, ss, order=0):
        values = self._values[order]
        if len(ss) == len(self.sigma) and np.array_equal(ss, self.sigma):  # the grid
            return values
        index = np.clip(np.searchsorted(self.sigma, ss), 0, len(self.sigma) - 1)
        if np.allclose(self.sigma[index], ss, rtol=0, atol=1e-12):
            return values[index]
        return np.column_stack(
            [np.interp(ss, self.sigma, values[:, k]) for k in range(values.shape[1])]
        )

    @property
    def dof(self) -> int:
        return self._values[0].shape[1]

    @property
    def path_interval(self) -> np.ndarray:
        return np.array([self.sigma[0], self.sigma[-1]])

    @property
    def waypoints(self):
        return None


@dataclasses.dataclass(frozen=True)
class _JointGrid:
    """What every TOPP-RA solve over the same joint rates and limits shares (the
    filtered stage's rounds differ in their speed and acceleration curves and spans
    only): the grid (``topp_grid``: indices ``keep`` (G,), ``sigma`` (G,) [m]), the
    path's values on it with σ as the seventh joint (q, q′, q″, each (G, 7)), the
    limits (7,) as ``_joint_constraints`` takes them, and the joint velocity
    constraint's bounds on σ̇² (G, 2): toppra's own numbers, row by row, so a span's
    rows are its solve's."""

    rates: JointRates  # held: the memo compares it by identity
    key: tuple
    keep: np.ndarray
    sigma: np.ndarray
    values: tuple[np.ndarray, np.ndarray, np.ndarray]
    limits: tuple[tuple[float, ...], tuple[float, ...]]
    velocity: np.ndarray


_LAST_GRID: list[_JointGrid] = []  # the last problem's (one process's; a solve at a time)


def _joint_grid(rates: JointRates, qd_max, qdd_max, v_cap, a_path, grid_points) -> _JointGrid:
    """The :class:`_JointGrid` of these rates and limits: made once for the solves that
    follow one another on them (the last one is kept)."""
    limits = (tuple(np.append(qd_max, v_cap)), tuple(np.append(qdd_max, a_path)))
    key = (*limits, grid_points)
    if _LAST_GRID and _LAST_GRID[0].rates is rates and _LAST_GRID[0].key == key:
        return _LAST_GRID[0]
    keep = topp_grid(rates.sigma, v_cap**2 / (2.0 * a_path), grid_points)
    sigma = rates.sigma[keep]
    ones = np.ones((len(sigma), 1))
    values = (
        np.hstack([rates.q[keep], sigma[:, None]]),
        np.hstack([rates.dq[keep], ones]),
        np.hstack([rates.ddq[keep], 0 * ones]),
    )
    velocity_limit = _joint_constraints(*limits)[0]
    xbound = velocity_limit.compute_constraint_params(_GridPath(sigma, *values), sigma)[-1]
    grid = _JointGrid(rates, key, keep, sigma, values, limits, xbound)
    _LAST_GRID[:] = [grid]
    return grid


def _speed_curve(v_max: np.ndarray, dof: int, a_max: np.ndarray | None = None):
    """A toppra constraint σ̇ ≤ v_max (G,) at the grid points, and |σ̈| ≤ a_max (G,)
    on the step after each if given, vectorised (toppra's
    JointVelocityConstraintVarying calls Python once per grid point)."""
    xbound = np.column_stack([np.zeros(len(v_max)), v_max**2])
    ubound = None if a_max is None else np.column_stack([-a_max, a_max])
    return _given(xbound, ubound, dof=dof)


def _given(xbound: np.ndarray, ubound: np.ndarray | None = None, *, dof: int):
    """A toppra constraint with the given bounds on σ̇² (G, 2) and on σ̈ (G, 2) or
    None, at the solve's grid points."""
    return _given_class()(xbound, ubound, dof)


@functools.cache
def _given_class():
    """The class of :func:`_given`'s constraints (made once: toppra loads on first use)."""
    _toppra_algorithm()  # toppra without matplotlib
    from toppra.constraint import LinearConstraint

    class Given(LinearConstraint):
        def __init__(self, xbound, ubound, dof):
            super().__init__()
            self.xbound, self.ubound, self.dof = xbound, ubound, dof

        def compute_constraint_params(self, path, gridpoints):
            return None, None, None, None, None, self.ubound, self.xbound

    return Given


def topp_grid(sigma: np.ndarray, ramp: float, most: int) -> np.ndarray:
    """Indices into ``sigma`` (G,) of TOPP-RA's grid: TOPP_GRID_SPACING_M apart (at least
    TOPP_MIN_GRID_POINTS, at most ``most`` of these), plus RAMP_POINTS spaced quadratically over
    the first and last ``ramp`` metres (the rest-to-rest ramps at the path
    acceleration, σ̇ ∝ √σ: else a slow process's ramp takes a whole grid step).
    """
    last = len(sigma) - 1
    count = min(
        max(int(np.ceil(sigma[-1] / TOPP_GRID_SPACING_M)) + 1, TOPP_MIN_GRID_POINTS),
        most,
        len(sigma),
    )
    ends = min(ramp, 0.5 * sigma[-1]) * np.linspace(0.0, 1.0, RAMP_POINTS) ** 2
    near = np.concatenate(
        [
            np.searchsorted(sigma, ends, "left"),  # nearest the ends
            np.searchsorted(sigma, sigma[-1] - ends, "right") - 1,
        ]
    )
    uniform = np.linspace(0, last, count).round().astype(int)
    return np.unique(np.concatenate([uniform, np.clip(near, 0, last)]))


class _Deferred(types.ModuleType):
    """Stands for a module while toppra loads; the real one is imported on first use."""

    def __getattr__(self, name: str):
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(importlib.import_module(self.__name__), name)


def _toppra_algorithm():
    """toppra.algorithm, imported here only (a plan without the time-optimal law does
    without it) and without matplotlib: toppra imports matplotlib.pyplot at load for its
    plot helpers only, 0.35 s of a plan's start. While toppra loads, matplotlib and
    matplotlib.pyplot are stand-ins that import the real module if toppra ever plots.

    Every solve's algorithm asks ``toppra.solverwrapper.available_solvers`` which
    optional solvers are installed, a search of the whole import path (~0.1 ms, 340
    times in a placement candidate): the answer is kept after the first."""
    if "toppra.algorithm" not in sys.modules:
        deferred = {
            name: _Deferred(name)
            for name in ("matplotlib", "matplotlib.pyplot")
            if name not in sys.modules
        }
        if "matplotlib" in deferred and "matplotlib.pyplot" in deferred:
            deferred["matplotlib"].pyplot = deferred["matplotlib.pyplot"]
        sys.modules.update(deferred)
        try:
            importlib.import_module("toppra.algorithm")
        finally:
            for name in deferred:
                del sys.modules[name]
        solvers = sys.modules["toppra.solverwrapper"]
        solvers.available_solvers = functools.cache(solvers.available_solvers)
    return sys.modules["toppra.algorithm"]


@functools.lru_cache(maxsize=32)
def _joint_constraints(v: tuple[float, ...], a: tuple[float, ...]):
    """toppra's joint velocity and acceleration constraints for limits v, a (7,),
    made once per limits: their constructors format every limit into a string (~4 ms
    a solve on this machine, a fifth of it)."""
    _toppra_algorithm()  # toppra without matplotlib
    import toppra.constraint as constraint

    v, a = np.array(v), np.array(a)
    return (
        constraint.JointVelocityConstraint(np.column_stack([-v, v])),
        constraint.JointAccelerationConstraint(
            np.column_stack([-a, a]),
            discretization_scheme=constraint.DiscretizationType.Interpolation,
        ),
    )


def profile_duration(sigma: np.ndarray, speed: np.ndarray) -> float:
    """Time to run the profile [s]: constant σ̈ between grid points, so each step
    takes 2 Δσ / (σ̇_i + σ̇_i+1)."""
    mean = 0.5 * (speed[1:] + speed[:-1])
    return float(np.sum(np.diff(sigma) / np.maximum(mean, 1e-300)))


def topp_profile(
    rates: JointRates,
    *,
    qd_max: np.ndarray,
    qdd_max: np.ndarray,
    v_cap: float,
    a_path: float,
    v_steady: np.ndarray | None = None,
    a_curve: np.ndarray | None = None,
    grid_points: int = TOPP_GRID_POINTS,
    span: tuple[int, int] | None = None,
    ends: tuple[float, float] = (0.0, 0.0),
) -> ToppProfile:
    """The time-optimal σ̇(σ) under the module's constraints (see the module doc).

    Args:
        rates: q, q′, q″ on a σ grid over [0, length], in the controller's axes.
        qd_max, qdd_max: (6,) joint velocity [rad/s] and acceleration [rad/s²] limits.
        v_cap: the process speed cap on σ̇ [m/s].
        a_path: the path acceleration limit on |σ̈| [m/s²].
        v_steady: (G,) optional further cap on σ̇ on the rates' grid [m/s] (the jerk
            stage's steady-speed jerk limit, |q‴σ̇³| ≤ q⃛_max: TOPP-RA knows no jerk).
        a_curve: (G,) optional further cap on |σ̈| on the rates' grid [m/s²] (the
            filtered stage lowers it where its window's speed changes are too hard).
        grid_points: most grid points of the solve (TOPP_GRID_SPACING_M apart, at least
            TOPP_MIN_GRID_POINTS).
        span: (i, j): solve on the grid points i..j only (of the whole path's grid, the
            returned ``sigma``), from σ̇ = ends[0] at i to σ̇ = ends[1] at j [m/s]; the
            whole path, rest to rest, if None (``resolve_locally``).
    """
    grid = _joint_grid(rates, qd_max, qdd_max, v_cap, a_path, grid_points)
    lo, hi = (0, len(grid.keep) - 1) if span is None else span
    keep, sigma = grid.keep[lo : hi + 1], grid.sigma[lo : hi + 1]
    path = _GridPath(sigma, *(values[lo : hi + 1] for values in grid.values))
    constraints = [
        _given(grid.velocity[lo : hi + 1], dof=path.dof),
        _joint_constraints(*grid.limits)[1],
    ]
    if v_steady is not None or a_curve is not None:
        v_curve = np.full(len(sigma), v_cap) if v_steady is None else v_steady[keep]
        a_step = None if a_curve is None else np.minimum(a_curve[keep], a_path)
        constraints.append(_speed_curve(np.minimum(v_curve, v_cap), path.dof, a_step))
    start = time.perf_counter()
    toppra = lean_toppra(_toppra_algorithm())
    solver = toppra(constraints, path, gridpoints=sigma, solver_wrapper="seidel")
    _, sd, _, K = solver.compute_parameterization(*ends, return_data=True)
    solve_s = time.perf_counter() - start
    code = solver.problem_data.return_code
    if sd is None or str(code.name) != "Ok":
        at = _failed_at(sigma, sd, K)
        return ToppProfile(
            sigma,
            np.zeros_like(sigma),
            np.inf,
            solve_s,
            False,
            str(getattr(code, "value", code)),
            at,
        )
    speed = np.clip(np.asarray(sd, dtype=float), 0.0, v_cap)
    return ToppProfile(sigma, speed, profile_duration(sigma, speed), solve_s, True)


def _failed_at(sigma: np.ndarray, sd, K) -> float:
    """Where a TOPP-RA solve failed [m]: the last grid point whose controllable set is
    empty (the backward pass ends there), else the first without a forward speed."""
    if K is not None and np.isnan(K).any():
        return float(sigma[int(np.flatnonzero(np.isnan(K).any(axis=1))[-1])])
    if sd is not None and np.isnan(sd).any():
        return float(sigma[int(np.argmax(np.isnan(sd)))])
    return float(sigma[0])


def resolve_locally(
    profile: ToppProfile, lowered: list[tuple[float, float]], solve, reach: float
) -> ToppProfile:
    """TOPP-RA again after its limit curves were lowered on the σ stretches
    ``lowered``, re-solving only around them; exact.

    The new profile is nowhere above the old one (its limits are tighter). Where a
    stretch widened by ``reach`` each way can be solved from the old profile's speed
    at its start to the old speed at its end, the old profile outside it and that
    solution inside make a feasible profile, and no feasible profile is higher
    (TOPP-RA's profile is the highest): it is the new optimum. Where not, the stretch
    widens (×2) until it can, or becomes the whole path.

    Args:
        profile: TOPP-RA's answer before the curves were lowered (``ok``).
        lowered: [(σ_start, σ_end), ...] where a limit curve was lowered [m].
        solve: (span, ends) ↦ ToppProfile: ``topp_profile`` with the new curves.
        reach: the first widening [m] (the shortest stop from the process speed,
            v²/2a: a longer one needs a wider stretch, which the widening finds).
    """
    sigma, speed = profile.sigma, profile.speed.copy()
    last, solve_s = len(sigma) - 1, profile.solve_s
    lo = np.searchsorted(sigma, [a - reach for a, _ in lowered], "right") - 1
    hi = np.searchsorted(sigma, [b + reach for _, b in lowered])
    spans = sorted(zip(lo.tolist(), hi.tolist(), strict=True))
    merged: list[list[int]] = []
    for i, j in spans:
        i, j = max(i, 0), min(j, last)
        if merged and i <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], j)
        else:
            merged.append([i, j])
    for i, j in merged:
        while True:
            part = solve((i, j), (float(speed[i]), float(speed[j])))
            solve_s += part.solve_s
            # toppra may start a little below the speed asked (its forward pass lowers
            # σ̇₀² on a numerical failure): then the step into i would be too hard.
            kept = part.ok and abs(part.speed[0] - speed[i]) <= START_TOL * max(speed[i], 1e-3)
            if kept:
                speed[i : j + 1] = np.minimum(part.speed, speed[i : j + 1])
                break
            if i == 0 and j == last:
                return dataclasses.replace(part, solve_s=solve_s)
            width = j - i
            i, j = max(i - width // 2 - 1, 0), min(j + width // 2 + 1, last)
    return ToppProfile(sigma, speed, profile_duration(sigma, speed), solve_s, True)
