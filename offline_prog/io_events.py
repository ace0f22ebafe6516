"""Process I/O as the plan decides it: the switch events every program writer translates.

A plan computes its I/O events once (``job.process_io``) and stores them with the plan
(``job.npz``); the KRL, RAPID, URScript and CSV writers turn them into statements and
never recompute a switch position from ``lead_mm``.

An event is one change of one output: the digital process output (glue gun, torch)
going on or off, or the analog flow output going live or back to its idle value.
Positions are distances along the seam's tool path from the seam's start [m] (negative
on the approach, beyond the seam's length L on the retract), so a controller can switch
on the path (KRL ``TRIGGER WHEN PATH``, RAPID ``TriggIO`` / ``TriggSpeed``).

The flow output is live only while the digital output is on (without on/off: while the
seam runs), and at its idle value otherwise: the flow at zero speed, ``offset`` clipped
to [min, max], which is what every controller's speed-proportional output gives when
its factor is zero. The dispenser's lag ``lag_s`` shifts the flow's changes earlier:
the flow goes live ``lag_s`` before the valve opens, so the dispensed flow is up to
speed where the gun opens; the cut-off is not led: the flow stays live until the valve
closes (a flow cut ``lag_s`` early thins the seam's last stretch).

The valve answers its output after its response time (``on.delay_s``, ``off.delay_s``):
a digital event is set that much before the tool reaches the position where the valve
opens or closes (``path_m``), at ``set_path_m``.
"""

from __future__ import annotations

import dataclasses
import enum

import numpy as np


class Signal(enum.Enum):
    """Which output an event changes."""

    DIGITAL = "digital"  # the process output: value 1 on, 0 off
    ANALOG = "analog"  # the flow output: value its level [V]


@dataclasses.dataclass(frozen=True)
class IoEvent:
    """One output change of seam ``seam``.

    Attributes:
        seam: the seam's name.
        signal: digital process output or analog flow output.
        output: the output's number on the controller.
        state: digital on / off; analog live / back to idle.
        value: digital 1.0 / 0.0; analog: the value from this event on [V].
        path_m: where along the seam's path from its start the change takes effect [m]
            (digital: where the valve opens or closes; flow: where the tool is
            ``lag_s`` after it is set: the gate going live, past the valve's closing
            for the cut-off, where a controller that leads by the lag itself sets it).
        t_s: job time at which the controller sets the output [s] (digital: the valve's
            delay before the tool passes ``path_m``; flow going live: ``lag_s`` before;
            flow cut-off: when the tool passes ``path_m``).
        set_path_m: where the tool is at ``t_s`` [m]: where a controller sets the
            output (without its own lag compensation for the flow).
    """

    seam: str
    signal: Signal
    output: int
    state: bool
    value: float
    path_m: float
    t_s: float
    set_path_m: float

    def as_dict(self) -> dict:
        """JSON-ready (``signal`` as its value)."""
        return {**dataclasses.asdict(self), "signal": self.signal.value}

    @classmethod
    def from_dict(cls, data: dict) -> IoEvent:
        return cls(**{**data, "signal": Signal(data["signal"])})


@dataclasses.dataclass(frozen=True)
class ProcessIo:
    """``tool.process_io`` in SI units: the digital output switched ``on_lead_m`` before
    each seam's start and ``off_lead_m`` before its end (None: no switching), set
    ``on_delay_s`` / ``off_delay_s`` earlier (the valve's response), and the
    analog flow output value = offset + per_mps · v_TCP [V] in [min, max] while the
    process output is on (None: no flow); ``lag_s`` the dispenser's lag [s]. The
    leads are the cell's words for the header; the positions are the events'."""

    digital_output: int | None = None
    on_lead_m: float = 0.0
    off_lead_m: float = 0.0
    on_delay_s: float = 0.0
    off_delay_s: float = 0.0
    analog_output: int | None = None
    per_mps: float = 0.0
    offset: float = 0.0
    min: float = 0.0
    max: float = 10.0
    lag_s: float = 0.0
    ao_unit: str = "volts"  # FANUC's AO value: volts, or counts (counts_per_volt per V)
    counts_per_volt: float = 1.0

    @property
    def idle(self) -> float:
        """The flow's value while the process output is off [V]: the flow at zero
        speed, ``offset`` clipped to [min, max]."""
        return float(min(max(self.offset, self.min), self.max))

    def flow(self, v_tcp):
        """The live flow's value [V] at TCP speeds ``v_tcp`` [m/s] (array or scalar)."""
        return np.clip(self.offset + self.per_mps * np.asarray(v_tcp), self.min, self.max)
