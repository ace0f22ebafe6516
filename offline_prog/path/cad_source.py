"""Seam points and normals from the part's CAD model (a seam's ``cad:`` keys).

The model (``cad.file``, default ``part.model``) is a STEP file, read exactly with Open
CASCADE, or a STL/OBJ/PLY mesh; :mod:`offline_prog.cad` picks the loop or chain and
samples it with the normal face's outward normals. Here they become the path's points
r_j in P [m] with normals into the surface (the project's convention, as for CSV
normals) and the exact seam the fit error is measured against. Open CASCADE is
imported only here, only for a STEP model.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from offline_prog.config.cad_keys import model_kind
from offline_prog.config.cell import Cell
from offline_prog.constants import UNIT_SCALE
from offline_prog.errors import InputError
from offline_prog.path.exact_seam import ExactSeam
from offline_prog.path.sources import PathPoints, clean_points

MM = 1e-3  # metres per millimetre


@functools.lru_cache(maxsize=4)
def _model(file: str, kind: str, mm_per_unit: float, set_units: str, _stamp: tuple):
    """The model of a file, read once per content stamp (a job's seams share it)."""
    if kind == "step":
        from offline_prog.cad.step_model import read_step

        return read_step(Path(file))
    from offline_prog.cad.mesh_model import read_mesh

    return read_mesh(Path(file), mm_per_unit, set_units=set_units)


def load_model(
    file: Path, kind: str, mm_per_unit: float = 1.0, *, set_units: str = "set mesh_units: mm"
):
    """A STEP (``kind="step"``) or mesh model of a file [mm], cached while unchanged
    (``set_units``: how the user gives a mesh's unit, for the hint of a mesh too large).

    Raises:
        cad.step_model.ModelError: unreadable, not a solid, or a mesh larger than a
            cell (one line).
    """
    stat = Path(file).stat()
    return _model(str(file), kind, mm_per_unit, set_units, (stat.st_mtime_ns, stat.st_size))


def model_units(cell: Cell, cad, units: str | None) -> float:
    """Millimetres per unit of the seam's model: a STEP file is read in mm; a mesh is in
    the seam's ``units``, else ``part.mesh_units``."""
    if model_kind(cad.file or cell.part.model) == "step":
        return 1.0
    return UNIT_SCALE[units or cell.part.mesh_units] / MM


def cad_samples(file: Path, cell: Cell, key: str = "path"):
    """The :class:`~offline_prog.cad.seam_samples.SeamSamples` of ``cell.path.cad``.

    Raises:
        InputError: the model cannot be read or is not a solid (naming ``part.model`` or
            ``path.cad.file``), or a point picks nothing or two things (naming its key).
    """
    from offline_prog.cad.picking import PickError
    from offline_prog.cad.step_model import ModelError

    path = cell.path
    cad = path.cad
    name = cad.file or cell.part.model
    model_key = f"{key}.cad.file" if cad.file else "part.model"
    kind = model_kind(name)
    normal = None if cad.normal is None else cad.normal.face_near_mm
    try:
        units_key = f"{key}.units" if path.units else "part.mesh_units"
        model = load_model(
            file.parent / name,
            kind,
            model_units(cell, cad, path.units),
            set_units=f"set {units_key}: mm",
        )
        if kind == "step":
            from offline_prog.cad import step_seams as seams
        else:
            from offline_prog.cad import mesh_seams as seams
        if cad.loop is not None:
            return seams.loop_seam(
                model, cad.loop.face_near_mm, normal, offset_mm=cad.offset_mm, key=f"{key}.cad"
            )
        return seams.chain_seam(
            model,
            cad.chain.near_mm,
            normal,
            offset_mm=cad.offset_mm,
            closed=path.closed,
            key=f"{key}.cad",
        )
    except ModelError as error:
        raise InputError(file, model_key, f"{name}: {error}") from None
    except PickError as error:
        key_tail = error.key.replace(f"{key}.cad.closed", f"{key}.closed")
        raise InputError(file, key_tail, f"{name}: {error.reason}") from None


def cad_points(file: Path, cell: Cell) -> PathPoints:
    """The seam's points r_j in P [m] with normals into the surface, and its exact seam."""
    samples = cad_samples(file, cell)
    name = cell.path.cad.file or cell.part.model
    edges = ", ".join(str(e) for e in samples.edges)
    exact = ExactSeam(
        samples.reference * MM,
        samples.closed,
        samples.tolerance_mm * MM,
        samples.length_mm * MM,
        f"{name}, edges {edges}",
        tuple((np.asarray(p) * MM, turn) for p, turn in samples.corners),
    )
    points = clean_points(samples.p * MM, -samples.outward, closed=samples.closed)
    return PathPoints(points.p_PR, points.normals_P, points.closed, points.rows, exact)
