"""Link moves of a job: collision-free joint motions between seams, from home and back.

A link first tries the direct joint move (a straight line in joint space, what a
controller's PTP / MoveAbsJ / movej to a fine point does). If the collision check
(:class:`~offline_prog.collision.motion.MotionChecker`: certified between configurations,
same pairs and clearances as the seams) rejects it, OMPL's RRTConnect plans in joint
space with that checker as its state and motion validity, and OMPL's PathSimplifier
shortens the path (``reduceVertices``: shortcuts between vertices; ``collapseCloseVertices``;
every new segment certified; ``simplifyMax`` found paths a few percent shorter at five to
ten times the cost, ``scripts/bench_links.py``). Each segment between waypoints is then
timed rest to rest by ruckig on one path parameter s ∈ [0, 1], q = q_a + s (q_b − q_a),
with the tightest joint's limits (v_s = min_k v_k / |Δq_k|, likewise for acceleration
and jerk): the motion stays on the certified straight segment and within every joint's
speed, acceleration and jerk limit (in the controller's axes; the IRB 2400's axis 3 =
q2 + q3 is linear in q, so straight stays straight). Waypoints are fine points (rest):
what the controller programs command, so the checked motion is the one the robot runs.

Determinism: OMPL's random numbers are seeded (``seed``) before each planning, so the
same link with the same seed gives the same path. A link not found within
``time_budget_s`` is a failure result naming the link.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from offline_prog.collision.motion import MotionChecker
from offline_prog.errors import Failure, PlanFailure
from offline_prog.robot.model import RobotModel
from offline_prog.timing.trajectory import sample_times

# RRTConnect's longest edge in joint space [rad, Euclidean]: long edges, few vertices
# (each edge is certified by conservative advancement, which steps as far as it may).
PLANNER_RANGE_RAD = 1.5
MIN_CLEARANCE_SAMPLES = 200  # samples of a link measured for its reported clearance


@dataclasses.dataclass(frozen=True)
class LinkMotion:
    """A link move, or why there is none.

    Attributes:
        name: "<from> -> <to>"; method: "direct" | "planned" ("" when it failed).
        t: (N,) time from the link's start [s]; q, qd: (N, 6) [rad, rad/s], URDF order.
        waypoints: (K, 6) the joint targets of the straight segments (the first is the
            start): what a controller program moves through to fine points.
        planning_time_s: wall time of the check and planning [s].
        failure: None, or the PlanFailure that ends the plan (naming the link).
    """

    name: str
    method: str
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    waypoints: np.ndarray
    planning_time_s: float
    failure: PlanFailure | None = None
    min_clearance_m: float | None = None  # over its samples (Drake's distances) [m]

    @property
    def ok(self) -> bool:
        return self.failure is None

    @property
    def duration_s(self) -> float:
        return float(self.t[-1]) if len(self.t) else 0.0

    @property
    def length_rad(self) -> float:
        """Joint-space length Σ |Δq| (Euclidean) of the waypoint polyline [rad]."""
        return float(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1).sum())


def plan_link(
    scene,
    robot: RobotModel,
    q_start: np.ndarray,
    q_goal: np.ndarray,
    *,
    clearance: float,
    self_clearance: float,
    seed: int,
    time_budget_s: float,
    rate_hz: float,
    name: str,
    checker: MotionChecker | None = None,
    speed_share: float = 1.0,
) -> LinkMotion:
    """The link move q_start → q_goal (6,) [rad], sampled at rate_hz [Hz], at
    ``speed_share`` of the joints' speed limits (``motion.link_speed_percent`` / 100)."""
    started = time.perf_counter()
    checker = checker or MotionChecker(scene, clearance=clearance, self_clearance=self_clearance)
    q_start, q_goal = (np.asarray(q, dtype=float) for q in (q_start, q_goal))

    def failed(reason: str) -> LinkMotion:
        failure = PlanFailure(Failure.COLLISION, 0.0, 0.0, f"collision: link {name}: {reason}")
        empty = np.zeros((0, 6))
        return LinkMotion(
            name, "", np.zeros(0), empty, empty, empty, time.perf_counter() - started, failure
        )

    for end, q in (("start", q_start), ("goal", q_goal)):
        if not checker.clear(q):
            return failed(f"its {end} configuration is closer than the clearance")
    if checker.move_clear(q_start, q_goal):
        method, waypoints = "direct", np.array([q_start, q_goal])
    else:
        waypoints = _ompl_path(robot, checker, q_start, q_goal, seed, time_budget_s)
        if waypoints is None:
            return failed(f"no collision-free path found within {time_budget_s:g} s (OMPL)")
        method = "planned"
    t, q, qd = timed_polyline(robot, waypoints, rate_hz, speed_share=speed_share)
    nearest = min(
        checker.min_distance(q_k) for q_k in q[:: max(1, len(q) // MIN_CLEARANCE_SAMPLES)]
    )
    return LinkMotion(
        name,
        method,
        t,
        q,
        qd,
        waypoints,
        time.perf_counter() - started,
        min_clearance_m=float(nearest),
    )


def _ompl_path(robot, checker, q_start, q_goal, seed, time_budget_s) -> np.ndarray | None:
    """(K, 6) waypoints of RRTConnect's shortened path, or None within the budget."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    space = ob.RealVectorStateSpace(6)
    bounds = ob.RealVectorBounds(6)
    lower, upper = _urdf_bounds(robot)
    for k in range(6):
        bounds.setLow(k, float(lower[k]))
        bounds.setHigh(k, float(upper[k]))
    space.setBounds(bounds)
    info = ob.SpaceInformation(space)

    def vector(state) -> np.ndarray:
        return np.array([state[k] for k in range(6)])

    def valid(state) -> bool:
        q = vector(state)
        q_c = robot.controller_joints(q)
        inside = bool(np.all(q_c >= robot.q_lower) and np.all(q_c <= robot.q_upper))
        return inside and bool(checker.clear(q))

    class Motion(ob.MotionValidator):
        def checkMotion(self, a, b) -> bool:
            return bool(checker.move_clear(vector(a), vector(b)))

    info.setStateValidityChecker(valid)
    motion = Motion(info)
    info.setMotionValidator(motion)
    info.setup()
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)  # setSeed warns that seeds were drawn before: re-seeded
    ou.RNG.setSeed(int(seed) + 1)  # OMPL ignores seed 0
    try:
        setup = og.SimpleSetup(info)
        start, goal = info.allocState(), info.allocState()
        for k in range(6):
            start[k], goal[k] = float(q_start[k]), float(q_goal[k])
        setup.setStartAndGoalStates(start, goal)
        planner = og.RRTConnect(info)
        planner.setRange(PLANNER_RANGE_RAD)
        setup.setPlanner(planner)
        setup.solve(time_budget_s)
        if not setup.haveExactSolutionPath():
            return None
        path = setup.getSolutionPath()
        simplifier = og.PathSimplifier(info)  # its random numbers: seeded above
        simplifier.reduceVertices(path)  # shortcuts between vertices, each certified
        simplifier.collapseCloseVertices(path)
        return np.array([vector(path.getState(i)) for i in range(path.getStateCount())])
    finally:
        ou.setLogLevel(level)


def _urdf_bounds(robot: RobotModel) -> tuple[np.ndarray, np.ndarray]:
    """(6,), (6,) a box in URDF joints holding every configuration inside the
    controller's limits (exact unless axes are coupled; validity checks the rest)."""
    lower, upper = robot.q_lower.copy(), robot.q_upper.copy()
    if robot.j23_coupled:  # q3 = a3 − f·q2 with a3 the controller's axis 3
        f_q2 = robot.j23_factor * np.array([robot.q_lower[1], robot.q_upper[1]])
        lower[2] = robot.q_lower[2] - f_q2.max()
        upper[2] = robot.q_upper[2] - f_q2.min()
    return lower, upper


def timed_polyline(
    robot: RobotModel, waypoints: np.ndarray, rate_hz: float, *, speed_share: float = 1.0
):
    """(t, q, qd): the waypoints (K, 6) joined by straight segments, each rest to rest,
    sampled at rate_hz (see the module docstring: ruckig on s with the tightest limits),
    the joints' speed limits scaled by ``speed_share`` ∈ (0, 1] (a PTP speed override
    scales the axes' speed, as KUKA's ``BAS(#VEL_PTP, %)``)."""
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    q_c = robot.controller_joints(waypoints)
    jerk = robot.jerk_limits
    ts, qs, qds, clock = [np.zeros(1)], [waypoints[:1]], [np.zeros((1, 6))], 0.0
    for a, b, a_c, b_c in zip(waypoints[:-1], waypoints[1:], q_c[:-1], q_c[1:], strict=True):
        delta = np.abs(b_c - a_c)
        if delta.max() < 1e-12:
            continue
        moving = delta > 1e-12
        otg, inp, profile = Ruckig(1), InputParameter(1), Trajectory(1)
        inp.current_position, inp.target_position = [0.0], [1.0]
        qd_max = speed_share * robot.qd_max[moving]
        inp.max_velocity = [float(np.min(qd_max / delta[moving]))]
        inp.max_acceleration = [float(np.min(robot.qdd_max[moving] / delta[moving]))]
        inp.max_jerk = [float(np.min(jerk[moving] / delta[moving]))]
        result = otg.calculate(inp, profile)
        assert result in (Result.Working, Result.Finished), result
        t = sample_times(profile.duration, rate_hz)[1:]
        s, sd = np.array([profile.at_time(x)[:2] for x in t])[:, :, 0].T
        ts.append(clock + t)
        qs.append(a + s[:, None] * (b - a))
        qds.append(sd[:, None] * (b - a))
        clock += profile.duration
    return np.concatenate(ts), np.concatenate(qs), np.concatenate(qds)
