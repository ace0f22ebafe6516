"""Process I/O along a job: the digital output that switches the process (glue gun,
torch) on ``lead_mm`` before each seam's start and off ``lead_mm`` before its end, and
an analog output that follows the TCP speed (value = offset + per_mps · v_TCP, clipped
to [min, max]) while the process runs.

Positions are distances along the tool's path on the part (``JobSamples.path_m``:
negative on the approach), so a controller can switch them on the path (KRL ``TRIGGER
WHEN PATH``, RAPID ``TriggIO``), not by time guesswork.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.config.cell import ProcessIoConfig
from offline_prog.job.assemble import JobSamples


@dataclasses.dataclass(frozen=True)
class IoEvent:
    """One switch: ``seam``; ``output`` number; ``state`` on/off; ``path_m`` its position
    along the seam's tool path from the seam's start [m]; ``t_s`` the job time [s]."""

    seam: str
    output: int
    state: bool
    path_m: float
    t_s: float


@dataclasses.dataclass(frozen=True)
class IoColumns:
    """Per row: ``digital`` (N,) 0/1 of the process output (None without on/off),
    ``analog`` (N,) the flow output's value (None without flow); ``events``."""

    digital: np.ndarray | None
    analog: np.ndarray | None
    events: list[IoEvent]


class IoPlacementError(ValueError):
    """A switching point lies outside its seam's approach, process and retract."""

    def __init__(self, key: str, reason: str):
        self.key, self.reason = key, reason
        super().__init__(f"{key}: {reason}")


def io_columns(
    samples: JobSamples, io: ProcessIoConfig | None, lengths_m: dict[str, float], tcp_speed
) -> IoColumns:
    """The process output's state and the flow value on every row, and the switches.

    Args:
        samples: the job's samples.
        io: ``tool.process_io`` (None: no I/O).
        lengths_m: each seam's path length L [m] by name.
        tcp_speed: (N,) speed of the tool along the part [m/s].

    Raises:
        IoPlacementError: a lead puts a switch before the approach's start or after the
            retract's end (naming the key).
    """
    n = len(samples.t)
    if io is None:
        return IoColumns(None, None, [])
    on = np.zeros(n, dtype=bool)
    events: list[IoEvent] = []
    for seam, rows in _seam_rows(samples).items():
        path, t = samples.path_m[rows], samples.t[rows]
        if io.on is None:
            on[rows] = np.isin(samples.labels()[rows], [f"process:{seam}"])
            continue
        switches = (
            ("on", io.on, -io.on.lead_mm * 1e-3, True),
            ("off", io.off, lengths_m[seam] - io.off.lead_mm * 1e-3, False),
        )
        times = {}
        for name, switch, position, state in switches:
            if not path[0] - 1e-9 <= position <= path[-1] + 1e-9:
                raise IoPlacementError(
                    f"tool.process_io.{name}.lead_mm",
                    f"{switch.lead_mm:g} mm puts the switch of seam {seam} outside its "
                    f"approach, seam and retract ({-path[0] * 1e3:.1f} mm before the start "
                    f"to {(path[-1] - lengths_m[seam]) * 1e3:.1f} mm after the end)",
                )
            # path_m is non-decreasing over the seam's rows: the first row at or past it.
            i = int(np.searchsorted(path, position - 1e-12))
            times[name] = float(np.interp(position, path, t)) if len(t) > 1 else float(t[0])
            events.append(IoEvent(seam, switch.digital_output, state, position, times[name]))
            if state:
                start = rows.start + i
            else:
                on[start : rows.start + i] = True
    digital = on.astype(np.int8) if io.on is not None else None
    analog = None
    if io.flow is not None:
        flow = io.flow
        value = np.clip(flow.offset + flow.per_mps * np.asarray(tcp_speed), flow.min, flow.max)
        analog = np.where(on, value, flow.min)
    return IoColumns(digital, analog, events)


def _seam_rows(samples: JobSamples) -> dict[str, slice]:
    """Rows of each seam's approach, process and retract, in run order."""
    rows: dict[str, list[int]] = {}
    for segment in samples.segments:
        if segment.kind != "link":
            span = rows.setdefault(segment.seam, [segment.start, segment.stop])
            span[1] = segment.stop
    return {seam: slice(a, b) for seam, (a, b) in rows.items()}
