"""The value each FANUC ``L`` motion holds on the flow output, through the dispenser.

An ``AO[n]=value`` statement holds one value for a whole motion, and no motion is
shorter than 0.5 mm (``export.merge.MIN_MOTION_M``), so where the tool speeds up from or
slows down to rest one motion spans a flow change of several per cent. The dispenser
answers its command through a first-order lag of time constant ``lag_s``
(``process.lag``), which smooths those steps. A live motion that lasts at least the lag
holds the middle of the plan's flow on it (the lag does not smooth within it); a
shorter one holds the value whose answer follows the dispenser's answer to the plan's
flow (the plan's ``ao`` column, stepping at its own event times): in run order, the
least-squares fit of the two answers over the motion's planned samples and the lag's
time after its start, from where the previous motions left the dispenser, weighted by
path length and relative to the flow there (the bead's cross-section is the flow over
the speed, so a relative flow error is the bead's). Values are clipped to the flow's
[min, max]; an idle motion holds ``idle``. Without a lag every motion holds the middle.
"""

from __future__ import annotations

import numpy as np

from offline_prog.process.lag import first_order_response

EDGE_S = 1e-9  # the plan's flow steps at its edges within this time [s]
RELATIVE_FLOOR = 0.01  # the weights' flow floor: this share of the plan's largest flow


def flow_values(
    samples, points: list[int], live: list[bool], io, flow_at, *, windows
) -> list[float]:
    """The flow value [V] each motion between consecutive points holds.

    Args:
        samples: the seam's planned samples (``fanuc_io.Samples``: t, path_m).
        points: sorted sample indices of the motions' ends (the first: where the robot
            is when the chain starts).
        live: (len(points) - 1,) whether the flow is live on each motion.
        io: the process I/O (idle, min, max, lag_s).
        flow_at: the plan's live flow [V] at job times (n,) [s].
        windows: the plan's live flow's [(t_on, t_off), ...] job times [s] (its analog
            events'; t_off inf: live to the end).

    Returns:
        One value per motion [V].
    """
    t, sigma = samples.t, samples.path_m
    state = np.zeros(len(t), bool)
    for (a, b), on in zip(zip(points, points[1:], strict=False), live, strict=True):
        state[a + 1 : b + 1] = on
    command = np.where(state, flow_at(t), io.idle)
    answer = _plan_answer(t, io, flow_at, windows)
    floor = RELATIVE_FLOOR * max(float(np.abs(command).max()), 1e-9)
    tau = io.lag_s
    held, y = [], io.idle  # the dispenser's answer at the motion's start
    for (a, b), on in zip(zip(points, points[1:], strict=False), live, strict=True):
        value = io.idle
        if on and t[b] - t[a] >= tau:  # the lag does not smooth within it: the plan's
            span = flow_at(t[a : b + 1])
            value = float(span.max() + span.min()) / 2
        elif on and b > a:
            k = _horizon(t, state, a, b, tau)
            # The error at k: c·gain − aim (on the motion: the held answer against the
            # plan's; past its end, the plan's flow follows, so the error left at b
            # decays with the lag).
            at = np.minimum(k, b)
            decay = np.exp(-(t[at] - t[a]) / tau) if tau > 0 else np.zeros(len(k))
            after = np.exp(-(t[k] - t[at]) / tau) if tau > 0 else (k <= b).astype(float)
            gain = (1.0 - decay) * after
            aim = (answer[at] - y * decay) * after
            weight = (sigma[k] - sigma[k - 1]) / np.maximum(np.abs(answer[k]), floor) ** 2
            norm = float((weight * gain**2).sum())
            if norm > 0:
                value = float((weight * gain * aim).sum() / norm)
            else:  # no path on the motion: the plan's flow at its end
                value = float(command[b])
            value = float(np.clip(value, io.min, io.max))
        held.append(value)
        if b > a:
            y = value + (y - value) * (np.exp(-(t[b] - t[a]) / tau) if tau > 0 else 0.0)
    return held


def _plan_answer(t: np.ndarray, io, flow_at, windows) -> np.ndarray:
    """(N,) the dispenser's answer at the sample times t (N,) [s] to the plan's flow:
    ``flow_at`` within the live windows [(t_on, t_off) [s], ...], idle outside them,
    stepping at their edges (the plan's own times, not the motions')."""
    edges = np.array([e for w in windows for e in w if t[0] < e < t[-1]])
    grid = np.unique(np.concatenate([t, edges, edges - EDGE_S]))
    on = np.zeros(len(grid), bool)
    for start, stop in windows:
        on |= (grid >= start) & (grid < stop)
    command = np.where(on, flow_at(grid), io.idle)
    return np.interp(t, grid, first_order_response(grid, command, io.lag_s, y0=io.idle))


def _horizon(t: np.ndarray, state: np.ndarray, a: int, b: int, tau: float) -> np.ndarray:
    """The samples a live motion a → b is fitted over: its own, and on while the flow
    stays live until ``tau`` after its start (a motion much shorter than the lag would
    else steer the dispenser's answer by a large step it cannot hold)."""
    stop = b
    while stop + 1 < len(t) and state[stop + 1] and t[stop + 1] <= t[a] + tau:
        stop += 1
    return np.arange(a + 1, stop + 1)
