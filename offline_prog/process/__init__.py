"""What the part gets along the path (the paper's outlook: process quality from a model
of the process): the bead's cross-section, the weld's heat input, the tape's nip
temperature, each predicted from the planned speed and the outputs as the programs set
them. Every model keeps one protocol (``protocol.ProcessModel``: its cell keys and their
bounds, the quality column, the band, the output schedule, the timing bound);
``registry.MODELS`` lists them and ``registry.process_model(process)`` is the one
factory."""

import numpy as np

from offline_prog.constants import STANDSTILL_SPEED_M_S


def per_metre(rate: np.ndarray, v_tcp: np.ndarray) -> np.ndarray:
    """(N,) what the part gets per metre of path: ``rate`` (N,) per second (a flow
    [m³/s], an arc's or heater's absorbed power [W]) over the TCP speed v_tcp (N,)
    [m/s]; NaN where the tool stands (v below ``STANDSTILL_SPEED_M_S``)."""
    v = np.asarray(v_tcp, float)
    moving = v >= STANDSTILL_SPEED_M_S
    return np.where(moving, np.asarray(rate, float) / np.where(moving, v, 1.0), np.nan)
