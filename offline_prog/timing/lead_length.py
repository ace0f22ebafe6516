"""Whether a seam runs flying, and how long its lead-in and lead-out are (``path.lead``).

The time law runs the seam with its leads rest to rest, so a lead must hold the
law's ramp from rest to the process speed v, with room to spare: the time-optimal
law (TOPP-RA, its jerk stage, its averaged profile) ramps faster than the sin² law
(on the sealing demo 27 mm against 36 mm), so the ramp is the sin² law's distance to v
under the seam's caps times RAMP_MARGIN. On the
lead-in the gun is switched before the seam's start (``lead_mm`` and the valve's
``delay_s`` at v) and the flow command leads by the dispenser's lag: that stretch
must already run at v, so it is added; likewise before the end for the lead-out.

Where the seam's approach (retract) runs at the process speed, the default, a lead
may take that move over where that is the shorter run (``_taken_over``): the tool
comes onto the seam along one curve, with no stop at the move's foot. A flying seam
that stops at its lead's far end has as many ramps as one at rest and a longer path,
so the take-over is what lets it be no slower: a normal move's lead lifts by the
move's distance and turns onto the seam as sharply as the tool's path limits allow
(on the 8 mm/s weld almost straight down: 2.3 mm along the tangent for a 50 mm lift),
a tangent move's lead runs the move's distance along the tangent.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.optimize import brentq

from offline_prog.config.cell import Cell
from offline_prog.config.process_speed import approach_speed
from offline_prog.path.lead import (
    LIFT_POWER,
    LIFT_RATIO,
    MAX_LIFT_RATIO,
    LeadPath,
    lead_shape,
    unit_length,
    unwrapped,
)
from offline_prog.process.registry import process_model
from offline_prog.process.timing_bound import ProcessCaps
from offline_prog.timing.time_law import sin2_time_law

RAMP_MARGIN = 1.2  # the lead's ramp room, a share of the sin² law's ramp
RAMP_SAMPLES = 4001  # time samples of the ramp that find where it reaches v
# A lead that takes a normal move over holds the nozzle within this of its working
# height where the valve is open before the seam [m].
AT_HEIGHT_TOL_M = 1e-4
BEND_SAMPLES = 4001  # samples of x ∈ [0, 1] that find a lift's largest curvature


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
    # The turn onto the seam changes the tool's heading, not its speed (nor the flow):
    # it keeps to the robot's path limits, not the process model's caps.
    turn = {"a_max": motion.max_acceleration, "j_max": motion.max_jerk}
    return _taken_over(inputs, flange, length, ramp, **turn)


def _taken_over(
    inputs, flange, length: float, ramp: float, *, a_max: float, j_max: float
) -> LeadPath:
    """The default leads of ``flange`` (a ``motion.lead_mm`` keeps its length and own
    lift), each ``length`` long or taking its move over; the leads compared are the
    ones run (``LeadPath.joined``: their tables built once). A lead
    takes the approach (retract) over where the move runs at the process speed (the
    default ``motion.approach_speed``) and that is the shorter run: the tool then comes
    onto the seam along one curve instead of stopping at the move's foot. A normal move
    of distance D (``Inputs.normal_moves_m``) is taken over by a lead lifting by D that
    turns onto the seam as sharply as the tool's acceleration allows
    (:func:`takeover_extent_m`), a tangent one (``Inputs.tangent_moves_m``) by a lead
    whose extent along the tangent is D (``job.approach`` drops the move a lead's
    extent covers, and shortens it by that extent otherwise). A lead's asked length is
    that of a plain lead of its extent (``path.lead.lead_shape``), at least ``length``.
    Both runs start from rest, so they compare as path lengths, the leads' as built (the
    seam's curvature and turn included), with a ramp counted as ``ramp`` [m] (the time
    a ramp loses at v is ramp/v): the lead taken over with one ramp, against the plain
    lead, the move's rest and its stop and start (two more ramps)."""
    v = inputs.speed.v_m_s
    normal, tangent = inputs.normal_moves_m, inputs.tangent_moves_m
    if not any(normal + tangent) or not np.isclose(
        approach_speed(inputs.cell, inputs.speed).v_m_s, v, rtol=1e-12
    ):
        return LeadPath(flange, lead_in_m=length, lead_out_m=length)
    at_height = _at_height_m(inputs.cell)
    extents = [
        takeover_extent_m(d, v=v, a_max=a_max, j_max=j_max, at_height_m=at_height) if d > 0.0 else t
        for d, t in zip(normal, tangent, strict=True)
    ]
    asked = [max(length, unit_length(LIFT_RATIO) * extent) for extent in extents]
    kept = LeadPath(flange, lead_in_m=length, lead_out_m=length)
    taken = LeadPath(flange, lead_in_m=asked[0], lead_out_m=asked[1], lifts_m=normal)
    kept_extent = lead_shape(length)[0]
    take = []
    for i, taken_m, kept_m in zip(
        (0, 1), (taken.lead_in_m, taken.lead_out_m), (kept.lead_in_m, kept.lead_out_m), strict=True
    ):
        rest = normal[i] - kept.lifts_m[i] if normal[i] > 0.0 else tangent[i] - kept_extent
        take.append(rest > 0.0 and taken_m + ramp < kept_m + rest + 3.0 * ramp)
    return LeadPath.joined(*(taken if take[i] else kept for i in (0, 1)))


