"""A job as the motion statements every controller program writes, in order, and where
the process output switches on them (shared by the KRL, RAPID and URScript job writers).

Steps: ``JointMove`` (a link: fine-point joint targets, the first being where the robot
already is), ``LinearMove`` (approach and retract: the tool frame T in P at the move's
end, X_PT (4, 4); and its joints for configuration bits), and ``Process`` (a seam: the
one-seam writers' point selection on the seam's own ProgramData: ``indices`` into its
samples). A switch sits on the motion whose end point it precedes: ``move`` is the index
of the target within the step (0 for a LinearMove; m ≥ 1 for the process LIN to point m)
and ``before_end_m`` its distance before that target along the path [m] (≥ 0), the way
KRL ``TRIGGER WHEN PATH = −d`` and RAPID ``TriggIO`` measure it. Positions along the path
are the seam's arc length σ (negative before the start: on the approach; beyond L: on the
retract), so LIN chords shorter than their arcs by at most the chord tolerance.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.export.densify import densify
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.krl_points import process_points
from offline_prog.export.program import ProgramData


@dataclasses.dataclass(frozen=True)
class Switch:
    """The process output set to ``state`` ``before_end_m`` [m] before target ``move``
    of its step; ``position_m`` is where that is along the seam's path [m]."""

    output: int
    state: bool
    move: int
    before_end_m: float
    position_m: float


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


def job_steps(
    job: JobProgramData, chord_tol_m: float, angle_tol_rad: float, *, style: str = "external_tcp",
    convention: str = "X_TP",
) -> list[JointMove | LinearMove | Process]:  # fmt: skip
    """The job's motion statements in run order, with the process I/O on them."""
    steps, links, rows = [], iter(job.link_waypoints), job.job
    seam_index = {name: k for k, name in enumerate(job.seam_names)}
    for segment in job.segments:
        if segment.kind == "link":
            steps.append(JointMove(next(links)))
            continue
        k = seam_index[segment.seam]
        positions = job.switch_positions(k)
        end = min(segment.stop, len(rows.t) - 1)  # the row where the segment ends
        if segment.kind == "process":
            seam = job.seams[k]
            dense = densify(seam, chord_tol_m, angle_tol_rad)
            tolerances = dense.selection_tolerances(chord_tol_m, angle_tol_rad)
            idx, chord, angle = process_points(dense.data, style, *tolerances, convention)
            chord, angle = dense.bound(chord, angle)
            sigma = dense.data.sigma[idx]
            switches = _on_points(job, positions, sigma)
            steps.append(Process(segment.seam, dense.data, idx, chord, angle, switches))
            continue
        start = rows.X_PF[segment.start]
        length = float(np.linalg.norm(rows.X_PF[end, :3, 3] - start[:3, 3]))
        speed = float(job.seams[k].process_speed_m_s)
        switches = ()
        if positions is not None and segment.kind == "approach":
            on = positions[0]
            if -length - 1e-9 <= on < 0.0:  # on the approach: before the seam's start
                switches = (Switch(job.process_io.digital_output, True, 0, -on, on),)
        if positions is not None and segment.kind == "retract":
            off, total = positions[1], job.seam_lengths_m[k]
            if total < off <= total + length + 1e-9:  # on the retract: after the seam's end
                switches = (Switch(job.process_io.digital_output, False, 0,
                                   total + length - off, off),)  # fmt: skip
        steps.append(
            LinearMove(
                segment.kind, segment.seam, rows.X_PF[end], rows.q[end], length, speed, switches
            )  # fmt: skip
        )
    return steps


def _on_points(job: JobProgramData, positions, sigma: np.ndarray) -> tuple[Switch, ...]:
    """The switches that fall on the seam's own LIN moves (0 < position ≤ L)."""
    if positions is None:
        return ()
    out = []
    for position, state in zip(positions, (True, False), strict=True):
        if sigma[0] < position <= sigma[-1] + 1e-9:
            m = int(np.searchsorted(sigma, position - 1e-12))  # σ[m−1] < position ≤ σ[m]
            m = min(max(m, 1), len(sigma) - 1)
            out.append(
                Switch(
                    job.process_io.digital_output,
                    state,
                    m,
                    float(sigma[m] - position),
                    float(position),
                )  # fmt: skip
            )
    return tuple(out)
