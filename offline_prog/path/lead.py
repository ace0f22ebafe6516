"""A seam's flying entry and exit: its flange path run on past both ends.

A seam planned rest to rest stops at its start and its end with the gun open there.
For a flying entry the time law runs a longer path, the seam with a lead-in before
σ = 0 and a lead-out after σ = L, so that it crosses both ends at the process speed;
the approach and retract then start and end at rest at the leads' far ends.

A lead continues the flange path X_IE(s) past an end s_e (u = s − s_e: negative on
the lead-in, positive on the lead-out) by its second-order expansion, with the tool
lifted off the part along the end frame's normal:

    p_IE(u) = p_e + u·p′_e + ½u²·p″_e + h(u)·e,        h(u) = H·|u/δ|³,
    R_IE(u) = Exp(u·w_e + ½u²·w′_e) · R_e,

with e = R_IP·n (the direction the part moves in I when the tool backs off the
surface along −n, as ``job.approach`` moves it), δ the lead's length and H =
LIFT_RATIO·δ. Position, velocity and acceleration of the flange and its angular
velocity and its rate are continuous at the end (the joints' q, q̇ and q̈ too), and the
lift starts with zero slope and curvature, so the first and last millimetres of a lead
(where the gun opens and closes) lie on the seam's tangent. The lead's parameter is
the seam's s continued (the tool's path length up to O(u²κ²)); the TCP speed
the plan reports is the exact rigid-body one.

The wrapped path is evaluated on the seam's own σ (negative on the lead-in, beyond L
on the lead-out), so a reader that asks for σ ∈ [0, L] gets the seam's samples bit for
bit; with both leads 0 (``entry: rest``) the wrapper changes nothing.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.path.fixed_tcp import FlangeSamples

# The lift at a lead's far end, a share of its length: the approach and retract along
# the normal are shorter by it (``job.approach``); near the seam the lift is tiny (at a
# tenth of the lead from the end, LIFT_RATIO/1000 of its length).
LIFT_RATIO = 1.0
# Step of the central difference that gives the lead's dw_s (the derivative of the
# closed-form angular velocity per metre) [m].
ROTATION_RATE_STEP_M = 1e-5


def _skew(a: np.ndarray) -> np.ndarray:
    """(N, 3, 3) skew matrices of (N, 3) vectors."""
    z = np.zeros(len(a))
    return np.stack(
        [
            np.stack([z, -a[:, 2], a[:, 1]], axis=1),
            np.stack([a[:, 2], z, -a[:, 0]], axis=1),
            np.stack([-a[:, 1], a[:, 0], z], axis=1),
        ],
        axis=1,
    )


def _exp_and_left_jacobian(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(Exp(a), J_l(a)) (N, 3, 3) of rotation vectors a (N, 3) [rad]: Rodrigues' formula
    and SO(3)'s left Jacobian (d Exp(a) = [J_l(a)·da]× Exp(a)), by series near 0."""
    theta = np.linalg.norm(a, axis=1)
    small = theta < 1e-6
    t = np.where(small, 1.0, theta)
    t2 = t * t
    s1 = np.where(small, 1.0 - theta**2 / 6.0, np.sin(t) / t)  # sin θ / θ
    c1 = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(t)) / t2)  # (1 − cos θ)/θ²
    d1 = np.where(small, 1.0 / 6.0 - theta**2 / 120.0, (t - np.sin(t)) / (t2 * t))
    K = _skew(a)
    K2 = K @ K
    eye = np.eye(3)
    R = eye + s1[:, None, None] * K + c1[:, None, None] * K2
    J = eye + c1[:, None, None] * K + d1[:, None, None] * K2
    return R, J


@dataclasses.dataclass(frozen=True)
class _End:
    """The flange path at one end: s_e [m], its samples there and the lead's lift."""

    s: float
    samples: FlangeSamples
    length: float  # δ [m]
    e_I: np.ndarray  # (3,) the lift's direction in I


