"""A job as the motion statements every controller program writes, in order, and where
the process output switches on them (shared by the KRL, RAPID and URScript job writers).

Steps: ``JointMove`` (a link: fine-point joint targets, the first being where the robot
already is), ``LinearMove`` (approach and retract: the tool frame T in P at the move's
end, X_PT (4, 4); and its joints for configuration bits), and ``Process`` (a seam: the
one-seam writers' point selection on the seam's own ProgramData: ``indices`` into its
samples). The plan's I/O events (``io_events``) are placed on these motions, never
recomputed: a switch sits on the motion whose end point it precedes: ``move`` is the
index of the target within the step (0 for a LinearMove; m ≥ 1 for the process LIN to
point m) and ``before_end_m`` its distance before that target along the path [m] (≥ 0),
the way KRL ``TRIGGER WHEN PATH = −d`` and RAPID ``TriggIO`` measure it. A motion holds
every switch that falls on it, in path order. Positions along the path are the seam's
arc length σ (negative before the start: on the approach; beyond L: on the retract), so
LIN chords shorter than their arcs by at most the chord tolerance.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.export.densify import densify
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.kuka.krl_points import process_points
from offline_prog.export.program import ProgramData
from offline_prog.io_events import IoEvent, Signal


@dataclasses.dataclass(frozen=True)
class Switch:
    """An I/O event placed on a motion: ``before_end_m`` [m] before target ``move`` of
    its step; ``event`` the plan's event (output, state, value, position)."""

    move: int
    before_end_m: float
    event: IoEvent

    @property
    def output(self) -> int:
        return self.event.output

    @property
    def state(self) -> bool:
        return self.event.state

    @property
    def signal(self) -> Signal:
        return self.event.signal


@dataclasses.dataclass(frozen=True)
class JointMove:
    targets: np.ndarray  # (K, 6) URDF joints [rad]; targets[0] is the start


@dataclasses.dataclass(frozen=True)
class LinearMove:
    kind: str  # approach | retract
    seam: str
    X_PT: np.ndarray  # (4, 4) the tool frame in P at the end of the move
    q: np.ndarray  # (6,) the joints there [rad]
    length_m: float
    speed_m_s: float
    switches: tuple[Switch, ...] = ()


@dataclasses.dataclass(frozen=True)
class Process:
    seam: str
    data: ProgramData  # the seam's (densified) samples
    indices: np.ndarray  # (K,) the LIN points' samples; the first is the seam's start
    max_chord_m: float
    max_angle_rad: float
    switches: tuple[Switch, ...] = ()

    def switches_before(self, m: int) -> tuple[Switch, ...]:
        """The switches on the LIN to point m, in path order."""
        return tuple(s for s in self.switches if s.move == m)


def job_steps(
    job: JobProgramData,
    chord_tol_m: float,
    angle_tol_rad: float,
    *,
    style: str = "external_tcp",
    convention: str = "X_TP",
    flow_where_set: bool = False,
) -> list[JointMove | LinearMove | Process]:
    """The job's motion statements in run order, with the plan's I/O events on them.

    ``flow_where_set``: place the flow's events where the controller sets them
    (``IoEvent.set_path_m``: ``lag_s`` ahead, for a controller that does not lead by the
    lag itself), not at their gate positions (``path_m``, RAPID's ScaleLag leads)."""
    steps, links, rows = [], iter(job.link_waypoints), job.job
    seam_index = {name: k for k, name in enumerate(job.seam_names)}
    for segment in job.segments:
        if segment.kind == "link":
            steps.append(JointMove(next(links)))
            continue
        k = seam_index[segment.seam]
        end = min(segment.stop, len(rows.t) - 1)  # the row where the segment ends
        if segment.kind == "process":
            seam = job.seams[k]
            dense = densify(seam, chord_tol_m, angle_tol_rad)
            tolerances = dense.selection_tolerances(chord_tol_m, angle_tol_rad)
            idx, chord, angle = process_points(dense.data, style, *tolerances, convention)
            chord, angle = dense.bound(chord, angle)
            steps.append(Process(segment.seam, dense.data, idx, chord, angle))
            continue
        start = rows.X_PF[segment.start]
        length = float(np.linalg.norm(rows.X_PF[end, :3, 3] - start[:3, 3]))
        speed = float(job.seams[k].process_speed_m_s)
        steps.append(
            LinearMove(segment.kind, segment.seam, rows.X_PF[end], rows.q[end], length, speed)
        )
    return _with_switches(steps, job, flow_where_set)


def _position(event: IoEvent, flow_where_set: bool) -> float:
    """Where along the path a program switches the event [m]."""
    return event.set_path_m if flow_where_set else event.path_m


def _with_switches(steps: list, job: JobProgramData, flow_where_set: bool) -> list:
    """Each seam's events placed on its approach, LIN and retract motions."""
    out = list(steps)
    for seam, k in {name: k for k, name in enumerate(job.seam_names)}.items():
        events = sorted(
            (e for e in job.events if e.seam == seam),
            key=lambda e: (_position(e, flow_where_set), e.signal is not Signal.DIGITAL),
        )
        if not events:
            continue
        # (step index, move, path position at the move's start and end [m]) in order.
        moves, length = [], job.seam_lengths_m[k]
        for i, step in enumerate(steps):
            if isinstance(step, LinearMove) and step.seam == seam:
                a = -step.length_m if step.kind == "approach" else length
                moves.append((i, 0, a, a + step.length_m))
            elif isinstance(step, Process) and step.seam == seam:
                sigma = step.data.sigma[step.indices]
                moves += [(i, m, sigma[m - 1], sigma[m]) for m in range(1, len(sigma))]
        moves.sort(key=lambda move: (move[2], move[3]))
        placed: dict[int, list[Switch]] = {}
        for event in events:
            # The first motion that ends at or past the position (the last one if none).
            at = _position(event, flow_where_set)
            i, m, _, b = next((mv for mv in moves if mv[3] >= at - 1e-9), moves[-1])
            before = max(0.0, float(b - at))
            placed.setdefault(i, []).append(Switch(m, before, event))
        for i, switches in placed.items():
            out[i] = dataclasses.replace(out[i], switches=tuple(switches))
    return out
