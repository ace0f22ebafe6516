"""The program record: a job as the motion statements every controller program writes,
in run order, with the plan's I/O events placed on them. It is built once per export
from the finished plan (:func:`program_record`) and every writer (``export.post``) only
translates it.

Steps: ``JointMove`` (home, then each link: fine-point joint targets) and ``SeamRun``
(a seam as run: its approach and retract, ``LinearMove`` to the tool frame T in P at
the move's end, X_PT (4, 4), and its joints for configuration bits; between them its
``Process``: the seam's samples and the ones the writer's ``PointRule`` chose as
points, ``indices`` into them). The plan's I/O events (``io_events``) are placed on
these motions, never recomputed: a switch sits on the motion whose end point it
precedes: ``move`` is the index of the target within the step (0 for a LinearMove;
m ≥ 1 for the process LIN to point m) and ``before_end_m`` its distance before that
target along the path [m] (≥ 0), the way KRL ``TRIGGER WHEN PATH = −d`` and RAPID
``TriggIO`` measure it. A motion holds every switch that falls on it, in path order.
Positions along the path are the seam's arc length σ (negative before the start: on
the approach; beyond L: on the retract), so LIN chords shorter than their arcs by at
most the chord tolerance.
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from offline_prog.export.densify import densify
from offline_prog.export.job_program import JobProgramData, JobSegment
from offline_prog.export.points import PointRule, process_points
from offline_prog.export.program import ProgramData
from offline_prog.io_events import IoEvent, Signal

# Path positions closer than this are one (a lead's end and the seam's sample there) [m].
PATH_TOL_M = 1e-6


@dataclasses.dataclass(frozen=True)
class Switch:
    """An I/O event placed on a motion: ``before_end_m`` [m] before target ``move`` of
    its step; ``event`` the plan's event (signal, output, state, value, position)."""

    move: int
    before_end_m: float
    event: IoEvent


@dataclasses.dataclass(frozen=True)
class JointMove:
    """Home (``number`` 0: from wherever the robot is, ``start`` None) or link
    ``number`` ≥ 1 from ``start`` (6,) [rad]: fine-point joint moves through
    ``targets`` (K, 6) [rad] (URDF joints), the planned, collision-checked moves."""

    number: int
    start: np.ndarray | None
    targets: np.ndarray


@dataclasses.dataclass(frozen=True)
class LinearMove:
    """The approach onto seam ``seam`` (run ``number``) or the retract off it: a straight
    move of ``length_m`` [m] at ``speed_m_s`` [m/s] to the tool frame ``X_PT`` (4, 4) in
    P, with the joints ``q`` (6,) [rad] there."""

    kind: str  # approach | retract
    seam: str
    number: int
    X_PT: np.ndarray
    q: np.ndarray
    length_m: float
    speed_m_s: float
    switches: tuple[Switch, ...] = ()


@dataclasses.dataclass(frozen=True)
class Process:
    """Seam ``seam`` (run ``number``): its (densified) samples ``data``, and ``indices``
    (K,) of the samples that are the writer's points (the first is the seam's start);
    the points' largest deviation from the continuous plan [m, rad]; ``residual`` the
    continuous plan's largest deviation [m, rad] from what the samples show
    (``Densified.bound``: a deviation measured at the samples plus it bounds the true one)
    and ``selection_tol`` the tolerances [m, rad] the points were chosen with (the
    writer's less the residual: a motion merged later holds them too)."""

    seam: str
    number: int
    data: ProgramData
    indices: np.ndarray
    max_chord_m: float
    max_angle_rad: float
    switches: tuple[Switch, ...] = ()
    residual: tuple[float, float] = (0.0, 0.0)
    selection_tol: tuple[float, float] = (0.0, 0.0)

    def switches_before(self, m: int) -> tuple[Switch, ...]:
        """The switches on the LIN to point m, in path order."""
        return tuple(s for s in self.switches if s.move == m)


