"""The cell-file keys of a seam taken from the part's CAD model (issue 26's contract).

``part.model`` names the part's model (STEP, or a STL/OBJ/PLY mesh); a seam (``path:``
or an entry of ``seams:``) with a ``cad:`` block takes its points and surface normals
from it::

    cad:
      loop: {face_near_mm: [150, 100, 10]}        # the outer loop of the nearest face
      chain: {near_mm: [[0, 0, 10], [300, 0, 10]]}  # or: connected edges, first to last
      normal: {face_near_mm: [150, -5, 5]}        # the face giving n (default: the loop's)
      offset_mm: 0.0                              # move the seam along n
      file: other.step                            # default: part.model

Points are in the part frame P, in mm (the keys say so). A STEP model is read in mm
(the reader converts the file's units); a mesh is in its declared units.
"""

import dataclasses

from offline_prog.errors import InputError

REQUIRED = {"required": True}


def _required():
    return dataclasses.field(default=None, metadata=REQUIRED)


@dataclasses.dataclass
class CadLoop:
    """The outer loop (boundary) of the model face nearest ``face_near_mm`` (in P, mm)."""

    face_near_mm: list[float] | None = _required()


@dataclasses.dataclass
class CadChain:
    """Connected model edges from the one nearest the first point to the one nearest the
    last, through those nearest the points between (in P, mm)."""

    near_mm: list[list[float]] | None = _required()


@dataclasses.dataclass
class CadNormal:
    """The face (nearest ``face_near_mm``, in P, mm) whose normal the seam takes."""

    face_near_mm: list[float] | None = _required()


@dataclasses.dataclass
class CadSeamConfig:
    """A seam from the CAD model: exactly one of loop or chain; normal, offset, file."""

    loop: CadLoop | None = None
    chain: CadChain | None = None
    normal: CadNormal | None = None
    offset_mm: float = 0.0  # along n (into the surface; negative: off it)
    file: str | None = None  # default: part.model


STEP_SUFFIXES = (".step", ".stp")
MESH_SUFFIXES = (".stl", ".obj", ".ply")
MAX_OFFSET_MM = 100.0  # cad.offset_mm: a bead beside an edge, not another seam


def model_kind(name: str) -> str | None:
    """``"step"``, ``"mesh"`` or None (not a model file) from a file name's suffix."""
    suffix = "." + name.rsplit(".", 1)[-1].lower() if "." in name else ""
    return "step" if suffix in STEP_SUFFIXES else "mesh" if suffix in MESH_SUFFIXES else None


def check_part_model(file, cell, check_data_file) -> None:
    """``part.model``: a STEP or mesh file that exists; not together with part.mesh."""
    model = cell.part.model
    if model is None:
        return
    if cell.part.mesh is not None:
        raise InputError(file, "part.model", "give part.model or part.mesh, not both")
    if model_kind(model) is None:
        raise InputError(
            file, "part.model", f"{model!r} is not a STEP (.step, .stp) or mesh (.stl, .obj, .ply)"
        )
    check_data_file(file, "part.model", file.parent / model)


def check_cad(file, key: str, path, cell, check_data_file) -> None:
    """A seam's ``cad:`` block: one of loop or chain, points of 3 numbers, a model file
    of a known kind, units that fit it. A loop is a closed seam: ``closed: false`` on it
    is refused (``load_cell`` makes a loop closed when the key is not given)."""
    cad, where = path.cad, f"{key}.cad"
    if (cad.loop is None) == (cad.chain is None):
        raise InputError(file, where, "give exactly one of loop or chain")
    for name in ("normal", "normal_from_mesh"):
        if getattr(path, name):
            raise InputError(
                file, f"{key}.{name}", "a cad: seam takes its normal from the model (cad.normal)"
            )
    points = [("loop.face_near_mm", cad.loop.face_near_mm)] if cad.loop else []
    if cad.chain is not None:
        if len(cad.chain.near_mm) < 2:
            raise InputError(file, f"{where}.chain.near_mm", "needs at least two points")
        points += [(f"chain.near_mm[{i}]", p) for i, p in enumerate(cad.chain.near_mm)]
        if cad.normal is None:
            raise InputError(
                file,
                f"{where}.normal.face_near_mm",
                "missing: an edge joins two faces; name the one whose normal the seam takes",
            )
    if cad.normal is not None:
        points.append(("normal.face_near_mm", cad.normal.face_near_mm))
    for name, point in points:
        if len(point) != 3:
            raise InputError(file, f"{where}.{name}", f"expected [x, y, z] in mm, got {point}")
    if not abs(cad.offset_mm) <= MAX_OFFSET_MM:
        raise InputError(file, f"{where}.offset_mm", f"must be within ±{MAX_OFFSET_MM:g} mm")
    model_key = f"{where}.file" if cad.file else "part.model"
    model = cad.file or cell.part.model
    if model is None:
        raise InputError(file, f"{where}.file", "no model: set part.model (or cad.file)")
    kind = model_kind(model)
    if kind is None:
        raise InputError(
            file, model_key, f"{model!r} is not a STEP (.step, .stp) or mesh (.stl, .obj, .ply)"
        )
    check_data_file(file, model_key, file.parent / model)
    if kind == "step" and path.units not in (None, "mm"):
        raise InputError(
            file, f"{key}.units", "a STEP model is read in mm (its own units are converted)"
        )
    if cad.loop is not None and path.closed is False:
        raise InputError(
            file,
            f"{key}.closed",
            "false, but a loop comes back to its start (leave closed out; an open run of "
            "edges is a chain)",
        )
