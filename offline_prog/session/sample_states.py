"""Each sample's state along a plan, for the path's colours and the status line.

In order of precedence: colliding (closer than the clearance, from the collision
check), near a singularity (the joint plan's near stretches: wrist, elbow, shoulder,
Jacobian), slowed by a joint limit (inside a stretch where the joint retiming lowered
the process speed), else ok.
"""

from __future__ import annotations

import numpy as np

OK, SLOWED, SINGULAR, COLLIDING = range(4)
NAMES = ("ok", "slowed by a joint limit", "near a singularity", "colliding")


def _in_stretches(sigma: np.ndarray, stretches) -> np.ndarray:
    inside = np.zeros(len(sigma), dtype=bool)
    for start, end in stretches:
        inside |= (sigma >= start) & (sigma <= end)
    return inside


def sample_states(plan) -> np.ndarray:
    """(N,) one of OK, SLOWED, SINGULAR, COLLIDING per trajectory sample of ``plan``
    (a :class:`~offline_prog.job.records.Plan`)."""
    traj, joints = plan.trajectory, plan.joints
    # The time law's own position: the σ that retiming and singularity stretches use.
    sigma = getattr(traj, "law_position", traj.s)
    states = np.full(len(traj.t), OK, dtype=int)
    slowed = [(a, b) for a, b, _ in joints.retiming.reductions]
    states[_in_stretches(sigma, slowed)] = SLOWED
    near = [s for kind in joints.singularities.values() for s in kind["near"]]
    states[_in_stretches(sigma, near)] = SINGULAR
    index = np.asarray(plan.collisions.samples_in_collision, dtype=int)
    states[index[(index >= 0) & (index < len(states))]] = COLLIDING
    return states


def counts(states: np.ndarray) -> dict[str, int]:
    """Samples per state name."""
    return {name: int(np.sum(states == k)) for k, name in enumerate(NAMES)}