@dataclasses.dataclass(frozen=True)
class SeamRun:
    """Seam ``seam`` as run, ``number`` from 1 in run order: approach, process, retract
    (no approach or retract where there is no straight move: the cell asks for none,
    or a flying seam's lead took it over and the link ends where the lead-in starts),
    its job ``segments``, the job's ``rows`` from the approach's first to the retract's
    last, and the seam's I/O ``events`` in time order."""

    seam: str
    number: int
    approach: LinearMove | None
    process: Process
    retract: LinearMove | None
    segments: tuple[JobSegment, ...]
    rows: slice
    events: tuple[IoEvent, ...]


@dataclasses.dataclass(frozen=True)
class ProgramRecord:
    """A job as its programs run it: ``job`` (the header's facts, rows and I/O) and the
    ``steps`` in run order (home first, then links and seam runs)."""

    job: JobProgramData
    steps: tuple[JointMove | SeamRun, ...]

    def runs(self) -> list[SeamRun]:
        """The seam runs, in run order."""
        return [step for step in self.steps if isinstance(step, SeamRun)]


def program_record(
    job: JobProgramData, points: PointRule | None, *, flow_where_set: bool = False
) -> ProgramRecord:
    """The job's motion statements in run order, with the plan's I/O events on them.

    Args:
        points: how the writer's controller interpolates between points, which decides
            the points of each seam (``export.points``); None: every planned sample (a
            writer that streams the plan).
        flow_where_set: place the flow's events where the controller sets them
            (``IoEvent.set_path_m``: ``lag_s`` ahead, for a controller that does not lead
            by the lag itself), not at their gate positions (``path_m``, RAPID's
            ScaleLag leads).
    """
    links = iter(job.link_waypoints)
    steps: list = [JointMove(0, None, job.link_waypoints[0][:1])]  # home
    # The segments in run order: links, and each seam's approach, process and retract.
    for is_link, group in itertools.groupby(job.segments, key=lambda s: s.kind == "link"):
        if is_link:
            for _ in group:
                w, number = next(links), sum(isinstance(s, JointMove) for s in steps)
                steps.append(JointMove(number, w[0], w[1:]))
            continue
        number = sum(isinstance(s, SeamRun) for s in steps) + 1
        steps.append(_seam_run(job, number, tuple(group), points, flow_where_set))
    return ProgramRecord(job, tuple(steps))


def _seam_run(job, number, segments, points, flow_where_set) -> SeamRun:
    by_kind = {s.kind: s for s in segments}
    seam = segments[0].seam
    k = job.seam_names.index(seam)
    moves = {
        kind: _linear_move(job, by_kind[kind], number, k)
        for kind in ("approach", "retract")
        if kind in by_kind and _has_straight_move(job, by_kind[kind], k)
    }
    process = _process(job.seams[k], seam, number, points)
    events = tuple(e for e in job.events if e.seam == seam)
    rows = slice(segments[0].start, min(segments[-1].stop + 1, len(job.job.t)))
    run = SeamRun(
        seam, number, moves.get("approach"), process, moves.get("retract"), segments, rows, events
    )
    return _with_switches(run, job.seam_lengths_m[k], flow_where_set)


def _has_straight_move(job: JobProgramData, segment: JobSegment, k: int) -> bool:
    """Whether an approach or retract segment holds a straight move, not only a flying
    seam's lead: the straight move's rows lie beyond the seam's samples along the path
    (``job.stages``: path_m −(lead-in + δ) before them, L + lead-out + δ after them),
    a lead alone starts (ends) on the seam's first (last) sample."""
    path, seam = job.job.path_m, job.seams[k].path_m
    if segment.kind == "approach":
        return bool(path[segment.start] < seam[0] - PATH_TOL_M)
    end = min(segment.stop, len(path) - 1)  # the next link's first row: NaN
    beyond = path[segment.start : end + 1]
    return bool(np.nanmax(beyond, initial=-np.inf) > seam[-1] + PATH_TOL_M)


