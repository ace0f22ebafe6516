"""TOPP-RA's two passes with toppra's own solver, step for step, in a lean loop.

toppra's ``TOPPRA.compute_parameterization`` spends most of a solve around its solver:
each grid step of the backward pass (the controllable sets) and of the forward pass
builds small arrays, tests ``None in K_next`` element by element on a numpy array and
asks for debug logging (on this machine 2.5× the time of the seidel solver calls
themselves on the job's laws). :func:`lean_toppra` is toppra's class with these two
passes written as plain loops over Python floats that call the same solver
(``seidelWrapper.solve_stagewise_optim``) with the same arguments in the same order,
and do the same float64 arithmetic: the profile is the same, bit for bit
(tests/timing/test_toppra_passes.py checks it against toppra's own passes).

What is left out: the auxiliary variables of the forward pass (``v_vec``, returned as
None; a joint-limit-only problem has none) and the log lines on failure.
"""

from __future__ import annotations

import functools
import math

import numpy as np


@functools.cache
def lean_toppra(algorithm):
    """``algorithm.TOPPRA`` (``algorithm``: the module toppra.algorithm, as
    ``time_optimal`` loads it) with lean backward and forward passes (module doc)."""
    from toppra.algorithm.algorithm import ParameterizationReturnCode
    from toppra.constants import MAX_TRIES, SMALL, TINY
    from toppra.exceptions import BadInputVelocities

    class LeanTOPPRA(algorithm.TOPPRA):
        """TOPPRA whose passes run as plain loops (module doc)."""

        def compute_controllable_sets(self, sdmin: float, sdmax: float) -> np.ndarray:
            """(N + 1, 2) the controllable sets of squared path speeds, as toppra's."""
            assert sdmin <= sdmax and sdmin >= 0
            n = self._N
            K = np.zeros((n + 1, 2))
            K[n] = [sdmin**2, sdmax**2]
            solve = self.solver_wrapper.solve_stagewise_optim
            upper = np.array([1e-9, -1.0])  # toppra's g_upper for two variables
            lower = -upper
            low, high = float(K[n, 0]), float(K[n, 1])
            self.solver_wrapper.setup_solver()
            for i in range(n - 1, -1, -1):
                after = (low, high)  # K[i + 1]
                high = float(solve(i, None, upper, math.nan, math.nan, *after)[1])
                low = float(solve(i, None, lower, math.nan, math.nan, *after)[1])
                low = 0.0 if low < 0 else low
                K[i] = low, high
                if math.isnan(low) or math.isnan(high):
                    return K  # as toppra: the solver is left open
            self.solver_wrapper.close_solver()
            return K

        def compute_parameterization(self, sd_start, sd_end, return_data=False):
            """(σ̈ (N,), σ̇ (N + 1,), None, K if ``return_data``): toppra's answer."""
            if sd_end < 0 or sd_start < 0:
                raise BadInputVelocities(
                    f"Negative path velocities: path velocities must be positive: "
                    f"({sd_start}, {sd_end})"
                )
            data = self._problem_data
            K = self.compute_controllable_sets(sd_end, sd_end)
            x_start = sd_start**2
            if not np.isnan(K).any():
                data.K = K
            if np.isnan(K).any() or x_start + SMALL < K[0, 0] or K[0, 1] + SMALL < x_start:
                data.return_code = ParameterizationReturnCode.FailUncontrollable
                return (None, None, None, K) if return_data else (None, None, None)
            wrapper = self.solver_wrapper
            n, solve = self._N, wrapper.solve_stagewise_optim
            deltas = wrapper.get_deltas().tolist()
            low, high = K[:, 0].tolist(), K[:, 1].tolist()
            xs, us = np.zeros(n + 1), np.zeros(n)
            x, tries, i = float(x_start), 0, 0
            xs[0] = x
            wrapper.setup_solver()
            while i < n:
                u = math.nan
                if not math.isnan(x):
                    g = np.array([-2 * deltas[i], -1.0])
                    u = float(solve(i, None, g, x, x, low[i + 1], high[i + 1])[0])
                if math.isnan(u):  # toppra: retry a little slower, MAX_TRIES times
                    if tries >= MAX_TRIES:
                        xs[i + 1 :] = np.nan
                        break
                    x = max(x - TINY, 0.999 * x)
                    xs[i] = x
                    tries += 1
                    continue
                tries, us[i] = 0, u
                x_next = x + 2 * deltas[i] * u
                x_next = max(x_next - TINY, 0.9999 * x_next)
                x = min(high[i + 1], max(low[i + 1], x_next))
                xs[i + 1] = x
                i += 1
            wrapper.close_solver()
            sd = np.sqrt(xs)
            data.sd_vec, data.sdd_vec = sd, np.copy(us)
            failed = np.isnan(sd).any()
            data.return_code = (
                ParameterizationReturnCode.ErrUnknown if failed else ParameterizationReturnCode.Ok
            )
            return (np.copy(us), sd, None, K) if return_data else (np.copy(us), sd, None)

    return LeanTOPPRA
