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

``model`` names one of ``process.registry.MODELS``; each model's section is that
model's ``Keys`` (its own module). Only the section the model names is read;
:func:`check_process` refuses an unknown model and a model without its section, and
the model checks its keys: their physical bounds and the outputs it needs (bead:
``tool.process_io.flow``), each in one line.
"""

import dataclasses
from pathlib import Path

from offline_prog.errors import InputError
from offline_prog.process.protocol import required_key
from offline_prog.process.registry import MODELS

# ``process:``: the model's name and one optional section per model (its keys).
ProcessConfig = dataclasses.make_dataclass(
    "ProcessConfig",
    [
        ("model", str, required_key()),  # one of MODELS
        *((name, model.Keys | None, None) for name, model in MODELS.items()),
    ],
)
ProcessConfig.__module__ = __name__  # found here when a cell is pickled (a forked worker)


def check_process(file: Path, process: ProcessConfig | None, flow) -> None:
    """The model named, its section given, and its keys checked by the model.

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
    model = MODELS[process.model]
    keys = getattr(process, model.name)
    if keys is None:
        key = f"process.{model.name}"
        raise InputError(file, key, f"missing: process.model {model.name} needs its section")
    model.check_keys(file, keys, flow)
