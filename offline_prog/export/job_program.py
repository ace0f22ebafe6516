"""JobProgramData: what a controller program of a whole job needs, saved with the plan.

A job is one sampled trajectory in named segments (``link``, ``approach:<seam>``,
``process:<seam>``, ``retract:<seam>``; see ``job.assemble``). ``job`` holds every row as
a :class:`ProgramData` (``path_m`` is the signed distance along the tool's path on the
part from the seam's start, NaN on links; ``X_PT`` is the tool frame T in P, which is
the process frame F on the seams and the backed-off frame on approach and retract);
``seams`` holds each seam's process rows as a ProgramData of their own (with the
continuous path on a fine grid), where the point selection (``export.points``) runs.
Process I/O: ``digital`` (N,) 0/1 and ``analog`` (N,) per row, and the plan's I/O
events (``offline_prog.io_events``): the writers translate them into statements and
never recompute a switch position.

Saved as ``plan.npz`` (the job's rows) plus ``job.npz`` (the segments, the link
waypoints, the I/O and each seam's data), so ``offline-prog export`` re-exports without
re-planning. A folder written before every plan was a job (a ``plan.npz`` of one seam,
no ``job.npz``) is refused: re-plan it.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
from pathlib import Path

import numpy as np

from offline_prog.atomic import atomic_stream
from offline_prog.export.program import PLAN_FILE, ProgramData
from offline_prog.io_events import IoEvent, ProcessIo, Signal

JOB_FILE = "job.npz"


@dataclasses.dataclass(frozen=True)
class JobSegment:
    """Rows [start, stop) of the job: ``kind`` (link | approach | process | retract) of
    ``seam`` ("" for links). Row ``stop`` (the next segment's first) is where it ends."""

    kind: str
    seam: str
    start: int
    stop: int

    @property
    def label(self) -> str:
        return "link" if self.kind == "link" else f"{self.kind}:{self.seam}"


@dataclasses.dataclass(frozen=True)
class JobProgramData:
    """A finished job, as the program writers see it.

    Attributes:
        job: every row of the job (see the module docstring), header fields included.
        segments: in run order; the last one ends at the last row.
        seams: each seam's process rows as a ProgramData, in run order.
        seam_names: (n_seams,) in run order; seam_lengths_m: their path lengths L [m].
        link_waypoints: per link, (K, 6) joint targets [rad] a controller moves through
            to fine points (the first is where the link starts).
        process_io: the process outputs, or None.
        digital: (N,) 0/1 state of the process output per row, or None.
        analog: (N,) the flow output's command per row [V], or None.
        events: the plan's I/O events in time order (``io_events.IoEvent``).
    """

    job: ProgramData
    segments: tuple[JobSegment, ...]
    seams: tuple[ProgramData, ...]
    seam_names: tuple[str, ...]
    seam_lengths_m: tuple[float, ...]
    link_waypoints: tuple[np.ndarray, ...]
    process_io: ProcessIo | None = None
    digital: np.ndarray | None = None
    analog: np.ndarray | None = None
    events: tuple[IoEvent, ...] = ()

    @property
    def feasible(self) -> bool:
        return self.job.feasible

    @property
    def failure(self) -> str:
        return self.job.failure

    @property
    def robot(self) -> str:
        return self.job.robot

    @property
    def language(self) -> str | None:
        return self.job.language

    def seam_events(self, seam: str, signal: Signal = Signal.DIGITAL) -> list[IoEvent]:
        """The events of one seam and output kind, in time order."""
        return [e for e in self.events if e.seam == seam and e.signal is signal]

    def load_robot(self):
        """The job's RobotModel (ProgramData.load_robot)."""
        return self.job.load_robot()

    def rows(self, segment: JobSegment) -> slice:
        """The rows of a segment and the row where it ends: [start, stop]."""
        return slice(segment.start, min(segment.stop + 1, len(self.job.t)))

    def save(self, folder: Path) -> Path:
        """Write ``folder/plan.npz`` (the job's rows) and ``folder/job.npz``, atomically."""
        self.job.save(folder)
        meta = {
            "segments": [dataclasses.asdict(s) for s in self.segments],
            "seam_names": list(self.seam_names),
            "seam_lengths_m": list(self.seam_lengths_m),
            "process_io": None if self.process_io is None else dataclasses.asdict(self.process_io),
            "events": [e.as_dict() for e in self.events],
            "seams": [],
            # Which plan.npz these belong to: its rows and when it was made.
            "rows": len(self.job.t),
            "generated": self.job.generated,
        }
        arrays = {f"link_{k}": w for k, w in enumerate(self.link_waypoints)}
        for name in ("digital", "analog"):
            if getattr(self, name) is not None:
                arrays[name] = getattr(self, name)
        for k, seam in enumerate(self.seams):
            seam_meta, seam_arrays = seam.packed()
            meta["seams"].append(seam_meta)
            arrays |= {f"seam{k}_{key}": value for key, value in seam_arrays.items()}
        target = Path(folder) / JOB_FILE
        with atomic_stream(target) as stream:
            np.savez(stream, meta=json.dumps(meta), **arrays)  # uncompressed, as plan.npz
        return target

    @classmethod
    def load(cls, folder: Path) -> JobProgramData:
        """Read a job's plan folder.

        Raises:
            ValueError: one line naming the file when it is unreadable, missing, from
                another plan, or a one-seam plan written before every plan was a job.
        """
        file = Path(folder) / JOB_FILE
        if not file.is_file():
            if ProgramData.load(folder).whole_job:  # (raises for a folder without a plan)
                raise ValueError(
                    f"{file}: missing: {Path(folder) / PLAN_FILE} holds a whole job's rows, "
                    "which export only with their job.npz (plan the cell again)"
                )
            raise ValueError(
                f"{Path(folder) / PLAN_FILE}: a one-seam plan written before every plan was "
                "a job (no job.npz): re-plan it with this version"
            )
        job = ProgramData.load(folder)
        try:
            with np.load(file) as data:
                meta = json.loads(str(data["meta"]))
                arrays = {name: np.asarray(data[name]) for name in data.files if name != "meta"}
            seams = tuple(
                ProgramData.unpacked(
                    seam_meta,
                    {
                        key.removeprefix(f"seam{k}_"): value
                        for key, value in arrays.items()
                        if key.startswith(f"seam{k}_")
                    },
                )
                for k, seam_meta in enumerate(meta["seams"])
            )
            n_links = sum(1 for s in meta["segments"] if s["kind"] == "link")
            io = meta["process_io"]
            data = cls(
                job,
                tuple(JobSegment(**s) for s in meta["segments"]),
                seams,
                tuple(meta["seam_names"]),
                tuple(meta["seam_lengths_m"]),
                tuple(arrays[f"link_{k}"] for k in range(n_links)),
                None if io is None else ProcessIo(**io),
                arrays.get("digital"),
                arrays.get("analog"),
                tuple(IoEvent.from_dict(e) for e in meta["events"]),
            )
            rows, generated = meta["rows"], meta["generated"]
        except Exception as error:  # truncated or foreign: zipfile, zlib, json, keys ...
            raise ValueError(f"{file}: unreadable, not a complete job ({error})") from None
        why = data._disagreement(rows, generated)
        if why:
            raise ValueError(f"{file}: does not belong to {Path(folder) / PLAN_FILE} ({why})")
        return data

    def _disagreement(self, rows: int, generated: str) -> str:
        """Why job.npz and plan.npz are not one plan's files ("" when they are)."""
        n = len(self.job.t)
        if not self.job.whole_job:
            return "plan.npz is a one-seam plan"
        if rows != n or generated != self.job.generated:
            return f"made with {rows} rows at {generated}, plan.npz has {n} rows made at " + (
                self.job.generated
            )
        ends = [self.segments[0].start] + [s.stop for s in self.segments]
        if ends[0] != 0 or ends[-1] != n or any(a > b for a, b in itertools.pairwise(ends)):
            return f"its segments do not cover the {n} rows"
        for name in ("digital", "analog"):
            column = getattr(self, name)
            if column is not None and len(column) != n:
                return f"its {name} column has {len(column)} rows, not {n}"
        unknown = {e.seam for e in self.events} - set(self.seam_names)
        if unknown or {s.seam for s in self.segments if s.seam} != set(self.seam_names):
            return "its seams and segments disagree"
        return ""
