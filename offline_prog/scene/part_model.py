"""The part's collision and visual geometry from its model (``part.model``), the same
file its ``cad:`` seams come from, so the two cannot drift apart.

A STEP solid is tessellated with Open CASCADE within TESSELLATION_TOLERANCE_MM of its
exact surface (cached by content hash and tolerance, as an STL in mm), then handled as
any mesh: the original triangles for exact distances, CoACD convex pieces for Drake.
A mesh model is used as it is, in ``part.mesh_units``.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from offline_prog.config.cad_keys import model_kind
from offline_prog.config.cell import Cell
from offline_prog.constants import UNIT_SCALE
from offline_prog.scene.mesh_cache import mesh_cache_dir

MM = 1e-3


def tessellated_step(file: Path) -> tuple[Path, float]:
    """An STL [mm] of a STEP solid within the tessellation tolerance, cached; and that
    tolerance [mm].

    Raises:
        ValueError: not a readable STEP solid (one line).
    """
    from offline_prog.cad.step_geometry import TESSELLATION_TOLERANCE_MM, tessellate
    from offline_prog.cad.step_model import ModelError, read_step

    tolerance = TESSELLATION_TOLERANCE_MM
    data = Path(file).read_bytes()
    key = hashlib.sha256(data + f"step {tolerance!r}".encode()).hexdigest()[:20]
    target = mesh_cache_dir() / f"{key}.stl"
    if not target.exists():
        import trimesh

        try:
            model = read_step(file)
        except ModelError as error:
            raise ValueError(f"{Path(file).name}: {error}") from None
        vertices, triangles, _ = tessellate(model.shape, tolerance)
        target.parent.mkdir(parents=True, exist_ok=True)
        temp = target.with_suffix(f".{os.getpid()}.tmp")
        trimesh.Trimesh(vertices, triangles).export(temp, file_type="stl")
        os.replace(temp, target)
    return target, tolerance


def model_mesh(cell: Cell, base: Path) -> tuple[Path, float]:
    """The mesh file of the part's model and its metres per unit: a STEP solid's
    tessellation, or the mesh model in ``part.mesh_units``.

    Raises:
        ValueError: a STEP file that is not a readable solid.
    """
    file = base / cell.part.model
    if model_kind(cell.part.model) == "step":
        return tessellated_step(file)[0], MM
    return file, UNIT_SCALE[cell.part.mesh_units]
