"""JobProgramData: what a controller program of a whole job needs, saved with the plan.

A job is one sampled trajectory in named segments (``link``, ``approach:<seam>``,
``process:<seam>``, ``retract:<seam>``; see ``job.assemble``). ``job`` holds every row as
a :class:`ProgramData` (``sigma`` is the signed distance along the tool's path on the
part from the seam's start, NaN on links; ``X_PF`` is the tool frame T in P, which is
the process frame F on the seams and the backed-off frame on approach and retract);
``seams`` holds each seam's process rows exactly as a one-seam plan's ProgramData, so the
one-seam point selection applies to them unchanged. Process I/O: ``digital`` (N,) 0/1
and ``analog`` (N,) per row, and the switching positions along each seam.

Saved as ``plan.npz`` (the job's rows, under the one-seam keys) plus ``job.npz`` (the
segments, the link waypoints, the I/O and each seam's data), so ``offline-prog export``
re-exports without re-planning.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from offline_prog.atomic import atomic_stream
from offline_prog.export.program import ProgramData

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
class ProcessIo:
    """``tool.process_io`` in SI units: the digital output switched ``on_lead_m`` before
    each seam's start and ``off_lead_m`` before its end (None: no switching), and the
    analog flow output value = offset + per_mps · v_TCP in [min, max] (None: no flow)."""

    digital_output: int | None = None
    on_lead_m: float = 0.0
    off_lead_m: float = 0.0
    analog_output: int | None = None
    per_mps: float = 0.0
    offset: float = 0.0
    min: float = 0.0
    max: float = 10.0


@dataclasses.dataclass(frozen=True)
class JobProgramData:
    """A finished job, as the program writers see it.

    Attributes:
        job: every row of the job (see the module docstring), header fields included.
        segments: in run order; the last one ends at the last row.
        seams: each seam's process rows as a one-seam ProgramData, in run order.
        seam_names: (n_seams,) in run order; seam_lengths_m: their path lengths L [m].
        link_waypoints: per link, (K, 6) joint targets [rad] a controller moves through
            to fine points (the first is where the link starts).
        process_io: the process outputs, or None.
        digital: (N,) 0/1 state of the process output per row, or None.
        analog: (N,) the flow output's value per row, or None.
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

    def load_robot(self):
        """The job's RobotModel (ProgramData.load_robot)."""
        return self.job.load_robot()

    def switch_positions(self, k: int) -> tuple[float, float] | None:
        """(on, off) positions [m] of seam k's process output along its tool path from
        its start (on: −lead, on the approach when positive), or None."""
        io = self.process_io
        if io is None or io.digital_output is None:
            return None
        return -io.on_lead_m, self.seam_lengths_m[k] - io.off_lead_m

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
            "seams": [],
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
            np.savez_compressed(stream, meta=json.dumps(meta), **arrays)
        return target

    @classmethod
    def load(cls, folder: Path) -> JobProgramData | None:
        """Read a job's plan folder; None when the folder holds a one-seam plan.

        Raises:
            ValueError: one line naming the file when it is unreadable.
        """
        file = Path(folder) / JOB_FILE
        if not file.is_file():
            return None
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
            return cls(
                job,
                tuple(JobSegment(**s) for s in meta["segments"]),
                seams,
                tuple(meta["seam_names"]),
                tuple(meta["seam_lengths_m"]),
                tuple(arrays[f"link_{k}"] for k in range(n_links)),
                None if io is None else ProcessIo(**io),
                arrays.get("digital"),
                arrays.get("analog"),
            )
        except Exception as error:  # truncated or foreign: zipfile, zlib, json, keys ...
            raise ValueError(f"{file}: unreadable, not a complete job ({error})") from None
