"""Universal Robots URScript: a whole job as one ``.script``.

Links: ``movej`` through the link's joint waypoints (the planned, collision-checked
straight joint moves; the controller's own timing at the joints' common limits). Each
seam with its approach and retract: the planned joint trajectory resampled to the
controller period and streamed with ``servoj``, as the one-seam writer does
(:mod:`offline_prog.export.ur.urscript`).

Process I/O from the plan's I/O events: an output is set (``set_standard_digital_out``,
``set_standard_analog_out``) just before the first ``servoj`` whose sample has reached
the event's time, so the tool is at most v_TCP · period past its position (0.2 mm at
100 mm/s and 2 ms). The flow, ``set_standard_analog_out(n, value / 10 V)`` (URScript
takes the output as a fraction of its 0–10 V range), follows the plan's ``ao`` column
while it is live, interpolated between live samples only (an edge is a step, not a
ramp), written at each event and whenever it has changed by ``ANALOG_STEP_V`` or by
``ANALOG_STEP_SHARE`` of its value, and holds the idle value otherwise.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.export.header import header_lines
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.payload import payload
from offline_prog.export.text import identifier, urscript_comment
from offline_prog.export.ur.urscript import (
    E_SERIES_PERIOD_S,
    NAME_MAX,
    SERVOJ_GAIN,
    SERVOJ_LOOKAHEAD_S,
    _list,
    joints_on_steps,
)
from offline_prog.io_events import Signal

ANALOG_RANGE_V = 10.0  # standard analog outputs: 0..10 V as 0..1
ANALOG_STEP_V = 0.02  # write the flow when it changed by this much
# ... or by this share of its value (a process model's quality follows the output's
# value relative to the speed: a bead or a tape at a slow ramp needs fine steps)
ANALOG_STEP_SHARE = 0.002


def write_urscript_job(
    data: JobProgramData,
    out_dir: Path,
    *,
    name: str = "offline_prog",
    period_s: float = E_SERIES_PERIOD_S,
    forced: bool = False,
) -> Path:
    """Write ``out_dir/<name>.script``; returns the file."""
    identifier(name, max_chars=NAME_MAX, what="name")
    robot = data.load_robot()
    job, io = data.job, data.process_io
    v_link, a_link = float(robot.qd_max.min()), float(robot.qdd_max.min())
    conventions = [
        "Units: m, rad, s. Joint order: " + ", ".join(job.joint_names) + ".",
        f"Job: {len(data.seam_names)} seams in this order: {', '.join(data.seam_names)}.",
        f"Links: movej through joint waypoints (a={a_link:.3f}, v={v_link:.3f}); seams with "
        f"approach and retract: servoj every {period_s} s (resampled from the plan).",
    ]
    if io is not None and io.digital_output is not None:
        conventions.append(
            f"Process output: standard digital out {io.digital_output}, on "
            f"{io.on_lead_m * 1e3:g} mm before each seam's start, off "
            f"{io.off_lead_m * 1e3:g} mm before its end (at the servoj sample that reaches it)."
        )
    if io is not None and io.analog_output is not None:
        conventions.append(
            f"Flow: standard analog out {io.analog_output} = ({io.offset:g} V + "
            f"{io.per_mps:g} V per m/s x v_TCP) / 10 V, within [{io.min:g}, {io.max:g}] V."
        )
    lines = [
        f"# {urscript_comment(line)}"
        for line in header_lines(job, conventions=conventions, forced=forced)
    ]
    lines.append(f"def {name}():")
    if (load := payload(job.payload)) is not None:
        mass, p_EC = load.total(job.X_EP)
        lines.append(f"  set_payload({mass:.3f}, {_list(p_EC, 4)})")
    lines.append(f"  movej({_list(data.link_waypoints[0][0])}, a={a_link:.3f}, v={v_link:.3f})")
    links = iter(data.link_waypoints)
    segments = list(data.segments)
    k = 0
    while k < len(segments):
        segment = segments[k]
        if segment.kind == "link":
            for q in next(links)[1:]:
                lines.append(f"  movej({_list(q)}, a={a_link:.3f}, v={v_link:.3f})")
            k += 1
            continue
        stop = k
        while stop + 1 < len(segments) and segments[stop + 1].kind != "link":
            stop += 1
        rows = slice(segment.start, min(segments[stop].stop + 1, len(job.t)))
        seam = data.seam_names.index(segment.seam)
        lines += _stream(data, rows, seam, period_s)
        k = stop + 1
    lines += ["  stopj(2.0)", "end", f"{name}()"]
    file = Path(out_dir) / f"{name}.script"
    write_atomic(file, "\n".join(lines) + "\n")
    return file


def _stream(data: JobProgramData, rows: slice, seam: int, period_s: float) -> list[str]:
    """servoj lines over the job's rows of one seam (approach to retract), with I/O."""
    job, io = data.job, data.process_io
    name = data.seam_names[seam]
    t = job.t[rows]
    grid = np.arange(0.0, t[-1] - t[0], period_s)
    grid = np.append(grid, t[-1] - t[0]) if t[-1] - t[0] - grid[-1] > 1e-9 else grid
    grid = grid + t[0]  # the job's clock
    q = joints_on_steps(t, job.q[rows], grid)
    # Event k is set before the first command whose sample is at or past its time.
    sets: dict[int, list] = {}
    for event in data.events:
        if event.seam == name:
            i = int(np.searchsorted(grid, event.t_s - 1e-12))
            sets.setdefault(min(max(i, 1), len(grid) - 1), []).append(event)
    flow = _flow(data, rows, grid, name)
    lines, last_flow = [], None
    for i in range(1, len(grid)):
        for event in sets.get(i, []):
            if event.signal is Signal.DIGITAL:
                state = "True" if event.state else "False"
                lines.append(f"  set_standard_digital_out({event.output}, {state})")
        if flow is not None and (
            last_flow is None
            or abs(flow[i] - last_flow) >= min(ANALOG_STEP_V, ANALOG_STEP_SHARE * abs(last_flow))
            or any(e.signal is Signal.ANALOG for e in sets.get(i, []))
        ):
            last_flow = flow[i]
            lines.append(
                f"  set_standard_analog_out({io.analog_output}, "
                f"{np.clip(flow[i] / ANALOG_RANGE_V, 0.0, 1.0):.4f})"
            )
        lines.append(
            f"  servoj({_list(q[i])}, t={period_s}, lookahead_time={SERVOJ_LOOKAHEAD_S}, "
            f"gain={SERVOJ_GAIN})"
        )
    return lines


def _flow(data: JobProgramData, rows: slice, grid: np.ndarray, seam: str) -> np.ndarray | None:
    """(len(grid),) the flow command at the grid times [V]: the plan's ``ao`` column
    between its live samples while the flow is live (its analog events), else idle."""
    io = data.process_io
    if io is None or io.analog_output is None or data.analog is None:
        return None
    t, value = data.job.t[rows], data.analog[rows]
    events = data.seam_events(seam, Signal.ANALOG)
    out = np.full(len(grid), io.idle)
    for on, off in zip(events[::2], events[1::2], strict=True):
        live = (t >= on.t_s) & (t < off.t_s)
        here = (grid >= on.t_s) & (grid < off.t_s)
        if live.any():
            out[here] = np.interp(grid[here], t[live], value[live])
        else:  # a window shorter than a sample: the event's own value
            out[here] = on.value
    return out
