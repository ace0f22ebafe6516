"""A program's flow and switches, read from its text (``program_readers``), placed on
the plan's time and replayed through the process model: what the part gets from the
program as the controller runs it at the plan's speed.

Placing: each motion's end and each switch's point (the tool's point on the part) is
found on the plan's rows of the seams' runs (approach, seam, retract: the tool's point
in P, a polyline), walking forward in run order, so a closed seam's start and its
overlap past it are told apart. Its fractional row gives the plan's time and path
position there.

The acceptance figures (issue 37): of the gun-on length, the share within ±5 % of the
target, the worst gun-on row, the gun-on rows at a standstill; the switches' error
against the plan's set positions [m].
"""

from __future__ import annotations

import numpy as np
from program_readers import (
    KRL_FLOW_LAW,
    Point,
    Switch,
    krl_items,
    rapid_items,
    urscript_digital,
    urscript_stream,
)

from offline_prog.process.registry import process_model

BAND = 0.05  # ±5 % of the target
WORST_ALLOWED = 0.20  # no gun-on row beyond ±20 %
PLACE_TOL_M = 1e-3  # a program's point is on the plan's tool path within this
STANDSTILL = 1e-3  # a gun-on row slower than this share of the process speed stands


def gun_on_rows(job) -> np.ndarray:
    """(N,) where the output is on: the valve open, else the digital output, else the
    seams' own rows (a process without a switched output)."""
    io = job.io
    if io.valve is not None:
        return io.valve.astype(bool)
    if io.digital is not None:
        return io.digital.astype(bool)
    on = np.zeros(len(job.samples.t), dtype=bool)
    for segment in job.samples.segments:
        if segment.kind == "process":
            on[segment.start : segment.stop] = True
    return on


def acceptance(job, ratio: np.ndarray, seam: str | None = None) -> dict:
    """The figures of the quality ``ratio`` (N,) per plan row (quality / target − 1):
    ``share`` of the gun-on length within ±5 %, ``worst`` |ratio| on a gun-on row
    (and its ``worst_row``), ``standstill`` gun-on rows where the tool stands; of the
    whole job or of one ``seam``'s run (approach, seam, retract)."""
    on = gun_on_rows(job)
    if seam is not None:
        mine = np.zeros(len(on), bool)
        for g in job.samples.segments:
            if g.kind != "link" and g.seam == seam:
                mine[g.start : g.stop] = True
        on &= mine
    w = job.tcp_speed * np.gradient(job.samples.t)  # the path length each row stands for
    finite = on & np.isfinite(ratio)
    ok = finite & (np.abs(ratio) <= BAND)
    worst = int(np.argmax(np.where(finite, np.abs(ratio), -1.0)))
    top = max(job.tcp_speed[on].max(), 1e-9) if on.any() else 1.0
    return {
        "share": float((w * ok).sum() / max((w * on).sum(), 1e-30)),
        "worst": float(abs(ratio[worst])) if finite.any() else float("nan"),
        "worst_row": worst,
        "standstill": int(np.count_nonzero(on & (job.tcp_speed < STANDSTILL * top))),
    }


def replayed(job, t: np.ndarray, value: np.ndarray) -> np.ndarray:
    """(K,) the model's quality (the report's unit) on the output's ``value`` (K,) at
    times ``t`` (K,) [s], at the plan's speed there."""
    model = process_model(job.cell.process)
    v = np.interp(t, job.samples.t, job.tcp_speed)
    return model.predict(t, v, value) * model.unit_scale


def ratio_to_target(job, quality: np.ndarray) -> np.ndarray:
    """quality (report's unit) / the model's target − 1."""
    model = process_model(job.cell.process)
    return quality / (model.target * model.unit_scale) - 1.0


# --- placing the program's points on the plan's rows ---------------------------------------


def fractional_row(p_rows: np.ndarray, p: np.ndarray, i: int | None = None) -> float:
    """The row position (a float index into p_rows (N, 3)) of the point p (3,) on the
    polyline of the rows, next to vertex i (None: the nearest)."""
    if i is None:
        i = int(np.argmin(np.linalg.norm(p_rows - p, axis=1)))
    best = (np.inf, float(i))
    for a in (i - 1, i):
        if 0 <= a < len(p_rows) - 1:
            d = p_rows[a + 1] - p_rows[a]
            u = float(np.clip(np.dot(p - p_rows[a], d) / max(np.dot(d, d), 1e-30), 0.0, 1.0))
            best = min(best, (np.linalg.norm(p_rows[a] + u * d - p), a + u))
    return best[1]


