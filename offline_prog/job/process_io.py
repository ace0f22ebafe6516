"""Process I/O along a job, decided once: where each seam's process output (glue gun,
torch) switches, when the flow output goes live, and both as per-row columns.

The digital output goes on ``on.lead_mm`` before each seam's start and off
``off.lead_mm`` before its end (positions along the tool's path on the part,
``JobSamples.path_m``: negative on the approach, beyond L on the retract). The flow
output follows the TCP speed (value = offset + per_mps · v_TCP, clipped to [min, max])
only while the digital output is on, and rests at its idle value (``ProcessIo.idle``)
otherwise; its command leads by the dispenser's lag ``flow.lag_s``. The events
(:class:`~offline_prog.io_events.IoEvent`) are what every program writer translates.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.config.cell import ProcessIoConfig
from offline_prog.errors import TravellingError
from offline_prog.io_events import IoEvent, ProcessIo, Signal
from offline_prog.job.assemble import JobSamples
from offline_prog.process.protocol import ProcessModel

POSITION_TOL_M = 1e-6  # a switch this close to the approach's start or retract's end


@dataclasses.dataclass(frozen=True)
class IoColumns:
    """Per row: ``digital`` (N,) 0/1 of the process output (None without on/off),
    ``analog`` (N,) the flow output's command [V] (None without flow); ``events`` in
    time order; ``settings`` the cell's process I/O in SI units (None: no I/O)."""

    digital: np.ndarray | None
    analog: np.ndarray | None
    events: list[IoEvent]
    settings: ProcessIo | None = None

    @property
    def switches(self) -> list[IoEvent]:
        """The digital output's events (report.json's ``process_io``)."""
        return [e for e in self.events if e.signal is Signal.DIGITAL]


class IoPlacementError(TravellingError, ValueError):
    """The switches of a seam are out of order or outside its approach, seam and retract."""

    def __init__(self, key: str, reason: str):
        self.key, self.reason = key, reason
        super().__init__(f"{key}: {reason}")


def process_io_settings(
    io: ProcessIoConfig | None, model: ProcessModel | None = None
) -> ProcessIo | None:
    """The cell's ``tool.process_io`` in SI units, with the speed-following output the
    process model sets (its ``speed_output``: the bead's flow gain and lead, the tape
    heater's power output); None: no process I/O."""
    fields = {} if model is None else model.speed_output()
    if io is None and not fields:
        return None
    flow = None if io is None else io.flow
    if flow is not None:
        fields = {
            "analog_output": flow.analog_output,
            "per_mps": flow.per_mps,
            "offset": flow.offset,
            "min": flow.min,
            "max": flow.max,
            "lag_s": flow.lag_s,
            "ao_unit": flow.ao_unit,
            "counts_per_volt": flow.counts_per_volt or 1.0,
        } | fields
    return ProcessIo(
        digital_output=None if io is None or io.on is None else io.on.digital_output,
        on_lead_m=0.0 if io is None or io.on is None else io.on.lead_mm * 1e-3,
        off_lead_m=0.0 if io is None or io.off is None else io.off.lead_mm * 1e-3,
        **fields,
    )