class LeadPath:
    """A flange path (``FlangePath`` or ``SmoothedFlangePath``) with a lead-in of
    ``lead_in_m`` before σ = 0 and a lead-out of ``lead_out_m`` after σ = L (module
    docstring); its domain is [−lead_in_m, L + lead_out_m].

    Args:
        inner: the seam's flange path over [0, L].
        lead_in_m, lead_out_m: the leads' lengths δ [m] (0: that end at rest).
        reason: why the seam starts and ends at rest ("" when flying), for report.json.
    """

    def __init__(self, inner, *, lead_in_m: float, lead_out_m: float, reason: str = ""):
        self.inner = inner
        self.lead_in_m, self.lead_out_m = float(lead_in_m), float(lead_out_m)
        self.reason = reason
        seam_length = inner.length
        self._ends = [
            self._end(0.0, self.lead_in_m),
            self._end(seam_length, self.lead_out_m),
        ]

    def _end(self, s: float, length: float) -> _End:
        f = self.inner(np.array([s]))
        R_PE = self.inner.X_PE.rotation().matrix()
        R_IP = f.R_IE[0] @ R_PE.T
        return _End(s, f, length, R_IP @ f.R_PF[0][:, 1])

    def __getattr__(self, name: str):  # X_IT, X_PE, path, normal, exact, tool_turn, …
        if name.startswith("__") or name == "inner":
            raise AttributeError(name)
        return getattr(self.__dict__["inner"], name)

    @property
    def flying(self) -> bool:
        """Whether either end is run flying (a lead longer than 0)."""
        return self.lead_in_m > 0.0 or self.lead_out_m > 0.0

    @property
    def lifts_m(self) -> tuple[float, float]:
        """(the lead-in's, the lead-out's) lift off the part at its far end [m]."""
        return LIFT_RATIO * self.lead_in_m, LIFT_RATIO * self.lead_out_m

    @property
    def seam_length(self) -> float:
        """L: the seam's own path length [m]."""
        return self.inner.length

    @property
    def start(self) -> float:
        """The domain's first σ, −lead_in_m [m]: the time law's σ = 0 is the seam's
        σ = start."""
        return -self.lead_in_m

    @property
    def end(self) -> float:
        """The domain's last σ, L + lead_out_m [m]."""
        return self.inner.length + self.lead_out_m

    @property
    def length(self) -> float:
        """The time law's path length, lead-in + L + lead-out [m]."""
        return self.end - self.start

    def __call__(self, s: np.ndarray) -> FlangeSamples:
        """The flange path at the seam's σ (N,) [m] (within [start, end])."""
        s = np.asarray(s, dtype=float)
        L = self.inner.length
        before, after = s < 0.0, s > L
        if not (before.any() or after.any()):
            return self.inner(s)
        inside = ~(before | after)
        parts = [(self.inner(s[inside]) if inside.any() else None, inside)]
        for end, mask in ((self._ends[0], before), (self._ends[1], after)):
            if mask.any():
                parts.append((self._lead(end, s[mask]), mask))
        fields = {}
        for field in dataclasses.fields(FlangeSamples):
            first = getattr(parts[-1][0], field.name)
            out = np.empty((len(s), *first.shape[1:]))
            for samples, mask in parts:
                if samples is not None:
                    out[mask] = getattr(samples, field.name)
            fields[field.name] = out
        return FlangeSamples(**fields)

    def poses(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(p_IE (N, 3) [m], R_IE (N, 3, 3)) at σ (N,)."""
        f = self(s)
        return f.p_IE, f.R_IE

    def _rotation(self, end: _End, u: np.ndarray):
        """(R_IE (N, 3, 3), w_s (N, 3) [rad/m]) on a lead at u (N,) from the end."""
        f = end.samples
        w, dw = f.w_s[0], f.dw_s[0]
        a = u[:, None] * w + 0.5 * (u**2)[:, None] * dw
        da = w + u[:, None] * dw
        Exp, J = _exp_and_left_jacobian(a)
        return Exp @ f.R_IE[0], np.einsum("nij,nj->ni", J, da)

    def _lead(self, end: _End, s: np.ndarray) -> FlangeSamples:
        """The lead's samples at σ (N,) beyond its end (module docstring)."""
        if end.length <= 0.0:
            raise ValueError(f"σ = {s[0]:.6g} m is beyond the path's end (no lead there)")
        f = end.samples
        u = s - end.s
        x = u / end.length
        H = LIFT_RATIO * end.length
        h = H * np.abs(x) ** 3
        dh = 3.0 * H * x * np.abs(x) / end.length
        ddh = 6.0 * H * np.abs(x) / end.length**2
        p0, dp0, ddp0 = f.p_IE[0], f.dp_IE[0], f.ddp_IE[0]
        p_IE = p0 + u[:, None] * dp0 + 0.5 * (u**2)[:, None] * ddp0 + h[:, None] * end.e_I
        dp_IE = dp0 + u[:, None] * ddp0 + dh[:, None] * end.e_I
        ddp_IE = ddp0 + ddh[:, None] * end.e_I
        R_IE, w_s = self._rotation(end, u)
        step = ROTATION_RATE_STEP_M
        dw_s = (self._rotation(end, u + step)[1] - self._rotation(end, u - step)[1]) / (2 * step)
        # The tool point T and the tool-fixed process frame in P (X_PT = X_PE·X_EI·X_IT).
        X_PE = self.inner.X_PE
        R_PE, p_PE = X_PE.rotation().matrix(), X_PE.translation()
        R_PI = R_PE @ np.swapaxes(R_IE, 1, 2)
        p_IT = self.inner.X_IT.translation()
        p_PF = p_PE + np.einsum("nij,nj->ni", R_PI, p_IT - p_IE)
        R_PF = R_PI @ (f.R_IE[0] @ R_PE.T @ f.R_PF[0])
        return FlangeSamples(s, p_PF, R_PF, p_IE, dp_IE, ddp_IE, R_IE, w_s, dw_s)


def unwrapped(flange):
    """The seam's flange path under a :class:`LeadPath` (``flange`` itself otherwise)."""
    return flange.inner if isinstance(flange, LeadPath) else flange


def path_ends(flange) -> tuple[float, float]:
    """(first σ, last σ) [m] a flange path is run over: a LeadPath's leads included."""
    if isinstance(flange, LeadPath):
        return flange.start, flange.end
    return 0.0, flange.length
