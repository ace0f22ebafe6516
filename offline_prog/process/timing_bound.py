"""What a process model asks of the time law on its process stretch (issue 28's
feedback): the speeds at which the output can hold the target, and the path jerk the
dispenser can follow.

**Speed band.** A model's ``speed_band(u_min, u_max)`` is the TCP speeds at which the
target is reachable with its output within its limits (the bead's flow, the tape
heater's power; the arc's fixed U·I for heat input). A seam's process speed outside it
cannot be held by any output: :func:`speed_band_reason` says why, with the figures,
and the cell is refused. The process speed is the time law's cap, so a speed within the
band is never exceeded; a minimum speed is not something a time law can impose against
a joint limit (the joints slow the path where they must), so a slowdown below the
band's low end is reported (``results.timing_bound``), not planned away.

**The dispenser's jerk.** The flow Q = k·y follows its command u through the lag
τ·y' + y = u, and the command leads the speed by τ, u(t) = (A*/k)·v(t + τ)
(``process.model.speed_output``). In Laplace terms the flow relative to what the
speed needs is the operator

    e^{τs} / (1 + τs) = 1 + τ²s²/2 − τ³s³/3 + …

so the lead cancels the lag exactly for a speed that changes linearly (the s¹ term is
zero: acceleration costs nothing) and leaves, to first order, the residual
τ²·v''/2: the bead's relative error is δA/A* = (y − u_lead)/u_lead ≈ τ²·v''/(2v),
with v'' the path jerk (the time law's σ⃛ for speed_reference tcp). The bound is
exact, not only asymptotic: the error operator is
K(s) = (e^{τs} − 1 − τs) / (s²(1 + τs)) applied to v'', and
(e^{τs} − 1 − τs)/s² is the transform of the ramp w(t) = τ + t on [−τ, 0] (≥ 0), so
K's kernel is that ramp convolved with the lag's impulse response e^{−t/τ}/τ (≥ 0):
a non-negative kernel of integral K(0) = τ²/2. Hence, wherever |v''| ≤ J over the
kernel's reach,

    |δA/A*| ≤ τ²·J / (2·v),

with equality under a jerk held long enough. Holding the bead within its tolerance t
at the process speed v_p asks for the path jerk cap

    J_bead = 2·t·v_p / τ²,

which :func:`process_caps` feeds into the time law of the process stretch (and only
there: approach, retract and links keep the user's caps) where it is below
``motion.max_jerk``; the acceleration needs no cap (the lead cancels it). Where the
speed falls below v_p (the start and stop ramps, a joint slowdown) the same jerk gives
a larger relative error (∝ 1/v): at the ramps from rest no jerk holds the bead
(δA/A* → τ²/t'² a time t' after the start, whatever J), which the quality report
names as the start ramp. With ``motion.speed_reference: flange`` the time law's
parameter is the flange's path, so the cap bounds the flange's jerk, not the TCP's:
the bound is then approximate where the two speeds differ (the path turns).
"""

from __future__ import annotations

import dataclasses
import math

from offline_prog.process.bead import BeadModel
from offline_prog.process.heat_input import HeatInputModel
from offline_prog.process.tape_heating import TapeHeatingModel


@dataclasses.dataclass(frozen=True)
class ProcessCaps:
    """The path caps of a seam's process stretch.

    Attributes:
        a_max, j_max: the caps the time law gets [m/s², m/s³] (≤ the user's).
        user_a_max, user_j_max: ``motion.max_acceleration`` / ``max_jerk`` [m/s², m/s³].
        reason: why the process lowered a cap (None: it did not).
    """

    a_max: float
    j_max: float
    user_a_max: float
    user_j_max: float
    reason: str | None = None

    @property
    def bounded(self) -> bool:
        return self.j_max < self.user_j_max or self.a_max < self.user_a_max


def bead_jerk_cap(model: BeadModel, v_process: float) -> float:
    """J_bead = 2·t·v_p/τ² [m/s³]: the path jerk at which the lead-compensated
    dispenser keeps the bead within its tolerance t at the speed v_p [m/s] (module
    docstring); inf without a lag."""
    if model.lag_s**2 <= 0.0:  # no lag (or one so small its square underflows)
        return math.inf
    return 2.0 * model.tolerance * v_process / model.lag_s**2


def process_caps(model, *, v_process: float, a_max: float, j_max: float) -> ProcessCaps:
    """The user's caps, lowered where the model needs it (a bead with a lag: the jerk
    cap :func:`bead_jerk_cap`); a model without dynamics (heat input, tape heating: the
    heater follows at once) keeps them."""
    if isinstance(model, BeadModel):
        cap = bead_jerk_cap(model, v_process)
        if cap < j_max:
            reason = (
                f"the dispenser's lag {model.lag_s:g} s holds the bead within "
                f"±{100 * model.tolerance:g} % at {v_process:g} m/s up to a path jerk of "
                f"2·tol·v/τ² = {cap:.4g} m/s³"
            )
            return ProcessCaps(a_max, cap, a_max, j_max, reason)
    return ProcessCaps(a_max, j_max, a_max, j_max)


def speed_band_reason(model, v: float, *, u_min: float, u_max: float) -> str | None:
    """Why the process speed v [m/s] cannot hold the model's target with its output in
    [u_min, u_max] (its unit), with the figures; None when it can.

    Args:
        model: a process model (process.model.process_model).
        v: the seam's process speed [m/s].
        u_min, u_max: the output's limits (job.process_io.process_io_settings).
    """
    low, high = model.speed_band(u_min, u_max)
    if isinstance(model, BeadModel):
        what = f"process.bead.area_mm2 {model.area_m2 * 1e6:g} mm²"
        k = model.flow_m3_s_per_unit * 1e9
        if v > high:
            return (
                f"{v:g} m/s is above the {high:.4g} m/s at which the flow output at its max "
                f"{u_max:g} (tool.process_io.flow.max; {k:g} mm³/s per unit) lays {what}"
            )
        if v < low:
            return (
                f"{v:g} m/s is below the {low:.4g} m/s at which the flow output at its min "
                f"{u_min:g} (tool.process_io.flow.min) lays {what}: the bead is too large"
            )
    elif isinstance(model, TapeHeatingModel):
        if v > high:
            return (
                f"{v:g} m/s is above the {high:.4g} m/s at which the heater "
                f"(process.tape_heating.max_power_w {model.max_power_w:g} W) reaches "
                f"target_c's low end {model.band_c[0]:g} °C"
            )
    elif isinstance(model, HeatInputModel):
        h_low, h_high = (x * 1e-6 for x in model.band_j_m)
        if v > high:
            return (
                f"{v:g} m/s is above the {high:.4g} m/s at which the heat input "
                f"k·U·I/v = {model.arc_power_w:g} W / v falls to "
                f"process.heat_input.target_kj_mm's low end {h_low:g} kJ/mm"
            )
        if v < low:
            return (
                f"{v:g} m/s is below the {low:.4g} m/s under which the heat input "
                f"k·U·I/v = {model.arc_power_w:g} W / v exceeds "
                f"process.heat_input.target_kj_mm's high end {h_high:g} kJ/mm"
            )
    return None
