"""The workspace trajectory of the flange, sampled in time (paper §4, eq. 9).

With the time law σ(t) and the flange path z_E(σ):
    ż_E = ∂z_E/∂σ · σ̇,    z̈_E = ∂²z_E/∂σ² · σ̇² + ∂z_E/∂σ · σ̈,
evaluated with the analytic s-derivatives of the flange path (no finite
differences). σ is either the TCP arc length s along the processing path
(speed_reference "tcp") or the arc length λ along the flange path ("flange");
in the latter case s(λ) is found by the same true arc-length machinery.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.constants import DEFAULT_SAMPLE_RATE_HZ
from offline_prog.path.arc_length import ArcLengthMap
from offline_prog.path.fixed_tcp import FlangePath, FlangeSamples
from offline_prog.timing.time_law import Sin2TimeLaw, sin2_time_law

CSV_COLUMNS = (
    "t,sigma,x,y,z,alpha,beta,gamma,vx,vy,vz,wx,wy,wz,ax,ay,az,tcp_speed,dwx,dwy,dwz".split(",")
)


def tait_bryan_xyz(R: np.ndarray) -> np.ndarray:
    """(N, 3) angles (α, β, γ) with R = Rx(α)·Ry(β)·Rz(γ), unwrapped along N [rad]."""
    alpha = np.arctan2(-R[:, 1, 2], R[:, 2, 2])
    beta = np.arctan2(R[:, 0, 2], np.hypot(R[:, 1, 2], R[:, 2, 2]))
    gamma = np.arctan2(-R[:, 0, 1], R[:, 0, 0])
    return np.stack([np.unwrap(alpha), beta, np.unwrap(gamma)], axis=1)


def flange_arc_length(flange: FlangePath, s_breakpoints: np.ndarray) -> ArcLengthMap:
    """λ(s) = ∫ |dp_IE/ds| ds: arc length along the flange path as a function of s."""

    def speed(s: np.ndarray, order: int = 1):
        f = flange(s)
        g = np.linalg.norm(f.dp_IE, axis=1)
        if order == 0:
            return (g,)
        return g, np.einsum("ij,ij->i", f.dp_IE, f.ddp_IE) / g

    return ArcLengthMap(speed, s_breakpoints, periodic=False)


@dataclasses.dataclass(frozen=True)
class WorkspaceTrajectory:
    """Flange trajectory sampled at times t (all arrays have N rows).

    Attributes:
        t: (N,) time [s]; s: (N,) TCP arc length on the processing path [m].
        s_dot, s_ddot: (N,) its first two time derivatives (speed of the path
            point under the TCP [m/s] and its rate [m/s²]).
        flange: the FlangeSamples at s (poses X_IE and s-derivatives).
        v_IE, a_IE: (N, 3) flange linear velocity / acceleration in I [m/s, m/s²].
        w_IE_I, dw_IE_I: (N, 3) angular velocity / acceleration in I [rad/s, rad/s²].
        rpy_IE: (N, 3) Tait-Bryan X-Y-Z angles of R_IE [rad], unwrapped.
        tcp_speed: (N,) speed of the part point under the TCP relative to the tool
            [m/s], from the rigid-body velocity of the part.
        law: the time law; reference: "tcp" or "flange".
        law_position: (N,) the time law's own position r(t) [m]: the TCP arc length s
            for the tcp reference, the flange path's arc length for the flange reference.
            Reports, the CSV and the programs call the TCP arc length s "σ"; this is the
            one place r differs from it.
    """

    t: np.ndarray
    s: np.ndarray
    s_dot: np.ndarray
    s_ddot: np.ndarray
    flange: FlangeSamples
    v_IE: np.ndarray
    a_IE: np.ndarray
    w_IE_I: np.ndarray
    dw_IE_I: np.ndarray
    rpy_IE: np.ndarray
    tcp_speed: np.ndarray
    law: Sin2TimeLaw
    reference: str
    law_position: np.ndarray

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    def table(self) -> np.ndarray:
        """(N, len(CSV_COLUMNS)) rows in the order of CSV_COLUMNS (SI units)."""
        return np.column_stack(
            [
                self.t,
                self.s,
                self.flange.p_IE,
                self.rpy_IE,
                self.v_IE,
                self.w_IE_I,
                self.a_IE,
                self.tcp_speed,
                self.dw_IE_I,
            ]
        )


# A grid time closer than this share of a step to a seam end's own sample is dropped.
JOIN_MERGE_SHARE = 0.25


def sample_times(duration: float, rate_hz: float) -> np.ndarray:
    """(N,) times 0, 1/rate, … with the end time appended exactly."""
    t = np.arange(0.0, duration, 1.0 / rate_hz)
    if duration - t[-1] > 1e-9 / rate_hz:
        t = np.append(t, duration)
    return t


class TimeLawParameter:
    """The time law's path parameter σ and its map to the TCP arc length s.

    "tcp": σ = s (the process speed is held at the tool). "flange": σ = λ, the
    arc length along the flange path, with s(λ) from the true arc-length map. On a
    path with a lead-in (``path.lead.LeadPath``) the law's σ counts from the lead's
    start: s = σ + ``flange.start`` (tcp only).

    Args:
        flange: the flange path X_IE(s).
        reference: "tcp" or "flange".
    """

    def __init__(self, flange, reference: str = "tcp"):
        if reference not in ("tcp", "flange"):
            raise ValueError(f"speed_reference must be 'tcp' or 'flange', got {reference!r}")
        self.reference = reference
        self._map = None
        self.start = float(getattr(flange, "start", 0.0))  # s at σ = 0 [m]
        if reference == "flange" and self.start != 0.0:
            raise ValueError("a lead-in needs speed_reference tcp")
        if reference == "flange":
            s_knots = flange.path.map.s_of_u(flange.path.fitted.breakpoints)
            self._map = flange_arc_length(flange, s_knots)
        self.length = flange.length if self._map is None else self._map.length

    def s(self, sigma: np.ndarray) -> list[np.ndarray]:
        """[s, ds/dσ, d²s/dσ²] at σ (N,), each (N,)."""
        sigma = np.asarray(sigma, dtype=float)
        if self._map is None:
            s = sigma + self.start if self.start else sigma
            return [s, np.ones_like(sigma), np.zeros_like(sigma)]
        return self._map.u_of_s(sigma, order=2)


def sample_times_through(law, sigmas: list[float], rate_hz: float) -> np.ndarray:
    """:func:`sample_times` of ``law`` with the times it passes each of ``sigmas`` (the
    law's σ [m], strictly inside its path) added as samples, a grid time closer than
    JOIN_MERGE_SHARE of a step to one of them dropped: a seam's ends on a path with
    leads are samples of their own, so the seam's rows run from σ = 0 to L exactly."""
    t = sample_times(law.duration, rate_hz)
    if not sigmas:
        return t
    dense = np.linspace(0.0, law.duration, max(20001, 4 * len(t)))
    sigma_dense = law(dense)[0]
    joins = []
    for target in sigmas:
        k = int(np.searchsorted(sigma_dense, target))
        a, b = dense[max(k - 1, 0)], dense[min(k, len(dense) - 1)]
        for _ in range(60):  # bisection on the monotone σ(t), to ~1e-18 of a step
            mid = 0.5 * (a + b)
            a, b = (mid, b) if law(np.array([mid]))[0][0] < target else (a, mid)
        joins.append(0.5 * (a + b))
    joins = np.array(joins)
    near = (np.abs(t[:, None] - joins[None, :]) < JOIN_MERGE_SHARE / rate_hz).any(axis=1)
    near[[0, -1]] = False
    return np.sort(np.concatenate([t[~near], joins]))


def seam_sample_times(law, parameter: TimeLawParameter, flange, rate_hz: float) -> np.ndarray:
    """The law's sample times, with a path with leads' (``path.lead.LeadPath``) seam
    ends σ = 0 and L as samples of their own (:func:`sample_times_through`)."""
    ends = [-parameter.start, -parameter.start + getattr(flange, "seam_length", 0.0)]
    return sample_times_through(law, [x for x in ends if 0.0 < x < parameter.length], rate_hz)


def sample_workspace_trajectory(
    flange,
    parameter: TimeLawParameter,
    law: Sin2TimeLaw,
    *,
    rate_hz: float = DEFAULT_SAMPLE_RATE_HZ,
    t: np.ndarray | None = None,
) -> WorkspaceTrajectory:
    """Sample the flange path timed by ``law`` over σ (paper §4, eq. 9), at ``t`` (N,)
    [s] if given, else at ``rate_hz`` (:func:`seam_sample_times`: a lead's seam ends
    too)."""
    t = seam_sample_times(law, parameter, flange, rate_hz) if t is None else t
    sigma, sigma_dot, sigma_ddot, _ = law(t)
    s, ds, dds = parameter.s(sigma)
    s_dot = ds * sigma_dot
    s_ddot = dds * sigma_dot**2 + ds * sigma_ddot
    f = flange(s)
    v_IE = f.dp_IE * s_dot[:, None]
    a_IE = f.ddp_IE * (s_dot**2)[:, None] + f.dp_IE * s_ddot[:, None]
    w_IE_I = f.w_s * s_dot[:, None]
    dw_IE_I = f.dw_s * (s_dot**2)[:, None] + f.w_s * s_ddot[:, None]
    # Velocity of the part's material point at the TCP: v_IE + w × (p_IT − p_IE).
    p_IT = flange.X_IT.translation()
    v_IQ = v_IE + np.cross(w_IE_I, p_IT - f.p_IE)
    return WorkspaceTrajectory(
        t=t,
        s=s,
        s_dot=s_dot,
        s_ddot=s_ddot,
        flange=f,
        v_IE=v_IE,
        a_IE=a_IE,
        w_IE_I=w_IE_I,
        dw_IE_I=dw_IE_I,
        rpy_IE=tait_bryan_xyz(f.R_IE),
        tcp_speed=np.linalg.norm(v_IQ, axis=1),
        law=law,
        reference=parameter.reference,
        law_position=sigma,
    )


def plan_workspace_trajectory(
    flange,
    *,
    v_max: float,
    a_max: float,
    j_max: float,
    reference: str = "tcp",
    rate_hz: float = DEFAULT_SAMPLE_RATE_HZ,
) -> WorkspaceTrajectory:
    """Time the flange path with the sin² law and sample it (paper §4).

    Args:
        flange: the flange path X_IE(s).
        v_max, a_max, j_max: limits of σ̇, σ̈, σ⃛ [m/s, m/s², m/s³].
        reference: "tcp" (σ = s, the process speed at the tool) or "flange"
            (σ = λ, the speed of the flange origin).
        rate_hz: sample rate [Hz].
    """
    parameter = TimeLawParameter(flange, reference)
    law = sin2_time_law(parameter.length, v_max=v_max, a_max=a_max, j_max=j_max)
    return sample_workspace_trajectory(flange, parameter, law, rate_hz=rate_hz)
