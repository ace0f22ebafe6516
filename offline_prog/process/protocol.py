"""The protocol every process model keeps: what the plan asks of it and what it gives.

A model is a frozen dataclass in SI units, in a module of its own that holds its cell
keys, their physical bounds, its equation, source and assumptions; adding one is that
module and its line in :data:`offline_prog.process.registry.MODELS`. Nothing outside
``process/`` asks which model it has: the plan calls these methods.

- **Cell keys**: ``name`` (``process.model``'s value and its section's key), ``Keys``
  (the section's dataclass), :meth:`check_keys` (their physical bounds and the outputs
  they need, one line each), :meth:`from_keys` (the model in SI units),
  :meth:`controller_outputs` (outputs the keys name, checked against the controller),
  ``sets_flow`` and ``lag_key`` (the model sets ``tool.process_io.flow``'s law and lead).
- **What it needs from the plan**: the times, the TCP speed along the part and, for a
  model with an output, the output's command as the programs set it
  (:meth:`predict`); what of the output reaches the part (:meth:`delivered`,
  :meth:`delivered_at_rest`) through its lag (``output_lag_s``).
- **The quality column it writes**: ``column`` of trajectory.csv, ``unit`` and
  ``unit_scale`` (SI → unit); ``compares_uncompensated``: the quality with the output's
  lead off is reported beside it.
- **Its band**: :attr:`band` (SI) and :attr:`target`.
- **Its output schedule**: :meth:`speed_output` (the speed-following output's law as
  ``io_events.ProcessIo`` fields), :meth:`saturated` (where its law leaves its limits).
- **Its timing bound**: :meth:`speed_band` (the TCP speeds at which the output can hold
  the target), :meth:`speed_band_reason` (why a process speed cannot), :meth:`jerk_cap`
  (the path jerk the process stretch may have).
"""

from __future__ import annotations

import abc
import dataclasses
import math
from typing import ClassVar

import numpy as np

from offline_prog.constants import STANDSTILL_SPEED_M_S
from offline_prog.io_events import ProcessIo
from offline_prog.process.lag import first_order_response

SATURATION_TOL = 1e-9  # [output unit]: a clipped output differs from its law by more


def required_key():
    """A field of a model's section that the cell file must give (the default only
    serves the loader; config.typed_check reads the ``required`` mark)."""
    return dataclasses.field(default=None, metadata={"required": True})


class ProcessModel(abc.ABC):
    """A process model (module docstring). Subclasses are frozen dataclasses."""

    name: ClassVar[str]  # process.model's value, and the key of the model's section
    Keys: ClassVar[type]  # the section's dataclass: process.<name>'s keys
    column: ClassVar[str]  # trajectory.csv's quality column
    unit: ClassVar[str]  # the column's unit, as report.json names it
    unit_scale: ClassVar[float]  # SI → unit
    sets_flow: ClassVar[bool] = False  # its output law is tool.process_io.flow's
    lag_key: ClassVar[str | None] = None  # the key that sets the flow's lead, if it does
    compares_uncompensated: ClassVar[bool] = False  # quality with the lead off, beside
    # A seam end the joint limits slow keeps its leads, run slowed, rather than rest: at
    # rest the model's output spoils both ends, at a slowed speed it follows it.
    flies_slowed: ClassVar[bool] = False

    # Cell keys.
    @classmethod
    @abc.abstractmethod
    def check_keys(cls, file, keys, flow) -> None:
        """The section's keys within their physical bounds, and the outputs the model
        needs (``flow``: the cell's ``tool.process_io.flow`` or None).

        Raises:
            InputError: one line naming the key (``process.<name>.<key>``) and why.
        """

    @classmethod
    @abc.abstractmethod
    def from_keys(cls, keys) -> ProcessModel:
        """The model of checked keys, in SI units."""

    @classmethod
    def controller_outputs(cls, keys) -> list[tuple[str, object]]:
        """(key, output record) of the controller outputs the keys name (an output
        record has ``digital_output`` or ``analog_output``); none by default."""
        return []

    # The quality column.
    @abc.abstractmethod
    def predict(self, t: np.ndarray, v_tcp: np.ndarray, command) -> np.ndarray:
        """(N,) the quality [SI] at times t (N,) [s] and TCP speeds v_tcp (N,) [m/s]
        from the output's command (N,) as the controller sets it (None: no output);
        NaN where the tool stands."""

    @property
    def output_lag_s(self) -> float:
        """The first-order lag between the output's command and what reaches the part
        [s] (0: none, or no output)."""
        return 0.0

    @abc.abstractmethod
    def delivered(self, t: np.ndarray, command) -> np.ndarray:
        """(N,) what of the output reaches the part on each row (its unit; > 0: the
        process dispenses there)."""

    @abc.abstractmethod
    def delivered_at_rest(self, settings: ProcessIo | None) -> float:
        """What the output gives at a standstill by its own law: a row where the tool
        stands dispenses only beyond it."""

    # The band.
    @property
    @abc.abstractmethod
    def band(self) -> tuple[float, float]:
        """[low, high] of the quality [SI]."""

    @property
    def target(self) -> float:
        """The quality the output holds [SI]: the band's middle unless the model says."""
        low, high = self.band
        return 0.5 * (low + high)

    # The output schedule.
    def speed_output(self) -> dict:
        """The speed-following output the model sets, as ``io_events.ProcessIo`` fields
        (none by default)."""
        return {}

    def saturated(self, v: np.ndarray, settings: ProcessIo | None) -> np.ndarray:
        """(N,) rows where the output the target needs at speed v (N,) [m/s] lies
        outside the output's limits (none without an output)."""
        return np.zeros(len(v), bool)

    # The timing bound.
    @abc.abstractmethod
    def speed_band(self, u_min: float, u_max: float) -> tuple[float, float]:
        """[low, high] TCP speeds [m/s] at which the output within [u_min, u_max] (its
        unit) can hold the target."""

    @abc.abstractmethod
    def speed_band_reason(self, v: float, *, u_min: float, u_max: float) -> str | None:
        """Why the process speed v [m/s] cannot hold the target with the output in
        [u_min, u_max], with the figures; None when it can."""

    def jerk_cap(self, v_process: float) -> tuple[float, str | None]:
        """(the path jerk the process stretch may have at the process speed v_process
        [m/s³], why) : (inf, None) where the process asks nothing of it."""
        return math.inf, None


class SpeedFollowingModel(ProcessModel):
    """A model whose output follows the TCP speed (a dispenser's flow, a heater's
    power) and reaches the part through a first-order lag of ``output_lag_s``."""

    @property
    def max_command(self) -> float:
        """The output's own ceiling beyond its limits [unit] (none by default)."""
        return math.inf

    def delivered(self, t: np.ndarray, command) -> np.ndarray:
        if command is None:
            raise ValueError(f"process model {self.name} needs its output's command")
        return first_order_response(t, command, self.output_lag_s)

    def delivered_at_rest(self, settings: ProcessIo | None) -> float:
        return float(settings.flow(STANDSTILL_SPEED_M_S))

    def saturated(self, v: np.ndarray, settings: ProcessIo | None) -> np.ndarray:
        law = settings.offset + settings.per_mps * v
        limit = min(settings.max, self.max_command)
        return (law > limit + SATURATION_TOL) | (law < settings.min - SATURATION_TOL)
