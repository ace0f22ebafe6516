"""The seams of a job, each as the one-seam pipeline sees it.

A cell gives either ``path:`` (one seam, the shorthand) or ``seams:``; each seam is a
processing path (every key of ``path:``) with a name, a direction, an optional own
speed, and its approach and retract. :func:`seam_inputs` turns seam k into the
:class:`~offline_prog.stages.Inputs` of the single-seam stages (paper §§2–4): the cell
with ``path`` set to the seam, its points in the direction asked, and its process speed
(``config.process_speed``: the one choice of ``seams[k].speed`` or ``motion.speed``;
the seam's cell keeps ``motion.speed`` as the cell gives it). Errors those stages raise
about ``path.*`` name ``seams[k].*``.
"""

from __future__ import annotations

import contextlib
import dataclasses

import numpy as np

from offline_prog.config.cell import Cell, JobConfig, PathConfig, SeamConfig, seam_moves_m
from offline_prog.config.process_speed import process_speed
from offline_prog.errors import InputError
from offline_prog.path.inputs import load_points
from offline_prog.path.sources import PathPoints
from offline_prog.stages import Inputs

SHORTHAND_NAME = "seam"  # the name of the one seam of a ``path:`` cell


def job_seams(cell: Cell) -> list[SeamConfig]:
    """The seams of a cell: ``seams:``, or ``path:`` as one seam named ``seam``."""
    if cell.seams:
        return list(cell.seams)
    fields = {f.name: getattr(cell.path, f.name) for f in dataclasses.fields(PathConfig)}
    return [SeamConfig(**fields, name=SHORTHAND_NAME)]


def job_config(cell: Cell) -> JobConfig:
    """The cell's ``job:``, or its defaults (home from the robot, the given order): a
    ``path:`` cell without ``job:`` is a one-seam job with these defaults."""
    return cell.job or JobConfig()


def seam_key(cell: Cell, k: int) -> str:
    """The cell-file key of seam k (``path`` for the shorthand)."""
    return "path" if not cell.seams else f"seams[{k}]"


@contextlib.contextmanager
def errors_named_for(key: str):
    """Re-raise an InputError about ``path...`` as one about ``key...`` (a seam)."""
    try:
        yield
    except InputError as error:
        if key == "path" or not error.key.startswith("path"):
            raise
        raise InputError(error.file, key + error.key[len("path") :], error.reason) from None


def reversed_points(points: PathPoints) -> PathPoints:
    """The same points run the other way; a closed contour keeps its start point."""
    order = np.arange(len(points.p_PR))[::-1]
    if points.closed:
        order = np.roll(order, 1)
    return dataclasses.replace(
        points,
        p_PR=points.p_PR[order],
        normals_P=None if points.normals_P is None else points.normals_P[order],
        rows=None if points.rows is None else points.rows[order],
    )


def seam_inputs(job: Inputs, k: int, *, reverse: bool = False) -> Inputs:
    """The single-seam Inputs of seam k of the job's cell, run forward or reversed.

    Raises:
        InputError: naming ``seams[k].<key>`` (or ``path.<key>``).
    """
    cell = job.cell
    seam = job_seams(cell)[k]
    fields = {f.name: getattr(seam, f.name) for f in dataclasses.fields(PathConfig)}
    if cell.seams and seam.points and seam.csv_seam is None and _has_seam_column(job.file, seam):
        fields["csv_seam"] = seam.name  # a CSV of several seams: this seam's rows
    seam_cell = dataclasses.replace(cell, path=PathConfig(**fields), seams=[])
    with errors_named_for(seam_key(cell, k)):
        points = load_points(job.file, seam_cell)
    if reverse:
        points = reversed_points(points)
    return dataclasses.replace(
        job,
        cell=seam_cell,
        points=points,
        speed=process_speed(cell, k),
        **seam_moves_m(seam.approach, seam.retract),
    )


def _has_seam_column(file, seam: SeamConfig) -> bool:
    """The seam's CSV has a ``seam`` column (its header's last name)."""
    try:
        with open(file.parent / seam.points, encoding="utf-8") as stream:
            for line in stream:
                if line.strip() and not line.startswith("#"):
                    return line.strip().lower().split(",")[-1].strip() == "seam"
    except OSError:
        return False
    return False
