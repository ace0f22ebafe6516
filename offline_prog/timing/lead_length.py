"""Whether a seam runs flying, and how long its lead-in and lead-out are (``path.lead``).

The time law runs the seam with its leads rest to rest, so a lead must hold the
law's ramp from rest to the process speed v, with room to spare: the time-optimal
law (TOPP-RA, its jerk stage, its averaged profile) ramps faster than the sin² law
(on the sealing demo 27 mm against 36 mm), so the ramp is the sin² law's distance to v
under the seam's caps times RAMP_MARGIN. On the
lead-in the gun is switched before the seam's start (``lead_mm`` and the valve's
``delay_s`` at v) and the flow command leads by the dispenser's lag: that stretch
must already run at v, so it is added; likewise before the end for the lead-out.

Where the seam's normal approach (retract) runs at the process speed, the default, a
lead may take that move over: it lifts by the move's distance (``path.lead``) and the
tool comes down onto the seam along one curve, with no stop at the move's foot; it
does where that is the shorter run (``_lifts_m``): on the sealing demo, not on the
8 mm/s weld, whose ramps are too short for a stop to cost much.
"""

from __future__ import annotations

import functools

import numpy as np

from offline_prog.config.cell import Cell
from offline_prog.config.process_speed import approach_speed
from offline_prog.path.lead import LeadPath, lead_shape, unwrapped
from offline_prog.process.registry import process_model
from offline_prog.process.timing_bound import ProcessCaps
from offline_prog.timing.time_law import sin2_time_law

RAMP_MARGIN = 1.2  # the lead's ramp room, a share of the sin² law's ramp
RAMP_SAMPLES = 4001  # time samples of the ramp that find where it reaches v


@functools.lru_cache(maxsize=256)
def ramp_length_m(v: float, *, a_max: float, j_max: float) -> float:
    """The sin² law's distance from rest to the speed v [m] under a_max, j_max
    [m/s², m/s³] (kept per (v, a_max, j_max): every option of a job's seams asks)."""
    long = sin2_time_law(1e3 * v, v_max=v, a_max=a_max, j_max=j_max)
    ramp_s = 10.0 * (v / a_max + a_max / j_max + np.sqrt(v / j_max))  # ample
    t = np.linspace(0.0, min(long.duration, ramp_s), RAMP_SAMPLES)
    sigma, speed = long(t)[:2]
    reached = np.flatnonzero(speed >= v * (1.0 - 1e-9))
    return float(sigma[reached[0]] if len(reached) else sigma[-1])


def with_leads(inputs, flange, caps: ProcessCaps, decided: LeadPath | None) -> LeadPath:
    """The flange path as timed (``inputs``: the seam's ``stages.Inputs``): with a
    lead-in and lead-out (``path.lead``) for ``entry: flying``, with leads of 0 and the
    reason otherwise. ``decided``: a path whose
    entry was decided before (a forced rest stays at rest)."""
    if decided is not None:
        return decided.around(flange)
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
    v = inputs.speed.v_m_s
    ramp = ramp_length_m(v, a_max=caps.a_max, j_max=caps.j_max)
    if motion.lead_mm is not None:  # the user's length: the leads keep it
        length = motion.lead_mm * 1e-3
        return LeadPath(flange, lead_in_m=length, lead_out_m=length)
    length = RAMP_MARGIN * ramp + _switch_m(cell, v)
    lifts = _lifts_m(inputs, length, ramp)
    return LeadPath(flange, lead_in_m=length, lead_out_m=length, lifts_m=lifts)


def _lifts_m(inputs, length: float, ramp: float) -> tuple[float, float]:
    """The least lifts of the default leads [m] (a ``motion.lead_mm`` keeps its length
    and own lift): a normal approach's (retract's) distance (``Inputs.normal_moves_m``)
    where the lead takes that move over, 0 where not. It does where the move runs at
    the process speed (the default ``motion.approach_speed``) and the one longer lead
    is shorter than the lead, the rest of the straight move and its stop (two ramps of
    ``ramp`` [m]) run at that speed: the tool then comes down onto the seam along one
    curve."""
    v = inputs.speed.v_m_s
    if not np.isclose(approach_speed(inputs.cell, inputs.speed).v_m_s, v, rtol=1e-12):
        return 0.0, 0.0
    _, plain_lift, plain = lead_shape(length)
    lifts = []
    for distance in inputs.normal_moves_m:
        taken = lead_shape(length, distance)[2]
        shorter = taken < plain + (distance - plain_lift) + 2.0 * ramp
        lifts.append(distance if distance > plain_lift and shorter else 0.0)
    return lifts[0], lifts[1]


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


def lead_failure(reason: str) -> str:
    """Why a seam runs at rest where no IK branch or joint timing runs its leads:
    ``reason``, the failure's on them (``stages.plan_motion``, ``job.untimed``)."""
    return f"the lead-in or lead-out: {reason}"


def at_rest(flange: LeadPath, reason: str) -> LeadPath:
    """``flange`` with both ends at rest, for ``reason`` (a lead that cannot be run)."""
    return LeadPath(unwrapped(flange), lead_in_m=0.0, lead_out_m=0.0, reason=reason)


def fallbacks(flange: LeadPath, reason: str) -> list[LeadPath]:
    """What a flying seam whose leads cannot be run tries next, in order: leads with
    their own lift (where they took a normal move over, ``_lifts_m``), then both ends
    at rest for ``reason``."""
    rest = at_rest(flange, reason)
    if not any(flange.asked["lifts_m"]):
        return [rest]
    return [LeadPath(unwrapped(flange), **(flange.asked | {"lifts_m": (0.0, 0.0)})), rest]
