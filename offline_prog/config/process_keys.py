"""The cell-file keys of the process model (issue 28's contract), under ``process:``::

    process:
      model: bead                    # bead | heat_input | tape_heating
      bead:                          # sealant / adhesive: cross-section A = Q / v_TCP
        area_mm2: 12.0               # target
        tolerance_pct: 5
        flow_mm3_s_per_unit: 250.0   # dispensed flow per unit of the flow output
        lag_s: 0.08                  # first-order lag of the dispenser (time constant)
      heat_input:                    # arc welding, EN 1011-1: H = k · U · I / v
        voltage_v: 24.0
        current_a: 180.0
        efficiency: 0.8
        target_kj_mm: [0.5, 0.7]
      tape_heating:                  # tape laying: nip temperature from heater power
        width_mm: 25.0
        thickness_mm: 0.2
        density_kg_m3: 1550
        specific_heat_j_kg_k: 1200
        absorbed_fraction: 0.6
        ambient_c: 20
        target_c: [380, 420]
        max_power_w: 3000
        power_output: {analog_output: 2, w_per_unit: 300}

Only the section the model names is read; :func:`check_process` refuses a model
without its section, a non-positive parameter, an inverted band and a model without
the output it needs (bead: ``tool.process_io.flow``), each in one line.
"""

import dataclasses
import math
from pathlib import Path

from offline_prog.errors import InputError

REQUIRED = {"required": True}
MODELS = ("bead", "heat_input", "tape_heating")


def _required():
    return dataclasses.field(default=None, metadata=REQUIRED)


@dataclasses.dataclass
class BeadConfig:
    area_mm2: float = _required()  # target cross-section of the bead
    tolerance_pct: float = 5.0  # the band: target ± this share
    flow_mm3_s_per_unit: float = _required()  # dispensed flow per unit of the output
    lag_s: float = 0.0  # the dispenser's first-order time constant


@dataclasses.dataclass
class HeatInputConfig:
    voltage_v: float = _required()  # arc voltage U
    current_a: float = _required()  # welding current I
    efficiency: float = _required()  # thermal efficiency k of the process (EN 1011-1)
    target_kj_mm: list[float] = _required()  # [low, high]


@dataclasses.dataclass
class PowerOutput:
    analog_output: int = _required()  # the heater's power command on the controller
    w_per_unit: float = _required()  # heater power per unit of the output [W]


@dataclasses.dataclass
class TapeHeatingConfig:
    width_mm: float = _required()
    thickness_mm: float = _required()
    density_kg_m3: float = _required()
    specific_heat_j_kg_k: float = _required()
    absorbed_fraction: float = _required()  # share of the heater power the tape takes up
    ambient_c: float = 20.0  # the tape's temperature before the heater
    target_c: list[float] = _required()  # nip temperature band [low, high]
    max_power_w: float = _required()
    power_output: PowerOutput = dataclasses.field(default_factory=PowerOutput, metadata=REQUIRED)


@dataclasses.dataclass
class ProcessConfig:
    model: str = _required()  # bead | heat_input | tape_heating
    bead: BeadConfig | None = None
    heat_input: HeatInputConfig | None = None
    tape_heating: TapeHeatingConfig | None = None


def _positive(file: Path, key: str, value: float) -> None:
    if not (math.isfinite(value) and value > 0):
        raise InputError(file, key, f"must be a positive number, got {value:g}")


def _band(file: Path, key: str, band: list[float], *, positive: bool) -> None:
    if len(band) != 2 or not all(math.isfinite(x) for x in band):
        raise InputError(file, key, "must be [low, high], two numbers")
    if not band[0] < band[1]:
        raise InputError(file, key, f"low {band[0]:g} must be below high {band[1]:g}")
    if positive and band[0] <= 0:
        raise InputError(file, key, f"must be positive, got {band[0]:g}")


def check_process(file: Path, process: ProcessConfig | None, flow) -> None:
    """The model named, its section given and sane, and the output it needs present.

    Args:
        file: the cell file (for the message).
        process: the cell's ``process:`` (None: no model, nothing to check).
        flow: the cell's ``tool.process_io.flow`` (an AnalogFlow or None).

    Raises:
        InputError: one line naming the key and the reason.
    """
    if process is None:
        return
    if process.model not in MODELS:
        raise InputError(file, "process.model", f"{process.model!r} (use {', '.join(MODELS)})")
    section = getattr(process, process.model)
    key = f"process.{process.model}"
    if section is None:
        raise InputError(file, key, f"missing: process.model {process.model} needs its section")
    if process.model == "bead":
        for name in ("area_mm2", "tolerance_pct", "flow_mm3_s_per_unit"):
            _positive(file, f"{key}.{name}", getattr(section, name))
        if not (math.isfinite(section.lag_s) and 0 <= section.lag_s <= 1.0):
            raise InputError(
                file, f"{key}.lag_s", f"must be within [0, 1] s, got {section.lag_s:g}"
            )
        if section.tolerance_pct >= 100:
            raise InputError(file, f"{key}.tolerance_pct", "must be below 100")
        if flow is None:
            raise InputError(
                file, "tool.process_io.flow", "missing: process.model bead needs the flow output"
            )
        for name, value in (
            ("per_mps", flow.per_mps),
            ("lag_s", flow.lag_s),
            ("offset", flow.offset),
        ):
            if value not in (None, 0.0):
                raise InputError(
                    file,
                    f"tool.process_io.flow.{name}",
                    f"set by process.bead (the flow holds its area_mm2 with no offset, "
                    f"leading by its lag_s): remove {name}",
                )
    elif process.model == "heat_input":
        for name in ("voltage_v", "current_a", "efficiency"):
            _positive(file, f"{key}.{name}", getattr(section, name))
        if section.efficiency > 1:
            raise InputError(
                file, f"{key}.efficiency", f"must be at most 1, got {section.efficiency:g}"
            )
        _band(file, f"{key}.target_kj_mm", section.target_kj_mm, positive=True)
    else:
        for name in (
            "width_mm",
            "thickness_mm",
            "density_kg_m3",
            "specific_heat_j_kg_k",
            "absorbed_fraction",
            "max_power_w",
        ):
            _positive(file, f"{key}.{name}", getattr(section, name))
        if section.absorbed_fraction > 1:
            raise InputError(
                file,
                f"{key}.absorbed_fraction",
                f"must be at most 1, got {section.absorbed_fraction:g}",
            )
        _band(file, f"{key}.target_c", section.target_c, positive=False)
        if not section.target_c[0] > section.ambient_c:
            raise InputError(
                file, f"{key}.target_c", f"must lie above ambient_c {section.ambient_c:g} °C"
            )
        output = section.power_output
        if output is None or output.analog_output is None:
            raise InputError(file, f"{key}.power_output", "missing: the heater's power output")
        _positive(file, f"{key}.power_output.w_per_unit", output.w_per_unit)
        if flow is not None:
            raise InputError(
                file,
                "tool.process_io.flow",
                "process.model tape_heating drives the heater's power_output along the "
                "speed: a tape cell has no flow output",
            )