@functools.lru_cache(maxsize=256)
def takeover_extent_m(
    lift: float, *, v: float, a_max: float, j_max: float, at_height_m: float
) -> float:
    """The extent δ along the tangent [m] of a lead that lifts by ``lift`` [m] to take a
    normal move over: the sharpest turn, H/δ up to MAX_LIFT_RATIO, whose centripetal
    acceleration v²·κ and its rate v³·dκ/ds at v [m/s] stay within a_max [m/s²] and
    j_max [m/s³] (the lift h = H·|u/δ|⁴ on a straight seam bends at most c₁(H/δ)/δ, its
    bend changing by at most c₂(H/δ)/δ² per metre: :func:`_bend`), and at least as long
    as the nozzle needs to be within AT_HEIGHT_TOL_M of its working height over the
    last ``at_height_m`` before the seam (where the valve is open: H·(x/δ)⁴ at x)
    (kept per arguments: a job's seams ask with the same few)."""
    if lift <= 0.0:
        return 0.0

    def excess(ratio: float) -> float:  # the turn's acceleration or jerk over its cap, − 1
        bend, rate = _bend(ratio)
        extent = lift / ratio
        return max(v**2 * bend / extent / a_max, v**3 * rate / extent**2 / j_max) - 1.0

    if excess(MAX_LIFT_RATIO) <= 0.0:
        ratio = MAX_LIFT_RATIO
    elif excess(LIFT_RATIO) >= 0.0:
        ratio = LIFT_RATIO
    else:  # the excess grows with the ratio: the sharpest turn within both caps
        ratio = brentq(excess, LIFT_RATIO, MAX_LIFT_RATIO, xtol=1e-6)
    height = at_height_m * (lift / AT_HEIGHT_TOL_M) ** (1.0 / LIFT_POWER)
    return max(lift / ratio, height)


@functools.lru_cache(maxsize=1024)
def _bend(ratio: float) -> tuple[float, float]:
    """(c₁, c₂) of the lift h = r·δ·x⁴, x ∈ [0, 1], over a straight seam: the largest
    curvature times δ and the largest rate of curvature per arc length times δ² (kept
    per ratio)."""
    x = np.linspace(0.0, 1.0, BEND_SAMPLES)
    n = LIFT_POWER
    slope = n * ratio * x ** (n - 1)
    bend = n * (n - 1) * ratio * x ** (n - 2) / (1.0 + slope**2) ** 1.5
    arc = np.sqrt(1.0 + slope**2)  # ds/dx per extent
    return float(bend.max()), float(np.abs(np.gradient(bend, x) / arc).max())


