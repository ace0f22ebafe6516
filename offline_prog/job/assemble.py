"""A whole job as one sampled joint trajectory with named segments.

The job runs home → link → approach₁ → process₁ → retract₁ → link → approach₂ → … →
retract_n → link → home. Each piece is sampled on its own clock from rest to rest; here
they are laid end to end: piece k's last sample is piece k+1's first configuration, so
rows [start, stop) of :class:`Segment` k hold its samples up to, not including, that
shared configuration (the last piece keeps its end). Joints are continuous across
segments, and every join is at rest.

Per row: ``path_m`` is the signed distance along the tool's path on the part from its
seam's start (−δ on the approach, σ on the seam, L + δ on the retract; NaN on links),
which is where process I/O switches (``tool.process_io``, leads in mm along the path).
"""

from __future__ import annotations

import dataclasses

import numpy as np

SEGMENT_KINDS = ("link", "approach", "process", "retract")


@dataclasses.dataclass(frozen=True)
class Piece:
    """One motion of the job before it is laid out: kind, seam name ("" for links),
    t (N,) from 0 [s], q (N, 6) [rad], qd (N, 6) [rad/s], path_m (N,) [m] (see module)."""

    kind: str
    seam: str
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    path_m: np.ndarray


@dataclasses.dataclass(frozen=True)
class Segment:
    """Rows [start, stop) of the job's samples: ``kind`` of ``seam`` ("" for links)."""

    kind: str
    seam: str
    start: int
    stop: int
    t_start: float
    t_stop: float

    @property
    def label(self) -> str:
        """``link`` or ``approach:<seam>``, ``process:<seam>``, ``retract:<seam>``:
        the trajectory.csv ``segment`` column (the contract)."""
        return "link" if self.kind == "link" else f"{self.kind}:{self.seam}"


@dataclasses.dataclass(frozen=True)
class JobSamples:
    """The job's samples: t (N,) [s], q, qd (N, 6), path_m (N,) [m], segments."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    path_m: np.ndarray
    segments: list[Segment]

    def labels(self) -> np.ndarray:
        """(N,) each row's segment label."""
        out = np.empty(len(self.t), dtype=object)
        for segment in self.segments:
            out[segment.start : segment.stop] = segment.label
        return out

    def segment_at(self, t: float) -> Segment:
        """The segment running at time t [s]."""
        for segment in self.segments:
            if t < segment.t_stop:
                return segment
        return self.segments[-1]


def lay_out(pieces: list[Piece]) -> JobSamples:
    """Concatenate pieces end to end (see the module docstring).

    Raises:
        ValueError: a piece does not start where the previous one ended (1e-6 rad).
    """
    t, q, qd, path, segments = [], [], [], [], []
    row, clock = 0, 0.0
    for k, piece in enumerate(pieces):
        assert piece.kind in SEGMENT_KINDS, piece.kind
        if k and np.abs(piece.q[0] - pieces[k - 1].q[-1]).max() > 1e-6:
            raise ValueError(
                f"job: {piece.kind} {piece.seam} does not start where "
                f"{pieces[k - 1].kind} {pieces[k - 1].seam} ends"
            )
        keep = len(piece.t) if k == len(pieces) - 1 else len(piece.t) - 1
        t.append(clock + piece.t[:keep])
        q.append(piece.q[:keep])
        qd.append(piece.qd[:keep])
        path.append(piece.path_m[:keep])
        duration = float(piece.t[-1])
        segments.append(Segment(piece.kind, piece.seam, row, row + keep, clock, clock + duration))
        row, clock = row + keep, clock + duration
    return JobSamples(
        np.concatenate(t), np.concatenate(q), np.concatenate(qd), np.concatenate(path), segments
    )