def io_columns(
    samples: JobSamples,
    io: ProcessIoConfig | None,
    lengths_m: dict[str, float],
    tcp_speed,
    model: ProcessModel | None = None,
) -> IoColumns:
    """The process output's state and the flow command on every row, and the events.

    Args:
        samples: the job's samples.
        io: ``tool.process_io`` (None: no I/O).
        lengths_m: each seam's path length L [m] by name.
        tcp_speed: (N,) speed of the tool along the part [m/s].
        model: the cell's process model (it may set the speed-following output).

    Raises:
        IoPlacementError: on a seam, the output goes off before it goes on, either
            switch lies outside the approach's start .. the retract's end, or the output
            is never on while the seam runs (one line naming the seam and both
            positions); or the flow's lag leads its start before the approach.
    """
    settings = process_io_settings(io, model)
    if settings is None:
        return IoColumns(None, None, [])
    t = samples.t
    on = np.zeros(len(t), dtype=bool)
    live = np.zeros(len(t), dtype=bool)  # the flow's command is live
    flowing = settings.analog_output is not None
    lag = settings.lag_s if flowing else 0.0
    events: list[IoEvent] = []
    for seam, (rows, t_end) in _seam_rows(samples).items():
        path, t_seam = _with_retract_end(samples.path_m[rows], t[rows], t_end)
        length = lengths_m[seam]
        if settings.digital_output is None:  # no switching: the flow runs on the seam
            gate = (0.0, length)
        else:
            gate = (-settings.on_lead_m, length - settings.off_lead_m)
            _check_gate(seam, gate, path, length)
        times = [_time_at(position, path, t_seam) for position in gate]
        if settings.digital_output is not None:
            on |= (t >= times[0]) & (t < times[1])
            events += [
                IoEvent(
                    seam,
                    Signal.DIGITAL,
                    settings.digital_output,
                    state,
                    float(state),
                    position,
                    time,
                    position,
                )
                for state, position, time in zip((True, False), gate, times, strict=True)
            ]
        if flowing:
            if times[0] - lag < t_seam[0] - 1e-9:  # a program sets it on the approach
                raise IoPlacementError(
                    _lag_key(model),
                    f"{lag:g} s before seam {seam}'s output goes on is before its approach "
                    f"starts ({times[0] - t_seam[0]:.3f} s earlier): a longer approach or "
                    "on.lead_mm leaves the flow room to lead",
                )
            live |= (t >= times[0] - lag) & (t < times[1] - lag)
            v_on = float(np.interp(times[0], t, tcp_speed))
            values = (float(settings.flow(v_on)), settings.idle)
            events += [
                IoEvent(
                    seam,
                    Signal.ANALOG,
                    settings.analog_output,
                    state,
                    value,
                    position,
                    time - lag,
                    float(np.interp(time - lag, t_seam, path)),
                )
                for state, value, position, time in zip(
                    (True, False), values, gate, times, strict=True
                )
            ]
    digital = on.astype(np.int8) if settings.digital_output is not None else None
    analog = None
    if flowing:
        # The command at t is the flow the tool needs lag_s later.
        value = settings.flow(np.interp(t + lag, t, tcp_speed))
        analog = np.where(live, value, settings.idle)
    events.sort(key=lambda e: (e.t_s, e.signal is not Signal.DIGITAL))
    return IoColumns(digital, analog, events, settings)


def _lag_key(model: ProcessModel | None) -> str:
    """The key that sets the flow's lead: the process model's (a bead's lag), else the
    flow's own."""
    own = None if model is None else model.lag_key
    return own or "tool.process_io.flow.lag_s"


def _check_gate(seam: str, gate: tuple[float, float], path: np.ndarray, length: float) -> None:
    """On before off, both within the approach's start .. the retract's end, and the
    output on for some of the seam."""
    on, off = gate
    start, end = float(path[0]), float(path[-1])
    why = None
    if not on < off:
        why = "the output must go on before it goes off"
    elif on < start - POSITION_TOL_M or off > end + POSITION_TOL_M:
        why = (
            f"both must lie between the approach's start ({start * 1e3:.1f} mm) and the "
            f"retract's end ({end * 1e3:.1f} mm)"
        )
    elif not (on < length and off > 0.0):
        why = f"the output is never on while the seam (0 to {length * 1e3:.1f} mm) runs"
    if why is not None:
        raise IoPlacementError(
            "tool.process_io",
            f"seam {seam}: on at {on * 1e3 + 0.0:.1f} mm and off at {off * 1e3 + 0.0:.1f} mm "
            "along its "
            f"path (on.lead_mm before the start, off.lead_mm before the end): {why}",
        )


def _with_retract_end(path: np.ndarray, t: np.ndarray, t_end: float):
    """A seam's path positions and times with the retract's end appended: its row is
    the next link's first (path_m NaN there), so its position continues the last two
    samples' speed to ``t_end`` (at rest in a plan: the last position)."""
    speed = np.diff(path[-2:]).sum() / max(np.diff(t[-2:]).sum(), 1e-12)
    end = path[-1] + speed * (t_end - t[-1])
    return np.append(path, end), np.append(t, t_end)


def _time_at(position: float, path: np.ndarray, t: np.ndarray) -> float:
    """The first time [s] the tool reaches ``position`` on a seam's non-decreasing
    path (linear between the samples around it)."""
    i = int(np.searchsorted(path, position, side="left"))
    if i <= 0:
        return float(t[0])
    if i >= len(path):
        return float(t[-1])
    a, b = path[i - 1], path[i]
    share = 0.0 if b <= a else (position - a) / (b - a)
    return float(t[i - 1] + share * (t[i] - t[i - 1]))


def _seam_rows(samples: JobSamples) -> dict[str, tuple[slice, float]]:
    """Rows of each seam's approach, process and retract, in run order, and the time
    its retract ends [s]."""
    rows: dict[str, list] = {}
    for segment in samples.segments:
        if segment.kind != "link":
            span = rows.setdefault(segment.seam, [segment.start, segment.stop, 0.0])
            span[1:] = segment.stop, segment.t_stop
    return {seam: (slice(a, b), t_end) for seam, (a, b, t_end) in rows.items()}
