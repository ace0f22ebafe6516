"""The one factory of process models: ``process:`` of a cell → a model record in SI units.

A model predicts the quality along the path from the TCP speed and the output as the
programs set it (``predict(t, v_tcp, command)``), names the band the quality must lie
in (``band``, SI; ``column`` and ``unit_scale`` give trajectory.csv's column and its
unit), and says at which TCP speeds the target is reachable with the output within its
limits (``speed_band``). A model with an output (bead: the flow, tape: the heater's
power) sets that output's speed-following law (:func:`speed_output`).
"""

from __future__ import annotations

from offline_prog.config.process_keys import ProcessConfig
from offline_prog.process.bead import BeadModel
from offline_prog.process.heat_input import HeatInputModel
from offline_prog.process.tape_heating import TapeHeatingModel

ProcessModel = BeadModel | HeatInputModel | TapeHeatingModel


def process_model(process: ProcessConfig | None) -> ProcessModel | None:
    """The model of a checked ``process:`` (config.process_keys.check_process), or None."""
    if process is None:
        return None
    if process.model == "bead":
        bead = process.bead
        return BeadModel(
            area_m2=bead.area_mm2 * 1e-6,
            tolerance=bead.tolerance_pct / 100.0,
            flow_m3_s_per_unit=bead.flow_mm3_s_per_unit * 1e-9,
            lag_s=bead.lag_s,
        )
    if process.model == "heat_input":
        weld = process.heat_input
        low, high = weld.target_kj_mm
        return HeatInputModel(
            arc_power_w=weld.efficiency * weld.voltage_v * weld.current_a,
            band_j_m=(low * 1e6, high * 1e6),
        )
    tape = process.tape_heating
    capacity = (
        tape.density_kg_m3
        * tape.specific_heat_j_kg_k
        * tape.width_mm
        * 1e-3
        * tape.thickness_mm
        * 1e-3
    )
    return TapeHeatingModel(
        heat_capacity_j_k_m=capacity,
        absorbed_fraction=tape.absorbed_fraction,
        ambient_c=tape.ambient_c,
        band_c=(tape.target_c[0], tape.target_c[1]),
        max_power_w=tape.max_power_w,
        w_per_unit=tape.power_output.w_per_unit,
    )


def speed_output(model: ProcessModel | None, process: ProcessConfig | None) -> dict:
    """The speed-following output the model sets, as ``io_events.ProcessIo`` fields:
    bead: the flow's gain A*/k, no offset, leading by the dispenser's lag; tape: the
    heater's power output, gain ρcwh(T*−T_0)/(η·W per unit), within [0, P_max]; heat
    input: nothing (the arc runs at its set U and I)."""
    if isinstance(model, BeadModel):
        return {"per_mps": model.per_mps, "offset": 0.0, "lag_s": model.lag_s}
    if isinstance(model, TapeHeatingModel):
        return {
            "analog_output": process.tape_heating.power_output.analog_output,
            "per_mps": model.per_mps,
            "offset": 0.0,
            "min": 0.0,
            "max": model.max_command,
            "lag_s": 0.0,
        }
    return {}