def place(data, items: list[Point | Switch]) -> list[tuple[Switch, float]]:
    """[(switch, its fractional row in the plan's rows ``data.job``)], in run order:
    a joint move's end is a seam's approach start (or a link's waypoint: not on the
    seams' runs), each cartesian motion's end the first stretch of the seams' runs'
    rows within PLACE_TOL_M after the last one's, each switch on its motion's rows."""
    rows = data.job
    p_rows = rows.X_PT[:, :3, 3]
    run = np.zeros(len(rows.t), bool)
    for g in data.segments:
        if g.kind != "link":
            run[g.start : g.stop + 1] = True
    starts = np.array([g.start for g in data.segments if g.kind == "approach"])
    here, end, placed = 0, 0, []
    for item in items:
        if isinstance(item, Switch):
            window = slice(here, end + 2)
            i = here + int(np.argmin(np.linalg.norm(p_rows[window] - item.p_PT, axis=1)))
            placed.append((item, fractional_row(p_rows, item.p_PT, i)))
        elif item.joint:
            ahead = starts[starts >= end]
            gap = np.linalg.norm(p_rows[ahead] - item.p_PT, axis=1)
            if len(ahead) and gap.min() < PLACE_TOL_M:
                here = end = int(ahead[np.argmin(gap)])
        else:
            gap = np.where(run[end:], np.linalg.norm(p_rows[end:] - item.p_PT, axis=1), np.inf)
            near = np.flatnonzero(gap < PLACE_TOL_M)
            assert len(near), "a cartesian motion's end off the plan's tool path"
            stretch = near[: np.argmax(np.append(np.diff(near) > 1, True)) + 1]
            here, end = end, end + int(stretch[np.argmin(gap[stretch])])
    return placed


def at_rows(values: np.ndarray, fractional: float) -> float:
    """A row column's value at a fractional row."""
    return float(np.interp(fractional, np.arange(len(values)), values))


def _digital_events(data) -> list:
    from offline_prog.io_events import Signal

    return [e for e in data.events if e.signal is Signal.DIGITAL]


def switch_errors(data, placed, what: str) -> np.ndarray:
    """(K,) per switch of output ``what`` (the program's name of the plan's digital
    output), its position along the path against the plan's ``set_path_m`` [m]."""
    events = _digital_events(data)
    mine = [row for switch, row in placed if switch.what == what]
    assert len(mine) == len(events), (len(mine), len(events))
    path = data.job.path_m
    return np.array(
        [at_rows(path, row) - e.set_path_m for row, e in zip(mine, events, strict=True)]
    )


# --- each controller's flow as it runs ------------------------------------------------------


def krl_flow(job, data, folder) -> tuple[np.ndarray, np.ndarray, list]:
    """(the plan's times t (N,) [s], the flow output KRL sets there [V], the placed
    switches): its ``ANOUT ON`` law on the plan's speed, ``FK`` switched by TRIGGERs
    at their positions and DELAYs (the output leads the speed by −DELAY)."""
    run, items = krl_items(data, folder)
    law = next(m for m in map(KRL_FLOW_LAW.search, run) if m)
    factor, (offset, delay, low, high) = law[2], (float(x) for x in law.groups()[2:])
    placed = place(data, items)
    t = job.samples.t
    live = np.zeros(len(t))
    for switch, row in placed:
        if switch.what == factor:
            live[t >= at_rows(data.job.t, row) + switch.delay_s] = float(switch.value)
    v_ahead = np.interp(t - delay, t, job.tcp_speed)  # DELAY < 0: the output leads
    return t, 10.0 * np.clip(live * v_ahead + offset, low, high), placed


def rapid_flow(job, data, text: str) -> tuple[np.ndarray, np.ndarray, list]:
    """(t (N,) [s], the flow RAPID sets [V], the placed switches): each ``TriggSpeed``'s
    ScaleValue (V per mm/s) from ScaleLag before the tool reaches its point, times the
    speed ScaleLag ahead; offset and limits are the signal's configuration (the
    header's, the cell's process I/O)."""
    placed = place(data, rapid_items(data, text))
    io, t = data.process_io, job.samples.t
    scale, lag = np.zeros(len(t)), np.zeros(len(t))
    for switch, row in placed:
        if switch.lag_s is not None:
            later = t >= at_rows(data.job.t, row) - switch.lag_s
            scale[later], lag[later] = float(switch.value) * 1e3, switch.lag_s
    v_ahead = np.interp(t + lag, t, job.tcp_speed)
    return t, np.clip(scale * v_ahead + io.offset, io.min, io.max), placed


