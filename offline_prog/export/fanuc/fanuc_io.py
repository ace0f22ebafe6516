"""The plan's I/O events on a seam's FANUC ``L`` points, with FANUC's rules.

FANUC's distance-before motion option (``L P[i] ... DB d mm,DO[n]=ON``) sets the output
when the TCP comes within d of the motion's destination, and a motion statement takes
ONE such option. The analog flow is set with plain ``AO[n]=value`` statements, which
take effect when the statement runs: when the motion after them starts. So a seam's
chain of ``L`` points (approach, seam, retract) is split at planned samples until

- every analog event (the flow going live or back to idle, at ``IoEvent.set_path_m``:
  ``lag_s`` ahead, since FANUC does not lead by the dispenser's lag itself) starts a
  motion: the planned sample nearest its position becomes an ``L`` point;
- every motion holds at most one digital event: where two fall on one motion, the
  first planned sample at or after the earlier one becomes an ``L`` point;
- while the flow is live, the plan's flow (the ``ao`` column: the flow at the speed the
  tool has ``lag_s`` later) varies by at most ``FLOW_STEP_V`` and ``FLOW_STEP_SHARE`` of
  its value on a motion (where the tool speeds up or slows down, a planned sample starts
  a new motion), and the motion's value is the middle of that range.

Then the writer may merge motions shorter than 0.5 mm (``export.merge``, the ``merge``
argument): never away from a digital event's motion end or a flow edge, and only where
the merged motion keeps the flow as flat as above (the writer's own rule decides where
that may give: FANUC's slowest ``L`` speed).

Every inserted point is a planned sample (trajectory.csv's rows on the approach and
retract, the seam's densified samples on the seam), so the program still moves through
the plan. Positions are the seam's path positions σ [m] (negative on the approach,
beyond L on the retract), as the events'.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Collection

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from offline_prog.export.fanuc.fanuc_flow import flow_values
from offline_prog.export.merge import MIN_MOTION_M
from offline_prog.io_events import IoEvent, ProcessIo, Signal

SAME_POINT_M = 1e-6  # a sample this close to an L point is that point
DB_STEP_M = 2e-5  # the tool's curve on a DB motion, sampled this finely
FLOW_STEP_V = 0.05  # a live motion's AO value is within half this of the plan's flow on it
FLOW_STEP_SHARE = 0.01  # ... and within half this share of it (a low flow on a ramp)


@dataclasses.dataclass(frozen=True)
class Samples:
    """A seam's planned samples from its approach's start to its retract's end.

    Attributes:
        path_m: (K,) path position [m], non-decreasing.
        t: (K,) job time [s].
        q: (K, 6) URDF joints [rad].
        X_BP: (K, 4, 4) the part P in the robot base B.
        p_BT: (3,) the fixed tool's origin in B [m].
    """

    path_m: np.ndarray
    t: np.ndarray
    q: np.ndarray
    X_BP: np.ndarray
    p_BT: np.ndarray


@dataclasses.dataclass(frozen=True)
class Motion:
    """One ``L`` motion from sample ``start`` to sample ``end`` (indices into Samples):
    ``event`` the digital event it switches (None: none) ``before_end_m`` [m] before
    its end; ``flow`` the value [V] of the flow output while it runs (None: no flow);
    ``flow_event`` the analog event at its start (None: none)."""

    start: int
    end: int
    event: IoEvent | None = None
    before_end_m: float = 0.0
    flow: float | None = None
    flow_event: IoEvent | None = None


def place_events(
    samples: Samples,
    points: list[int],
    events: list[IoEvent],
    *,
    seam: str,
    io: ProcessIo | None,
    flow_at: Callable[[np.ndarray], np.ndarray] | None = None,
    merge: Callable[[list[int], set[int], Callable[[int, int], bool]], list[int]] | None = None,
    fixed: Collection[int] = (),
) -> list[Motion]:
    """The seam's ``L`` motions with its events on them, split at planned samples.

    Args:
        samples: the seam's planned samples (candidates for ``L`` points).
        points: sorted indices of the ``L`` points before splitting; ``points[0]`` is
            where the robot already is (the approach's start).
        events: the seam's I/O events (the plan's).
        seam: its name, for errors.
        io: the process I/O (None: no flow values).
        flow_at: the live flow's values [V] at job times (n,) [s] (the plan's).
        merge: merges short motions (``export.merge``): the points after the splits,
            the points it must keep (the digital events' motion ends, the flow's
            edges) and whether the plan's flow allows a motion from sample a to b (as
            flat as the splits make it) ↦ the points left (None: no merging).
        fixed: points no merge may drop (the seam's FINE ends): a flow edge less than
            MIN_MOTION_M from one of them (or from the chain's ends) starts there.

    Returns:
        The motions in run order (at most one digital event each).

    Raises:
        ValueError: two digital events fall between the same two planned samples, so
            no ``L`` point can separate them (names the seam and both positions).
    """
    points = sorted(set(points))
    sigma = samples.path_m
    analog = sorted((e for e in events if e.signal is Signal.ANALOG), key=lambda e: e.set_path_m)
    fixed = {points[0], points[-1], *fixed}
    split = [(_split(samples, points, e.set_path_m, fixed), e) for e in analog]  # (L point, event)
    edges = [(sigma[i], e.state) for i, e in split]
    digital = sorted((e for e in events if e.signal is Signal.DIGITAL), key=lambda e: e.set_path_m)
    while (pair := _crowded(sigma, points, digital)) is not None:
        first, second = pair
        inside = np.flatnonzero(
            (sigma >= first.set_path_m - SAME_POINT_M) & (sigma < second.set_path_m - SAME_POINT_M)
        )
        inside = [i for i in inside if all(abs(sigma[i] - sigma[p]) > SAME_POINT_M for p in points)]
        if not inside:
            raise ValueError(
                f"seam {seam}: the output switches at {first.set_path_m * 1e3:.3f} mm and at "
                f"{second.set_path_m * 1e3:.3f} mm along its path with no planned sample "
                "between them: a FANUC motion takes one DB option"
            )
        points = sorted({*points, int(inside[0])})
    if io is not None and io.analog_output is not None:
        points = _flow_splits(samples, points, edges, flow_at)
    if merge is not None:  # the switches' points and the flow's edges stay where they are
        ends = {points[_motion_of(sigma, points, e.set_path_m)] for e in digital}
        pinned = ends | {i for i, _ in split}

        def flow_fits(a: int, b: int) -> bool:  # a merged live motion's flow as coarse
            live = io is not None and io.analog_output is not None and _live(samples, a, edges)
            travel = float(np.linalg.norm(samples.X_BP[b, :3, 3] - samples.X_BP[a, :3, 3]))
            return not live or _flow_fits(flow_at(samples.t[a : b + 1]), travel)

        points = merge(points, pinned, flow_fits)
    on_motion = {_motion_of(sigma, points, e.set_path_m): e for e in digital}
    assert len(on_motion) == len(digital), "one digital event per motion"
    flows = [None] * (len(points) - 1)
    if io is not None and io.analog_output is not None:
        live = [_live(samples, a, edges) for a in points[:-1]]
        flows = flow_values(samples, points, live, io, flow_at, windows=_windows(analog))
    motions = []
    for i in range(1, len(points)):
        a, b = points[i - 1], points[i]
        event = on_motion.get(i)
        before = 0.0 if event is None else tcp_before_end(samples, a, b, event.set_path_m)
        motions.append(Motion(a, b, event, before, flows[i - 1], dict(split).get(a)))
    return motions


def tcp_before_end(samples: Samples, a: int, b: int, position: float) -> float:
    """[m] How far the programmed TCP (P's origin: UTOOL) is from the motion's end b
    when the tool is at ``position`` [m] on the seam's path: the distance FANUC's DB
    measures (it sets the output when the TCP enters the sphere of that radius around
    the motion's destination).

    The controller moves the TCP on the straight chord from sample a to sample b with
    the orientation slerped; the tool's point on the part then runs a curve whose
    length from sample a gives the position's share λ of the chord. Where the part
    turns, this differs from the path's own distance to b: the tool's point on the part
    moves with the turn times the lever from P's origin.
    """
    X_a, X_b = samples.X_BP[a], samples.X_BP[b]
    length = float(np.linalg.norm(X_b[:3, 3] - X_a[:3, 3]))
    if length <= SAME_POINT_M:
        return 0.0
    turn = Rotation.from_matrix(X_a[:3, :3].T @ X_b[:3, :3]).magnitude()
    lever = float(np.linalg.norm(samples.p_BT - X_a[:3, 3]))
    share = np.linspace(0.0, 1.0, int(max(length, turn * lever) / DB_STEP_M) + 2)
    R = Slerp([0.0, 1.0], Rotation.from_matrix([X_a[:3, :3], X_b[:3, :3]]))(share).as_matrix()
    p_BP = X_a[:3, 3] + share[:, None] * (X_b[:3, 3] - X_a[:3, 3])
    p_PT = np.einsum("gji,gj->gi", R, samples.p_BT - p_BP)  # the tool's point on the part
    along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p_PT, axis=0), axis=1))])
    at = float(np.interp(position - samples.path_m[a], along, share))
    return (1.0 - at) * length


def _windows(analog: list[IoEvent]) -> list[tuple[float, float]]:
    """The plan's live flow as [(t_on, t_off), ...] job times [s] (t_off inf: live to
    the end) from its analog events."""
    windows, start = [], None
    for event in sorted(analog, key=lambda e: e.t_s):
        if event.state and start is None:
            start = event.t_s
        elif not event.state and start is not None:
            windows.append((start, event.t_s))
            start = None
    return windows if start is None else [*windows, (start, np.inf)]


def _live(samples: Samples, a: int, edges) -> bool:
    """Whether the flow is live on the motion from sample a (the edges before it)."""
    live = False
    for position, state in edges:
        if position <= samples.path_m[a] + SAME_POINT_M:
            live = state
    return live


def _flow_splits(samples: Samples, points: list[int], edges, flow_at) -> list[int]:
    """Points split so the plan's flow varies by at most FLOW_STEP_V, and by at most
    FLOW_STEP_SHARE of its value, on a live motion, except that no split makes a
    motion whose TCP travels less than MIN_MOTION_M: where the tool speeds up from or
    slows down to rest, the flow steps are as coarse as a 0.5 mm motion needs (a short
    rest before the next point joins the motion before it)."""
    p = samples.X_BP[:, :3, 3]
    out = [points[0]]
    for a, b in zip(points, points[1:], strict=False):
        if _live(samples, a, edges):
            values = flow_at(samples.t[a : b + 1])
            start = 0
            for k in range(1, len(values)):
                long = np.linalg.norm(p[a + k - 1] - p[out[-1]]) >= MIN_MOTION_M
                if not _flat(values[start : k + 1]) and k - 1 > start and long:
                    start = k - 1
                    out.append(a + start)
            if out[-1] != a and np.linalg.norm(p[b] - p[out[-1]]) < MIN_MOTION_M:
                out.pop()  # the short rest to b joins the motion before it
        out.append(b)
    return out


def _flow_fits(values: np.ndarray, travel_m: float) -> bool:
    """Whether a motion whose TCP travels travel_m [m] may hold one flow value over
    the plan's values (n,) [V]: flat, or no longer than two of the shortest motions
    ``_flow_splits`` leaves where the flow steps coarsely."""
    return _flat(values) or travel_m < 2 * MIN_MOTION_M


def _flat(values: np.ndarray) -> bool:
    """Whether flow values (n,) [V] on one motion vary by at most FLOW_STEP_V and by at
    most FLOW_STEP_SHARE of their largest."""
    return values.max() - values.min() <= min(FLOW_STEP_V, FLOW_STEP_SHARE * values.max())


def _split(samples: Samples, points: list[int], position: float, fixed: Collection[int]) -> int:
    """Make the planned sample nearest ``position`` an L point (in place); its index.
    A fixed point (one no merge may drop) whose TCP is less than MIN_MOTION_M from that
    sample's is taken instead (the nearest along the path), so that no motion that
    short stays; from any other point the merge may take the short motion away."""
    sigma, p = samples.path_m, samples.X_BP[:, :3, 3]
    i = int(np.argmin(np.abs(sigma - position)))
    if any(abs(sigma[k] - sigma[i]) <= SAME_POINT_M for k in points):
        return next(k for k in points if abs(sigma[k] - sigma[i]) <= SAME_POINT_M)
    near = [k for k in fixed if np.linalg.norm(p[k] - p[i]) < MIN_MOTION_M]
    if near:
        return min(near, key=lambda k: abs(sigma[k] - sigma[i]))
    if sigma[points[0]] < sigma[i] < sigma[points[-1]]:
        points.append(i)
        points.sort()
        return i
    return points[0] if sigma[i] <= sigma[points[0]] else points[-1]


def _motion_of(sigma: np.ndarray, points: list[int], position: float) -> int:
    """The motion (index of its end in points, ≥ 1) that ends at or past position."""
    for m in range(1, len(points)):
        if sigma[points[m]] >= position - 1e-9:
            return m
    return len(points) - 1


def _crowded(sigma, points, digital) -> tuple[IoEvent, IoEvent] | None:
    """The first two digital events on one motion, in path order (None: none)."""
    for first, second in zip(digital, digital[1:], strict=False):
        if _motion_of(sigma, points, first.set_path_m) == _motion_of(
            sigma, points, second.set_path_m
        ):
            return first, second
    return None