def _switches(cell: Cell) -> list:
    """The process switches of ``tool.process_io`` (on, off) the cell sets."""
    io = cell.tool.process_io
    return [s for s in (io.on, io.off) if s is not None] if io else []


def _at_height_m(cell: Cell) -> float:
    """How far from a seam end its valve is open off the seam [m]: the switches'
    ``lead_mm`` (their ``delay_s`` moves the command, not the valve)."""
    return max([abs(s.lead_mm) * 1e-3 for s in _switches(cell)] + [0.0])


def _switch_m(cell: Cell, v: float) -> float:
    """How far before a seam end its switches act, run at v [m]: the largest of the
    switches' ``lead_mm`` + ``delay_s``·v, plus the dispenser's lag at v (the flow's
    command leads the speed by it; it goes live earlier still, ``job.process_io``, while
    the tool may still ramp: the command follows the speed)."""
    io = cell.tool.process_io
    ahead = max([s.lead_mm * 1e-3 + s.delay_s * v for s in _switches(cell)] + [0.0])
    model = process_model(cell.process)
    lag = max(io.flow.lag_s if io and io.flow else 0.0, model.output_lag_s if model else 0.0)
    return ahead + lag * v


def lead_failure(reason: str) -> str:
    """Why a seam runs at rest where no IK branch or joint timing runs its leads:
    ``reason``, the failure's on them (``stages.plan_motion``, ``job.untimed``)."""
    return f"the lead-in or lead-out: {reason}"


def slowed_end(flange: LeadPath, reductions, v: float) -> str:
    """Why a flying seam's leads miss their purpose, "" where they do not: the joints'
    speed ``reductions`` ((σ_start, σ_end, speed) [m, m, m/s] on the law's σ, 0 at the
    lead-in's start: ``PathTiming.reductions``) hold a seam end that a lead meets below
    the process speed v [m/s], so the tool crosses it slowed and runs its leads slowed
    too (on a 15 mm circle the wrist's jerk held a whole seam at 1 % of v). Such a seam
    is planned with the leads' fallbacks (:func:`fallbacks`): at rest its ends cost a
    ramp at the speed the joints allow, not a lead at it."""
    held = held_ends(flange, reductions)
    if not held:
        return ""
    name, speed = held[0]
    share = 100.0 * speed / v
    return lead_failure(
        f"the joint limits hold the seam's {name} at {share:.0f} % of the process speed"
    )


def held_ends(flange: LeadPath, reductions) -> list[tuple[str, float]]:
    """The led seam ends that the joints' speed ``reductions`` (as for
    :func:`slowed_end`) hold: ("start" or "end", the reduction's speed [m/s]) in the
    reductions' order."""
    ends = (
        ("start", flange.lead_in_m, flange.lead_in_m > 0.0),
        ("end", flange.lead_in_m + flange.inner.length, flange.lead_out_m > 0.0),
    )
    return [
        (name, speed)
        for a, b, speed in reductions
        for name, at, led in ends
        if led and a <= at <= b
    ]


def at_rest(flange: LeadPath, reason: str) -> LeadPath:
    """``flange`` with both ends at rest, for ``reason`` (a lead that cannot be run)."""
    return LeadPath(unwrapped(flange), lead_in_m=0.0, lead_out_m=0.0, reason=reason)


def fallbacks(flange: LeadPath, reason: str) -> list[LeadPath]:
    """What a flying seam whose leads cannot be run tries next, in order: leads with
    their own lift (where they took a normal move over, ``_taken_over``), then both ends
    at rest for ``reason``."""
    rest = at_rest(flange, reason)
    if not any(flange.asked["lifts_m"]):
        return [rest]
    return [LeadPath(unwrapped(flange), **(flange.asked | {"lifts_m": (0.0, 0.0)})), rest]
