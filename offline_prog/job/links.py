# TEMPORARY stand-in (not committed): replaced by the links branch.
import dataclasses

import numpy as np

from offline_prog.timing.time_law import sin2_time_law
from offline_prog.timing.trajectory import sample_times


@dataclasses.dataclass
class LinkMotion:
    name: str
    method: str
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    waypoints: np.ndarray
    ok: bool = True
    failure: object = None


def plan_link(
    scene, robot, q_start, q_goal, *, clearance, self_clearance, seed, time_budget_s, rate_hz, name
):
    d = np.abs(q_goal - q_start)
    L = max(float(np.max(d / robot.qd_max)), 1e-3)
    law = sin2_time_law(1.0, v_max=1.0 / L * 0.5, a_max=4.0 / L**2, j_max=40.0 / L**3)
    t = sample_times(law.duration, rate_hz)
    s = law(t)
    q = q_start + s[0][:, None] * (q_goal - q_start)
    qd = s[1][:, None] * (q_goal - q_start)
    return LinkMotion(name, "direct", t, q, qd, np.array([q_start, q_goal]))
