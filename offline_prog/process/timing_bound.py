"""What a process model asks of the time law on its process stretch (issue 28's
feedback): the speeds at which the output can hold the target, and the path jerk the
dispenser can follow.

**Speed band.** A model's ``speed_band(u_min, u_max)`` is the TCP speeds at which the
target is reachable with its output within its limits (the bead's flow, the tape
heater's power; the arc's fixed U·I for heat input). A seam's process speed outside it
cannot be held by any output: the model's ``speed_band_reason`` says why, with the
figures, and the cell is refused (``job.speed_band``). The process speed is the time
law's cap, so a speed within the band is never exceeded; a minimum speed is not
something a time law can impose against a joint limit (the joints slow the path where
they must), so a slowdown below the band's low end is reported
(``results.timing_bound``), not planned away.

**The dispenser's jerk.** The flow Q = k·y follows its command u through the lag
τ·y' + y = u, and the command leads the speed by τ, u(t) = (A*/k)·v(t + τ)
(``BeadModel.speed_output``). In Laplace terms the flow relative to what the
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

(``BeadModel.jerk_cap``), which :func:`process_caps` feeds into the time law of the
process stretch (and only there: approach, retract and links keep the user's caps) where it is below
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

from offline_prog.process.protocol import ProcessModel


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


def process_caps(
    model: ProcessModel | None, *, v_process: float, a_max: float, j_max: float
) -> ProcessCaps:
    """The user's caps, lowered where the model needs it (``model.jerk_cap``: a bead
    with a lag caps the path jerk at J_bead = 2·t·v_p/τ²); a model without dynamics
    (heat input, tape heating: the heater follows at once) and no model keep them."""
    if model is not None:
        cap, reason = model.jerk_cap(v_process)
        if cap < j_max:
            return ProcessCaps(a_max, cap, a_max, j_max, reason)
    return ProcessCaps(a_max, j_max, a_max, j_max)