def _linear_move(job: JobProgramData, segment: JobSegment, number: int, k: int) -> LinearMove:
    """The straight part of an approach or retract: a flying seam's approach ends where
    its lead-in starts (the seam's first sample), its retract starts where its lead-out
    ends (the seam's last sample): the leads are the seam's samples
    (``results.program_data.seam_rows``), and the job's rows, at the cell's sample
    rate, need not hold the lead's end."""
    rows, seam = job.job, job.seams[k]
    start, end = segment.start, min(segment.stop, len(rows.t) - 1)  # the segment's rows
    X_from, X_to, q_to = rows.X_PT[start], rows.X_PT[end], rows.q[end]
    if segment.kind == "approach" and seam.path_m[0] < 0.0:
        X_to, q_to = seam.X_PT[0], seam.q[0]
    if segment.kind == "retract" and seam.path_m[-1] > job.seam_lengths_m[k]:
        X_from = seam.X_PT[-1]
    length = float(np.linalg.norm(X_to[:3, 3] - X_from[:3, 3]))
    speed = float(seam.off_seam_speed_m_s)
    return LinearMove(segment.kind, segment.seam, number, X_to, q_to, length, speed)


def _process(seam: ProgramData, name: str, number: int, points: PointRule | None) -> Process:
    """The seam's samples and its points under the rule (every sample without one)."""
    if points is None:
        return Process(name, number, seam, np.arange(len(seam.t)), 0.0, 0.0)
    dense = densify(seam, points.chord_tol_m, points.angle_tol_rad)
    tolerances = dense.selection_tolerances(points.chord_tol_m, points.angle_tol_rad)
    idx, chord, angle = process_points(dense.data, points, *tolerances)
    chord, angle = dense.bound(chord, angle)
    residual = dense.bound(0.0, 0.0)
    return Process(
        name, number, dense.data, idx, chord, angle, residual=residual, selection_tol=tolerances
    )


def _position(event: IoEvent, flow_where_set: bool) -> float:
    """Where along the path a program switches the event [m]: a digital output where
    it is set (its valve's response time ahead), the flow where it is set or where it
    takes effect (a controller that leads by the lag itself)."""
    if event.signal is Signal.DIGITAL or flow_where_set:
        return event.set_path_m
    return event.path_m


def _with_switches(run: SeamRun, length: float, flow_where_set: bool) -> SeamRun:
    """The seam's events placed on its approach, LIN and retract motions."""
    events = sorted(
        run.events,
        key=lambda e: (_position(e, flow_where_set), e.signal is not Signal.DIGITAL),
    )
    if not events:
        return run
    # (part, move, path position at the move's start and end [m]) in path order.
    moves = []
    sigma = run.process.data.path_m[run.process.indices]  # from a lead-in's start
    first, last = min(sigma[0], 0.0), max(sigma[-1], length)
    if run.approach is not None:
        moves.append(("approach", 0, first - run.approach.length_m, first))
    moves += [("process", m, sigma[m - 1], sigma[m]) for m in range(1, len(sigma))]
    if run.retract is not None:
        moves.append(("retract", 0, last, last + run.retract.length_m))
    moves.sort(key=lambda move: (move[2], move[3]))
    placed: dict[str, list[Switch]] = {}
    for event in events:
        # The first motion that ends at or past the position (the last one if none).
        at = _position(event, flow_where_set)
        part, m, _, b = next((mv for mv in moves if mv[3] >= at - 1e-9), moves[-1])
        placed.setdefault(part, []).append(Switch(m, max(0.0, float(b - at)), event))
    parts = {
        part: dataclasses.replace(getattr(run, part), switches=tuple(switches))
        for part, switches in placed.items()
    }
    return dataclasses.replace(run, **parts)
