"""Whether a seam runs flying, and how long its lead-in and lead-out are (``path.lead``).

The time law runs the seam with its leads rest to rest, so a lead must hold the
law's ramp from rest to the process speed v, with room to spare: the time-optimal
law (TOPP-RA, its jerk stage, its averaged profile) ramps faster than the sin² law
(on the sealing demo 27 mm against 36 mm), so the ramp is the sin² law's distance to v
under the seam's caps times RAMP_MARGIN. On the
lead-in the gun is switched before the seam's start (``lead_mm`` and the valve's
``delay_s`` at v) and the flow command leads by the dispenser's lag: that stretch
must already run at v, so it is added; likewise before the end for the lead-out.
"""

from __future__ import annotations

import numpy as np

from offline_prog.config.cell import Cell
from offline_prog.path.lead import LeadPath, unwrapped
from offline_prog.process.registry import process_model
from offline_prog.process.timing_bound import ProcessCaps
from offline_prog.timing.time_law import sin2_time_law

RAMP_MARGIN = 1.2  # the lead's ramp room, a share of the sin² law's ramp
RAMP_SAMPLES = 4001  # time samples of the ramp that find where it reaches v


def ramp_length_m(v: float, *, a_max: float, j_max: float) -> float:
    """The sin² law's distance from rest to the speed v [m] under a_max, j_max
    [m/s², m/s³]."""
    long = sin2_time_law(1e3 * v, v_max=v, a_max=a_max, j_max=j_max)
    ramp_s = 10.0 * (v / a_max + a_max / j_max + np.sqrt(v / j_max))  # ample
    t = np.linspace(0.0, min(long.duration, ramp_s), RAMP_SAMPLES)
    sigma, speed = long(t)[:2]
    reached = np.flatnonzero(speed >= v * (1.0 - 1e-9))
    return float(sigma[reached[0]] if len(reached) else sigma[-1])


def lead_length_m(v: float, *, a_max: float, j_max: float, switch_m: float) -> float:
    """A lead's length [m]: the ramp to v with its margin, plus ``switch_m`` [m] (the
    stretch before a seam end that is run at v for its switches)."""
    return RAMP_MARGIN * ramp_length_m(v, a_max=a_max, j_max=j_max) + switch_m


def with_leads(inputs, flange, caps: ProcessCaps, decided: LeadPath | None) -> LeadPath:
    """The flange path as timed (``inputs``: the seam's ``stages.Inputs``): with a
    lead-in and lead-out (``path.lead``) for ``entry: flying``, with leads of 0 and the
    reason otherwise. ``decided``: a path whose
    entry was decided before (a forced rest stays at rest)."""
    if decided is not None:
        lead_in, lead_out = decided.lead_in_m, decided.lead_out_m
        return LeadPath(flange, lead_in_m=lead_in, lead_out_m=lead_out, reason=decided.reason)
    cell, motion = inputs.cell, inputs.cell.motion
    rest = ""
    if cell.path.entry == "rest":
        rest = "entry: rest"
    elif motion.lead_mm == 0.0:
        rest = "motion.lead_mm: 0"
    elif motion.speed_reference != "tcp":
        rest = "speed_reference flange (the leads run on the tool's path)"
    if rest:
        return LeadPath(flange, lead_in_m=0.0, lead_out_m=0.0, reason=rest)
    if motion.lead_mm is not None:
        length = motion.lead_mm * 1e-3
    else:
        v = inputs.speed.v_m_s
        length = lead_length_m(v, a_max=caps.a_max, j_max=caps.j_max, switch_m=_switch_m(cell, v))
    return LeadPath(flange, lead_in_m=length, lead_out_m=length)


def _switch_m(cell: Cell, v: float) -> float:
    """How far before a seam end its switches act, run at v [m]: the largest of the
    switches' ``lead_mm`` + ``delay_s``·v, plus the dispenser's lag at v (the flow's
    command leads the speed by it; it goes live earlier still, ``job.process_io``, while
    the tool may still ramp: the command follows the speed)."""
    io = cell.tool.process_io
    switches = [s for s in (io.on, io.off) if s is not None] if io else []
    ahead = max([s.lead_mm * 1e-3 + s.delay_s * v for s in switches] + [0.0])
    model = process_model(cell.process)
    lag = max(io.flow.lag_s if io and io.flow else 0.0, model.output_lag_s if model else 0.0)
    return ahead + lag * v


def at_rest(flange: LeadPath, reason: str) -> LeadPath:
    """``flange`` with both ends at rest, for ``reason`` (a lead that cannot be run)."""
    return LeadPath(unwrapped(flange), lead_in_m=0.0, lead_out_m=0.0, reason=reason)