def urscript_flow(job, script: str, output: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(the servoj commands' plan times (K,) [s], the analog output's value while each
    runs [V], the stream's period [s])."""
    q, value, period = urscript_stream(script, output)
    return stream_times(job, q, period), value, period


def urscript_switch_errors(data, script: str, t: np.ndarray) -> np.ndarray:
    """(K,) per ``set_standard_digital_out`` of the servoj stream (commands at plan
    times ``t``), the path position at the command that runs next against the plan's
    ``set_path_m`` [m] (set as the one before it ends: at most its travel late)."""
    switches, events = urscript_digital(script), _digital_events(data)
    assert [(n, s) for n, s, _ in switches] == [(e.output, e.state) for e in events]
    path = np.interp(t, data.job.t, data.job.path_m)
    return np.array([path[k] - e.set_path_m for (_, _, k), e in zip(switches, events, strict=True)])


def stream_times(job, q_stream: np.ndarray, period: float) -> np.ndarray:
    """(K,) the plan's time of each servoj target: the block runs the approach to the
    retract every ``period``; its start is where the joints agree with the plan's."""
    s = job.samples
    start = next(g.t_start for g in s.segments if g.kind == "approach")
    best = None
    for shift in np.arange(-2, 3) * period:
        t = start + shift + period * np.arange(len(q_stream))
        q_plan = np.stack([np.interp(t, s.t, s.q[:, j]) for j in range(6)], axis=1)
        error = np.abs(job.robot.controller_joints(q_plan) - q_stream).max()
        if best is None or error < best[0]:
            best = (error, t)
    assert best[0] < 1e-3, f"the servoj stream is not the plan's motion ({best[0]:.2g} rad)"
    return best[1]


def fanuc_flow(job, data, folder, robot, *, steps: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """(times (M,) [s] on a grid ``steps`` times finer than the plan's rows, the AO value
    the LS program holds there [V]): each L motion's AO (``fanuc_reader.walk``: placed by
    the program's own poses along the part) from the motion's start, the flow's idle
    value off the seams' paths. The grid is fine so that a step between two rows is not
    smeared over a row interval (the model's lag takes a piecewise-linear command)."""
    from fanuc_reader import walk

    s, idle = job.samples, data.process_io.idle
    at = np.arange((len(s.t) - 1) * steps + 1) / steps
    t_fine = np.interp(at, np.arange(len(s.t)), s.t)
    held = np.full(len(t_fine), idle)
    finite = np.isfinite(s.path_m)
    rows_near = np.round(at).astype(int)
    for seam, g in zip(walk(data, folder, robot), _runs(data), strict=True):
        ends = np.array([b for _, b, _ in seam["moves"]])
        values = np.array([v for _, _, v in seam["moves"]])
        lo, hi = g
        mine = (at >= lo) & (at <= hi) & finite[np.floor(at).astype(int)] & finite[rows_near]
        path = np.interp(t_fine[mine], s.t, np.nan_to_num(s.path_m))
        k = np.minimum(np.searchsorted(ends, path, side="left"), len(ends) - 1)
        held[mine] = values[k]
    return t_fine, held


def fanuc_switch_errors(data, folder, robot) -> np.ndarray:
    """(K,) per DB switch of the LS program, where it lands along the part
    (``fanuc_reader.walk``) against the plan's ``set_path_m`` [m]."""
    from fanuc_reader import walk

    errors = []
    for seam, name in zip(walk(data, folder, robot), data.seam_names, strict=True):
        events = [e for e in _digital_events(data) if e.seam == name]
        assert [(n, s) for n, s, _ in seam["db"]] == [(e.output, e.state) for e in events]
        errors += [p - e.set_path_m for (_, _, p), e in zip(seam["db"], events, strict=True)]
    return np.array(errors)


def _runs(data) -> list[tuple[int, int]]:
    """[(first row, last row)] of each seam's run (approach to retract), in run order."""
    runs = {}
    for g in data.segments:
        if g.kind != "link":
            lo, hi = runs.get(g.seam, (g.start, g.stop))
            runs[g.seam] = (min(lo, g.start), max(hi, g.stop))
    return list(runs.values())
