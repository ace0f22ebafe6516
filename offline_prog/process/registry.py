"""The process models a cell may name, and the one factory.

``process.model`` names one of :data:`MODELS`; its section ``process.<name>`` holds
that model's keys (``Keys``), checked by the model itself
(:meth:`~offline_prog.process.protocol.ProcessModel.check_keys`). A new model is a
module that keeps the protocol (``process.protocol``) and its line here.
"""

from __future__ import annotations

from offline_prog.process.bead import BeadModel
from offline_prog.process.heat_input import HeatInputModel
from offline_prog.process.protocol import ProcessModel
from offline_prog.process.tape_heating import TapeHeatingModel

MODELS: dict[str, type[ProcessModel]] = {
    model.name: model for model in (BeadModel, HeatInputModel, TapeHeatingModel)
}


def process_model(process) -> ProcessModel | None:
    """The model of a checked ``process:`` (``config.process_keys.check_process``) in SI
    units, or None (no ``process:``)."""
    if process is None:
        return None
    model = MODELS[process.model]
    return model.from_keys(getattr(process, model.name))
