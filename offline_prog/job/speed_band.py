"""Each seam's process speed against its process model's speed band (issue 28): a speed
at which the output cannot hold the target is bad input, refused before planning.

The band is the model's ``speed_band`` with the output's limits as the programs set
them (``job.process_io.process_io_settings``): the bead's flow output within
``tool.process_io.flow.min .. max``, the tape heater within [0, max_power_w], the arc's
fixed heat (no output) for heat input. The speed is each seam's
``config.process_speed.ProcessSpeed``, the same record its time law runs at.
"""

from __future__ import annotations

from offline_prog.config.process_speed import process_speed
from offline_prog.errors import InputError
from offline_prog.job.process_io import process_io_settings
from offline_prog.job.seams import job_seams
from offline_prog.process.registry import process_model
from offline_prog.stages import Inputs


def check_speed_bands(inputs: Inputs) -> None:
    """Every seam's process speed (``seams[k].speed`` or ``motion.speed``) within its
    model's speed band.

    Raises:
        InputError: one line naming the speed's key and why, with the figures.
    """
    cell = inputs.cell
    model = process_model(cell.process)
    if model is None:
        return
    settings = process_io_settings(cell.tool.process_io, model)
    u_min, u_max = (0.0, 0.0) if settings is None else (settings.min, settings.max)
    for k in range(len(job_seams(cell))):
        speed = process_speed(cell, k)
        reason = model.speed_band_reason(speed.v_m_s, u_min=u_min, u_max=u_max)
        if reason is not None:
            raise InputError(inputs.file, speed.key, reason)
