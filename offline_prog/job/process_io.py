"""Process I/O along a job, decided once: where each seam's process output (glue gun,
torch) switches, when the flow output goes live, and both as per-row columns.

The valve opens ``on.lead_mm`` before each seam's start and closes ``off.lead_mm``
before its end (positions along the tool's path on the part, ``JobSamples.path_m``:
negative on the approach, beyond L on the retract; a closed seam's L includes its
``overlap_mm``); the digital output is set the valve's response time (``on.delay_s``,
``off.delay_s``) before. The flow output follows the TCP speed (value = offset +
per_mps · v_TCP, clipped to [min, max]) while the valve is open, and rests at its idle
value (``ProcessIo.idle``) otherwise; it goes live ``flow.lag_s`` before the valve
opens (on a flying seam FLOW_PRIME_LAGS lags before: the tool is at speed there and the
lagging flow has risen to its command by the opening) and its command leads the speed
by that lag, but it is cut when the valve closes. The events
(:class:`~offline_prog.io_events.IoEvent`) are what every program writer translates.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.config.cell import ProcessIoConfig
from offline_prog.constants import FLOW_PRIME_LAGS
from offline_prog.errors import TravellingError
from offline_prog.io_events import IoEvent, ProcessIo, Signal
from offline_prog.job.assemble import JobSamples
from offline_prog.process.protocol import ProcessModel

POSITION_TOL_M = 1e-6  # a switch this close to the approach's start or retract's end


@dataclasses.dataclass(frozen=True)
class IoColumns:
    """Per row: ``digital`` (N,) 0/1 of the process output (None without on/off),
    ``analog`` (N,) the flow output's command [V] (None without flow); ``events`` in
    time order; ``settings`` the cell's process I/O in SI units (None: no I/O);
    ``valve`` (N,) where the valve is open (the output's response time after it is set;
    None without on/off)."""

    digital: np.ndarray | None
    analog: np.ndarray | None
    events: list[IoEvent]
    settings: ProcessIo | None = None
    valve: np.ndarray | None = None  # (N,) bool: the valve open (the output's delay on)

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
        on_delay_s=0.0 if io is None or io.on is None else io.on.delay_s,
        off_delay_s=0.0 if io is None or io.off is None else io.off.delay_s,
        **fields,
    )


def io_columns(
    samples: JobSamples,
    io: ProcessIoConfig | None,
    lengths_m: dict[str, float],
    tcp_speed,
    model: ProcessModel | None = None,
    *,
    flying: frozenset[str] = frozenset(),
) -> IoColumns:
    """The process output's state and the flow command on every row, and the events.

    Args:
        samples: the job's samples.
        io: ``tool.process_io`` (None: no I/O).
        lengths_m: each seam's path length L [m] by name.
        flying: the names of the seams run flying (``path.lead``).
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
    on = np.zeros(len(t), dtype=bool)  # the output as the controller sets it
    valve = np.zeros(len(t), dtype=bool)  # the valve open, its response time later
    live = np.zeros(len(t), dtype=bool)  # the flow's command is live
    flowing = settings.analog_output is not None
    switching = settings.digital_output is not None
    lag = settings.lag_s if flowing else 0.0
    events: list[IoEvent] = []
    for seam, (rows, t_end) in _seam_rows(samples).items():
        path, t_seam = _with_retract_end(samples.path_m[rows], t[rows], t_end)
        length = lengths_m[seam]
        if not switching:  # no switching: the flow runs on the seam
            gate = (0.0, length)
        else:
            gate = (-settings.on_lead_m, length - settings.off_lead_m)
            _check_gate(seam, gate, path, length)
        times = [_time_at(position, path, t_seam) for position in gate]  # valve opens, closes
        if switching:
            set_times = [times[0] - settings.on_delay_s, times[1] - settings.off_delay_s]
            _check_delays(seam, set_times, t_seam[0])
            on |= (t >= set_times[0]) & (t < set_times[1])
            valve |= (t >= times[0]) & (t < times[1])
            events += [
                _event(
                    seam,
                    Signal.DIGITAL,
                    settings.digital_output,
                    state,
                    float(state),
                    position,
                    time,
                    path,
                    t_seam,
                )
                for state, position, time in zip((True, False), gate, set_times, strict=True)
            ]
        if flowing:
            prime = (FLOW_PRIME_LAGS if seam in flying else 1.0) * lag
            if times[0] - prime < t_seam[0] - 1e-9:  # a program sets it on the approach
                raise IoPlacementError(
                    _lag_key(model),
                    f"{prime:g} s before seam {seam}'s output goes on is before its approach "
                    f"starts ({times[0] - t_seam[0]:.3f} s earlier): a longer approach or "
                    "on.lead_mm leaves the flow room to lead",
                )
            # Live FLOW_PRIME_LAGS lags before the valve opens, until it closes (the
            # cut-off not led).
            flow_times = (times[0] - prime, times[1])
            live |= (t >= flow_times[0]) & (t < flow_times[1])
            # Where each takes effect, lag_s after it is set (a controller that leads by
            # the lag itself places it there): the gate's side, and past the valve's closing.
            flow_at = tuple(float(np.interp(x + lag, t_seam, path)) for x in flow_times)
            v_on = float(np.interp(times[0], t, tcp_speed))
            values = (float(settings.flow(v_on)), settings.idle)
            events += [
                _event(
                    seam,
                    Signal.ANALOG,
                    settings.analog_output,
                    state,
                    value,
                    position,
                    time,
                    path,
                    t_seam,
                )
                for state, value, position, time in zip(
                    (True, False), values, flow_at, flow_times, strict=True
                )
            ]
    digital = on.astype(np.int8) if switching else None
    analog = None
    if flowing:
        # The command at t is the flow the tool needs lag_s later.
        value = settings.flow(np.interp(t + lag, t, tcp_speed))
        analog = np.where(live, value, settings.idle)
    events.sort(key=lambda e: (e.t_s, e.signal is not Signal.DIGITAL))
    return IoColumns(digital, analog, events, settings, valve if switching else None)


def _event(seam, signal, output, state, value, position, time, path, t_seam) -> IoEvent:
    """The event taking effect at ``position`` [m], set at ``time`` [s] where the tool
    is then on the seam's path."""
    where = float(np.interp(time, t_seam, path))
    return IoEvent(seam, signal, output, state, value, float(position), float(time), where)


def _check_delays(seam: str, set_times: list[float], t_start: float) -> None:
    """The valve's response times leave the output set after the approach starts and
    on before off."""
    if set_times[0] < t_start - 1e-9:
        raise IoPlacementError(
            "tool.process_io.on.delay_s",
            f"seam {seam}: the output would be set {t_start - set_times[0]:.3f} s before its "
            "approach starts: a longer approach or a smaller on.lead_mm leaves the valve room",
        )
    if not set_times[0] < set_times[1]:
        raise IoPlacementError(
            "tool.process_io.off.delay_s",
            f"seam {seam}: the output would be set off before it is set on (off.delay_s "
            "longer than the seam's run)",
        )


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
