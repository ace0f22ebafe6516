"""A seam's flying entry and exit: its flange path run on past both ends.

A seam planned rest to rest stops at its start and its end with the gun open there.
For a flying entry the time law runs a longer path, the seam with a lead-in before
σ = 0 and a lead-out after σ = L, so that it crosses both ends at the process speed;
the approach and retract then start and end at rest at the leads' far ends.

A lead continues the flange path X_IE(s) past an end s_e by its second-order
expansion in u (negative on the lead-in, positive on the lead-out), with the tool
lifted off the part along the end frame's normal:

    p_IE(u) = p_e + u·p′_e + ½u²·p″_e + h(u)·e,        h(u) = H·|u/δ|⁴,
    R_IE(u) = Exp(u·w_e + ½u²·w′_e) · R_e,

with e = R_IP·n (the direction the part moves in I when the tool backs off the
surface along −n, as ``job.approach`` moves it), δ the lead's extent along the
tangent and H its lift: LIFT_RATIO·δ, or a normal approach's (retract's) distance
when the lead takes that move over (``timing.lead_length``): the tool then comes down
onto the seam at speed along one curve instead of stopping at its foot. The lead is
parameterized by the tool's path length in P, σ − s_e = ±ℓ(u),
ℓ(u) = ∫₀^|u| g, with g = |p′_IE + w_u × (p_IT − p_IE)| the tool point's rigid-body
speed in P per metre of u (X_PT = X_PE·X_EI·X_IT), integrated per end and inverted by
cubic Hermite interpolation; so the time law's cap on σ̇ caps the tool's speed on the
lead as on the seam, and the lead is as long along the tool's path as asked (its
extent scaled to it; :func:`lead_shape` sizes it leaving the seam's curvature out).
With du/dσ = 1/g and d²u/dσ² = −g′/g³ the chain rule gives the σ-derivatives.
Position, velocity and acceleration of the flange and its angular velocity and its
rate are continuous at the end (the joints' q, q̇ and q̈ too), and the lift starts with
zero slope, curvature and jerk: where the gun opens and closes, a few millimetres from
the end, the nozzle is at its working height (5 mm from the end of a 50 mm lift over
25 mm: 0.08 mm off). The TCP speed the plan reports is the exact rigid-body one.

The wrapped path is evaluated on the seam's own σ (negative on the lead-in, beyond L
on the lead-out), so a reader that asks for σ ∈ [0, L] gets the seam's samples bit for
bit; with both leads 0 (``entry: rest``) the wrapper changes nothing.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
from scipy.interpolate import CubicHermiteSpline

from offline_prog.path.fixed_tcp import FlangeSamples

# The least lift at a lead's far end, a share of its extent δ: the approach and retract
# along the normal are shorter by the lift (``job.approach``).
LIFT_RATIO = 1.0
# The lift's power: h = H·|u/δ|⁴ rises with zero slope, curvature and jerk.
LIFT_POWER = 4
# The most lift per extent of a lead that takes over a normal approach or retract: its
# extent grows with the lift beyond it, so it turns onto the seam no sharper than this
# (``timing.lead_length`` asks for a longer extent where the tool's acceleration needs it).
MAX_LIFT_RATIO = 32.0
# Samples of ℓ(u)/δ over u/δ ∈ [0, 1] that invert the lead's arc length (by cubic
# Hermite interpolation with the exact slopes 1/g: u and du/dσ agree to ~1e-11).
ARC_SAMPLES = 2001
# A lead's length along the tool's path matches the asked one within LENGTH_TOL after
# at most LENGTH_ITERATIONS scalings of its extent.
LENGTH_TOL = 1e-9
LENGTH_ITERATIONS = 6
# Step of the central difference that gives the lead's dw_s (the derivative of the
# closed-form angular velocity per metre) [m].
ROTATION_RATE_STEP_M = 1e-5


@functools.lru_cache(maxsize=64)
def unit_length(ratio: float) -> float:
    """ℓ₁(r) = ∫₀¹ √(1 + (4r·x³)²) dx: the length per extent δ of a lead on a straight
    seam lifting r·δ (the trapezoid rule on ARC_SAMPLES points), for sizing leads."""
    x = np.linspace(0.0, 1.0, ARC_SAMPLES)
    g = np.sqrt(1.0 + (LIFT_POWER * ratio * x ** (LIFT_POWER - 1)) ** 2)
    return float(np.sum(0.5 * (g[1:] + g[:-1]) * np.diff(x)))


def _skew(a: np.ndarray) -> np.ndarray:
    """(N, 3, 3) skew matrices of (N, 3) vectors."""
    K = np.zeros((len(a), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -a[:, 2], a[:, 1], -a[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = a[:, 2], -a[:, 1], a[:, 0]
    return K


def _exp_and_left_jacobian(a: np.ndarray, *, exp: int) -> tuple[np.ndarray, np.ndarray]:
    """(Exp(a) (exp, 3, 3) of the first ``exp`` rows, J_l(a) (N, 3, 3)) of rotation
    vectors a (N, 3) [rad]: Rodrigues' formula and SO(3)'s left Jacobian
    (d Exp(a) = [J_l(a)·da]× Exp(a)), by series near 0."""
    theta = np.linalg.norm(a, axis=1)
    small = theta < 1e-6
    t = np.where(small, 1.0, theta)
    t2 = t * t
    c1 = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(t)) / t2)  # (1 − cos θ)/θ²
    d1 = np.where(small, 1.0 / 6.0 - theta**2 / 120.0, (t - np.sin(t)) / (t2 * t))
    K = _skew(a)
    K2 = K @ K
    eye = np.eye(3)
    J = eye + c1[:, None, None] * K + d1[:, None, None] * K2
    small, theta, t = small[:exp], theta[:exp], t[:exp]
    s1 = np.where(small, 1.0 - theta**2 / 6.0, np.sin(t) / t)  # sin θ / θ
    return eye + s1[:, None, None] * K[:exp] + c1[:exp, None, None] * K2[:exp], J


def lead_shape(length_m: float, lift_m: float = 0.0) -> tuple[float, float, float]:
    """(δ, H, λ) [m] of a lead asked to be ``length_m`` long with at least ``lift_m`` of
    lift: its extent along the tangent, δ = max(length/ℓ₁(LIFT_RATIO),
    lift/MAX_LIFT_RATIO); its lift, H = max(LIFT_RATIO·δ, lift); its length along the
    tool's path (the seam's curvature left out), λ = ℓ₁(H/δ)·δ (all 0 for a length of
    0: that end at rest)."""
    if length_m <= 0.0:
        return 0.0, 0.0, 0.0
    extent = max(length_m / unit_length(LIFT_RATIO), lift_m / MAX_LIFT_RATIO)
    lift = max(LIFT_RATIO * extent, lift_m)
    return extent, lift, unit_length(lift / extent) * extent


@dataclasses.dataclass
class _End:
    """The flange path at one end, s_e [m] and its samples there, and the lead's shape:
    its side (−1 the lead-in, +1 the lead-out), its extent δ along the tangent, its lift
    H [m] along e_I (3,); its length λ along the tool's path [m] and u/δ at a length ℓ/δ
    from the end (``x_at``), filled in by ``LeadPath._table``."""

    s: float
    samples: FlangeSamples
    side: float
    extent: float
    lift: float
    e_I: np.ndarray
    length: float = 0.0
    x_at: CubicHermiteSpline | None = None


class LeadPath:
    """A flange path (``FlangePath`` or ``SmoothedFlangePath``) with a lead-in before
    σ = 0 and a lead-out after σ = L (module docstring); its domain is
    [−lead_in_m, L + lead_out_m].

    Args:
        inner: the seam's flange path over [0, L].
        lead_in_m, lead_out_m: the leads' least lengths along the tool's path [m] (the
            room their time law needs; 0: that end at rest).
        lifts_m: the least lifts (lead-in, lead-out) at their far ends [m]: a lead that
            takes over a normal approach or retract lifts by its distance (longer along
            the tool's path then: ``lead_in_m`` and ``lead_out_m`` are the lengths run,
            :func:`lead_shape`).
        reason: why the seam starts and ends at rest ("" when flying), for report.json.
    """

    def __init__(
        self,
        inner,
        *,
        lead_in_m: float,
        lead_out_m: float,
        lifts_m: tuple[float, float] = (0.0, 0.0),
        reason: str = "",
    ):
        self.inner = inner
        self.asked = {"lead_in_m": lead_in_m, "lead_out_m": lead_out_m, "lifts_m": lifts_m}
        self.reason = reason
        self._ends = [
            self._shaped(self._end(s, side, *lead_shape(length, lift)[:2]), length, lift)
            for s, side, length, lift in zip(
                (0.0, inner.length), (-1.0, 1.0), (lead_in_m, lead_out_m), lifts_m, strict=True
            )
        ]
        self.lead_in_m, self.lead_out_m = (end.length for end in self._ends)

    @classmethod
    def joined(cls, lead_in: LeadPath, lead_out: LeadPath) -> LeadPath:
        """The lead-in of ``lead_in`` and the lead-out of ``lead_out`` (leads around the
        same flange path, flying): the path ``LeadPath`` builds when asked for these two
        leads, with their tables as built (not built again)."""
        if lead_in.inner is not lead_out.inner:
            raise ValueError("leads around two flange paths cannot be joined")
        joined = cls.__new__(cls)
        joined.inner, joined.reason = lead_in.inner, ""
        joined.asked = {
            "lead_in_m": lead_in.asked["lead_in_m"],
            "lead_out_m": lead_out.asked["lead_out_m"],
            "lifts_m": (lead_in.asked["lifts_m"][0], lead_out.asked["lifts_m"][1]),
        }
        joined._ends = [lead_in._ends[0], lead_out._ends[1]]
        joined.lead_in_m, joined.lead_out_m = lead_in.lead_in_m, lead_out.lead_out_m
        return joined

    def around(self, inner) -> LeadPath:
        """These leads, as asked, around another flange path of the same seam (around
        their own: these, whose tables are built already)."""
        if inner is self.inner:
            return self
        return LeadPath(inner, **self.asked, reason=self.reason)

    def _end(self, s: float, side: float, extent: float, lift: float) -> _End:
        f = self.inner(np.array([s]))
        R_PE = self.inner.X_PE.rotation().matrix()
        R_IP = f.R_IE[0] @ R_PE.T
        return _End(s, f, side, extent, lift, R_IP @ f.R_PF[0][:, 1])

    def _shaped(self, end: _End, asked: float, lift: float) -> _End:
        """``end`` with its table, its extent scaled (lead_shape's λ leaves the seam's
        curvature out) so that the lead is ``asked`` long along the tool's path (at
        least that where a lift of ``lift`` makes it longer)."""
        for _ in range(LENGTH_ITERATIONS if end.extent > 0.0 else 0):
            end.length, end.x_at = self._table(end)
            error = end.length / asked - 1.0
            if abs(error) <= LENGTH_TOL or (error > 0.0 and end.lift == lift):
                break
            end.extent /= 1.0 + error
            end.lift = max(LIFT_RATIO * end.extent, lift)
        return end

    def _table(self, end: _End) -> tuple[float, CubicHermiteSpline]:
        """(λ, x(ℓ/δ)) of a lead: ℓ/δ = ∫₀^x g dx′ at ARC_SAMPLES values of x = |u|/δ by
        the trapezoid rule with its end correction (d/dx = g, d²/dx² = ±δ·g′), inverted
        by cubic Hermite interpolation with the exact slopes 1/g."""
        x = np.linspace(0.0, 1.0, ARC_SAMPLES)
        g, dg = self._speed(end, *self._along(end, end.side * x * end.extent, pose=False)[:5])
        slope, curvature = g, end.side * end.extent * dg
        step = np.diff(x)
        pieces = 0.5 * step * (slope[1:] + slope[:-1])
        pieces += step**2 / 12.0 * (curvature[:-1] - curvature[1:])
        arc = np.concatenate([[0.0], np.cumsum(pieces)])
        return float(arc[-1] * end.extent), CubicHermiteSpline(arc, x, 1.0 / g)

    def _along(self, end: _End, u: np.ndarray, *, pose: bool = True):
        """The lead at u (N,) [m] from its end, per metre of u: (p_IE, p′_IE, p″_IE
        (N, 3), w_u, w′_u (N, 3), R_IE (N, 3, 3); None unless ``pose``)."""
        f = end.samples
        x, n = u / end.extent, LIFT_POWER
        h = end.lift * np.abs(x) ** n
        dh = np.sign(u) * n * end.lift * np.abs(x) ** (n - 1) / end.extent  # dh/du
        ddh = n * (n - 1) * end.lift * np.abs(x) ** (n - 2) / end.extent**2  # d²h/du²
        p0, dp0, ddp0 = f.p_IE[0], f.dp_IE[0], f.ddp_IE[0]
        p_IE = p0 + u[:, None] * dp0 + 0.5 * (u**2)[:, None] * ddp0 + h[:, None] * end.e_I
        dp_u = dp0 + u[:, None] * ddp0 + dh[:, None] * end.e_I
        ddp_u = ddp0 + ddh[:, None] * end.e_I
        R_IE, w_u, dw_u = self._rotation(end, u, pose=pose)
        return p_IE, dp_u, ddp_u, w_u, dw_u, R_IE

    def _speed(self, end, p_IE, dp_u, ddp_u, w_u, dw_u) -> tuple[np.ndarray, np.ndarray]:
        """(g, dg/du) (N,): the tool point's speed in P per metre of u, the rigid-body
        g = |p′_IE + w_u × (p_IT − p_IE)| (X_PT = X_PE·X_EI·X_IT), and its derivative."""
        r = self.inner.X_IT.translation() - p_IE
        v = dp_u + np.cross(w_u, r)
        dv = ddp_u + np.cross(dw_u, r) - np.cross(w_u, dp_u)
        g = np.linalg.norm(v, axis=1)
        return g, np.einsum("ni,ni->n", v, dv) / g

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
        """(the lead-in's, the lead-out's) lift H off the part at its far end [m]."""
        return self._ends[0].lift, self._ends[1].lift

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
        """The flange path at the seam's σ (N,) [m] (within [start, end]); its arrays are
        read-only (an evaluation at the same σ, bit for bit, returns the same
        FlangeSamples, as the seam's own path does: a joint plan evaluates its samples
        several times in a row)."""
        s = np.asarray(s, dtype=float)
        L = self.inner.length
        before, after = s < 0.0, s > L
        if not (before.any() or after.any()):
            return self.inner(s)
        key = s.tobytes()
        last_key, last = self.__dict__.get("_last", (None, None))  # one tuple, replaced whole
        if key == last_key:
            return last
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
            out.setflags(write=False)
            fields[field.name] = out
        samples = FlangeSamples(**fields)
        self._last = (key, samples)
        return samples

    def __getstate__(self) -> dict:
        """Pickled without the last evaluation (a cache)."""
        return {k: v for k, v in self.__dict__.items() if k != "_last"}

    def poses(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(p_IE (N, 3) [m], R_IE (N, 3, 3)) at σ (N,)."""
        f = self(s)
        return f.p_IE, f.R_IE

    def _rotation(self, end: _End, u: np.ndarray, *, pose: bool = True):
        """(R_IE (N, 3, 3), None unless ``pose``; w_s (N, 3) [rad/m]; its rate per metre
        of u (N, 3), the central difference over ±ROTATION_RATE_STEP_M) on a lead at u
        (N,) from the end: the rotation vector's Exp and left Jacobian at u and u ± the
        step in one evaluation."""
        f = end.samples
        w, dw = f.w_s[0], f.dw_s[0]
        n, step = len(u), ROTATION_RATE_STEP_M
        at = np.concatenate([u, u + step, u - step])
        a = at[:, None] * w + 0.5 * (at**2)[:, None] * dw
        da = w + at[:, None] * dw
        Exp, J = _exp_and_left_jacobian(a, exp=n if pose else 0)
        w_at = np.einsum("nij,nj->ni", J, da)
        rate = (w_at[n : 2 * n] - w_at[2 * n :]) / (2 * step)
        return (Exp @ f.R_IE[0] if pose else None), w_at[:n], rate

    def _lead(self, end: _End, s: np.ndarray) -> FlangeSamples:
        """The lead's samples at σ (N,) beyond its end (module docstring)."""
        if end.length <= 0.0:
            raise ValueError(f"σ = {s[0]:.6g} m is beyond the path's end (no lead there)")
        f = end.samples
        arc = np.minimum(np.abs(s - end.s) / end.extent, end.length / end.extent)  # ℓ/δ
        u = end.side * end.extent * end.x_at(arc)
        p_IE, dp_u, ddp_u, w_u, dw_u, R_IE = self._along(end, u)
        g, dg = self._speed(end, p_IE, dp_u, ddp_u, w_u, dw_u)
        du, ddu = 1.0 / g, -dg / g**3  # du/dσ, d²u/dσ²
        dp_IE = dp_u * du[:, None]
        ddp_IE = ddp_u * (du**2)[:, None] + dp_u * ddu[:, None]
        w_s = w_u * du[:, None]
        dw_s = dw_u * (du**2)[:, None] + w_u * ddu[:, None]
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
