"""A flying seam's timed rows split at its ends: lead-in, seam, lead-out.

A seam with leads (``path.lead``) is timed as one path from the lead-in's start to the
lead-out's end, with samples of their own at σ = 0 and σ = L
(``timing.trajectory.sample_times_through``). :func:`split_leads` cuts those rows
there: the seam's plan keeps its rows σ ∈ [0, L] (its clock from 0 at σ = 0, its law
read on that clock), and the leads' rows go to the job's approach and retract pieces
(``job.stages``), labelled ``approach:<seam>`` and ``retract:<seam>``, with path_m
their σ (negative on the lead-in, beyond L on the lead-out). The cuts share a row, so
the pieces join at the same configuration and joint speed.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.joints.joint_plan import JointTrajectory
from offline_prog.path.fixed_tcp import FlangeSamples
from offline_prog.timing.trajectory import WorkspaceTrajectory

SEAM_END_TOLERANCE_M = 1e-9  # a row this close to σ = 0 or L is the seam's end row


@dataclasses.dataclass(frozen=True)
class LeadRows:
    """A lead's samples: t (N,) from the lead's first row [s], q, qd (N, 6) [rad,
    rad/s], s (N,) σ [m] (the seam's, continued), tcp_speed (N,) [m/s]. The lead-in's
    last row is the seam's first, the lead-out's first row the seam's last."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    s: np.ndarray
    tcp_speed: np.ndarray

    @property
    def length_m(self) -> float:
        return float(abs(self.s[-1] - self.s[0]))


class ShiftedLaw:
    """A time law read from ``t0`` [s] on: law(t) = inner(t + t0), σ less ``s0`` [m];
    duration ``duration`` [s]; other attributes (v_peak, a_max, …) the inner law's."""

    def __init__(self, inner, *, t0: float, s0: float, duration: float):
        self.inner, self.t0, self.s0, self._duration = inner, t0, s0, duration

    def __getattr__(self, name: str):
        if name.startswith("__") or name == "inner":
            raise AttributeError(name)
        return getattr(self.__dict__["inner"], name)

    @property
    def duration(self) -> float:
        return self._duration

    def __call__(self, t):
        sigma, *rest = self.inner(np.asarray(t, dtype=float) + self.t0)
        return [sigma - self.s0, *rest]


def _rows(traj: WorkspaceTrajectory, rows: slice, law) -> WorkspaceTrajectory:
    flange = FlangeSamples(
        **{f.name: getattr(traj.flange, f.name)[rows] for f in dataclasses.fields(FlangeSamples)}
    )
    arrays = {
        name: getattr(traj, name)[rows]
        for name in (
            "s",
            "s_dot",
            "s_ddot",
            "v_IE",
            "a_IE",
            "w_IE_I",
            "dw_IE_I",
            "rpy_IE",
            "tcp_speed",
            "law_position",
        )
    }
    t = traj.t[rows]
    return dataclasses.replace(traj, t=t - t[0], flange=flange, law=law, **arrays)


def _lead(joints: JointTrajectory, rows: slice) -> LeadRows:
    traj = joints.trajectory
    t = traj.t[rows]
    return LeadRows(t - t[0], joints.q[rows], joints.qd[rows], traj.s[rows], traj.tcp_speed[rows])


def split_leads(
    joints: JointTrajectory, length_m: float
) -> tuple[JointTrajectory, LeadRows | None, LeadRows | None]:
    """(the seam's rows σ ∈ [0, L] as a JointTrajectory, the lead-in's rows or None, the
    lead-out's rows or None) of a seam timed with its leads (L = ``length_m``)."""
    traj = joints.trajectory
    s = traj.s
    first = int(np.argmin(np.abs(s))) if s[0] < 0.0 else 0
    last = int(np.argmin(np.abs(s - length_m))) if s[-1] > length_m else len(s) - 1
    assert abs(s[first]) <= SEAM_END_TOLERANCE_M or first == 0, s[first]
    assert abs(s[last] - length_m) <= SEAM_END_TOLERANCE_M or last == len(s) - 1, s[last]
    seam = slice(first, last + 1)
    t0 = float(traj.t[first])
    law_s0 = float(traj.law_position[first] - s[first])  # the law's σ at the seam's σ = 0
    law = ShiftedLaw(traj.law, t0=t0, s0=law_s0, duration=float(traj.t[last] - t0))
    trajectory = _rows(traj, seam, law)
    cut = dataclasses.replace(
        joints, trajectory=trajectory, q=joints.q[seam], qd=joints.qd[seam], qdd=joints.qdd[seam]
    )
    lead_in = _lead(joints, slice(0, first + 1)) if first > 0 else None
    lead_out = _lead(joints, slice(last, len(s))) if last < len(s) - 1 else None
    return cut, lead_in, lead_out
