"""Cell shapes for collision checks: Drake shapes, the original meshes and exact distances.

A :class:`~offline_prog.config.cell.ShapeConfig` (sizes in mm at the edge) becomes a
:class:`CellShape` in SI units, posed in its owner's frame O (P for the part, T for the
tool, I for obstacles, E for the gripper) by X_OG, G being the shape's own frame
(primitives centred on G, cylinders and capsules along G's z, like Drake and FCL). Drake
uses a mesh's convex hull for collision, so a mesh is decomposed into convex pieces with
CoACD (Wei et al., "Approximate Convex Decomposition for 3D Meshes with Collision-Aware
Concavity and Tree Search", SIGGRAPH 2022), cached on disk by content hash and scale; the
original triangle mesh is kept for the exact distances of :func:`exact_distance`
(python-fcl on a BVH of the triangles).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from pydrake.geometry import Box, Capsule, Convex, Cylinder, Mesh, Shape, Sphere
from pydrake.math import RigidTransform

from offline_prog.config.cell import GRIPPER_MESH_NAME, Cell, transform
from offline_prog.config.safe_yaml import short_repr
from offline_prog.config.unit_slips import large_mesh
from offline_prog.errors import TravellingError
from offline_prog.scene.mesh_cache import as_obj, convex_pieces

if TYPE_CHECKING:  # trimesh costs ~0.5 s to import; loaded where a mesh is used
    import trimesh

KINDS = ("box", "cylinder", "sphere", "capsule", "mesh")
MESH_SCALES = {"m": 1.0, "mm": 1e-3}


class ShapeError(TravellingError, ValueError):
    """A bad shape entry; str() is one line ``key: reason`` (``key`` like ``obstacles[2]``)."""

    def __init__(self, key: str, reason: str):
        self.key, self.reason = key, reason
        super().__init__(f"{key}: {reason}")


@dataclasses.dataclass(frozen=True, eq=False)
class CellShape:
    """One named shape of the cell.

    Attributes:
        name: unique name in the cell (used in reports and ``allowed_contact``).
        kind: box | cylinder | sphere | capsule | mesh.
        X_OG: the shape frame G in its owner's frame O (P, T, I or E).
        size_m: box (x, y, z), sphere (r,), cylinder and capsule (r, length) [m]; () for meshes.
        mesh: the original triangle mesh in G [m] (meshes only).
        pieces: OBJ files of the convex pieces in G [m] (meshes only).
        visual_file: OBJ of the original mesh in G [m] (meshes only).
    """

    name: str
    kind: str
    X_OG: RigidTransform
    size_m: tuple[float, ...] = ()
    mesh: trimesh.Trimesh | None = None
    pieces: tuple[Path, ...] = ()
    visual_file: Path | None = None

    def collision_shapes(self) -> list[Shape]:
        """Drake shapes in G: the primitive, or one Convex per piece of a mesh."""
        if self.kind == "mesh":
            return [Convex(str(piece)) for piece in self.pieces]
        return [_drake_primitive(self.kind, self.size_m)]

    def visual_shape(self) -> Shape:
        """The Drake shape to draw (the original mesh, not its pieces)."""
        if self.kind == "mesh":
            return Mesh(str(self.visual_file))
        return _drake_primitive(self.kind, self.size_m)


def _drake_primitive(kind: str, size: tuple[float, ...]) -> Shape:
    return {"box": Box, "sphere": Sphere, "cylinder": Cylinder, "capsule": Capsule}[kind](*size)


def _positive(key: str, name: str, value, count: int) -> tuple[float, ...]:
    values = [value] if count == 1 and not isinstance(value, list) else value
    if value is None:
        raise ShapeError(key, f"missing for the {name!r} shape")
    if not (len(values) == count and all(np.isfinite(v) and v > 0 for v in values)):
        got = short_repr(value)
        raise ShapeError(key, f"expected {count} positive number(s) for {name!r}, got {got}")
    return tuple(float(v) * 1e-3 for v in values)


def _mesh_scale(key: str, units: str, name: str) -> float:
    if units not in MESH_SCALES:
        raise ShapeError(key, f"{units!r} for {name!r} (expected m or mm)")
    return MESH_SCALES[units]


def load_shape(config, base_dir: Path, *, key: str) -> CellShape:
    """The CellShape of a ShapeConfig (sizes in mm, mesh files relative to base_dir).

    Args:
        config: a :class:`~offline_prog.config.cell.ShapeConfig`.
        base_dir: the cell file's folder.
        key: where the entry is in the cell file, e.g. ``"tool.geometry[0]"`` (for errors).

    Raises:
        ShapeError: one line naming the key, the shape and the problem.
    """
    name, kind = config.name, config.shape
    if not name:
        raise ShapeError(f"{key}.name", "missing (every shape needs a name)")
    pose = transform(config.pose)
    if kind == "box":
        return CellShape(name, kind, pose, _positive(f"{key}.size_mm", name, config.size_mm, 3))
    if kind == "sphere":
        return CellShape(name, kind, pose, _positive(f"{key}.radius_mm", name, config.radius_mm, 1))
    if kind in ("cylinder", "capsule"):
        (radius,) = _positive(f"{key}.radius_mm", name, config.radius_mm, 1)
        (length,) = _positive(f"{key}.length_mm", name, config.length_mm, 1)
        return CellShape(name, kind, pose, (radius, length))
    if kind == "mesh":
        if not config.mesh:
            raise ShapeError(f"{key}.mesh", f"missing for the mesh shape {name!r}")
        scale = _mesh_scale(f"{key}.mesh_units", config.mesh_units, name)
        return mesh_shape(name, Path(base_dir) / config.mesh, scale, X_OG=pose, key=f"{key}.mesh")
    raise ShapeError(f"{key}.shape", f"unknown {kind!r} for {name!r} (expected {', '.join(KINDS)})")


def mesh_shape(
    name: str, file: Path, scale: float, *, X_OG: RigidTransform | None = None, key: str = "mesh"
) -> CellShape:
    """A mesh file (STL/OBJ/PLY/GLB) as a CellShape: original mesh plus convex pieces [m].

    The mesh read is kept (the last MESHES_KEPT files, by path, size, modification time
    and scale): a session re-plans and placement builds a cell per candidate from the
    same files. The kept mesh is shared: nothing changes a CellShape's mesh in place.
    """
    file = Path(file)
    try:
        if not file.is_file():
            raise ValueError("no such file")
        stat = file.stat()
        cache_key = (str(file.resolve()), stat.st_size, stat.st_mtime_ns, scale)
        kept = _meshes.get(cache_key)
        if kept is None:
            kept = _read_mesh(file, scale)
    except Exception as error:  # trimesh raises many kinds; report one line
        reason = (str(error).splitlines() or [""])[0] or type(error).__name__
        raise ShapeError(key, f"cannot read {str(file)!r} for {name!r} ({reason})") from None
    mesh, extent = kept
    units_key = key.rsplit(".", 1)[0] + ".mesh_units"  # part.model -> part.mesh_units
    too_large = large_mesh(extent, set_units=f"set {units_key}: mm")
    if too_large:  # before CoACD, which would take minutes on it
        raise ShapeError(key, f"{str(file)!r} for {name!r} is {too_large}")
    visual = as_obj(file, scale)
    pieces = (visual,) if mesh.is_convex else convex_pieces(file, scale, mesh)
    _meshes[cache_key] = kept
    while len(_meshes) > MESHES_KEPT:
        _meshes.pop(next(iter(_meshes)), None)
    return CellShape(name, "mesh", X_OG or RigidTransform(), (), mesh, pieces, visual)


MESHES_KEPT = 4
_meshes: dict[tuple, tuple] = {}  # (path, size, mtime, scale) ↦ (mesh [m], extent [m])


def _read_mesh(file: Path, scale: float) -> tuple:
    """(the triangle mesh scaled to metres, its largest extent [m])."""
    import trimesh

    mesh = trimesh.load(file, force="mesh")
    if len(mesh.faces) == 0:
        raise ValueError("no triangles")
    mesh.apply_scale(scale)
    return mesh, float(max(mesh.extents))


@dataclasses.dataclass(frozen=True)
class CellGeometry:
    """The cell's shapes by owner, and the pairs of names whose contact is intended.

    The gripper's shapes are posed in the flange frame E (empty: no gripper modelled)."""

    part: list[CellShape]
    tool: list[CellShape]
    obstacles: list[CellShape]
    allowed_contact: list[tuple[str, str]]
    gripper: list[CellShape] = dataclasses.field(default_factory=list)


def cell_geometry(cell: Cell, cell_file: Path) -> CellGeometry:
    """The shapes a cell file gives (part.mesh named part.name, gripper.mesh named
    "gripper", then the geometry of part, tool, obstacles and gripper).

    Raises:
        ShapeError: a bad shape entry (one line, naming the key).
    """
    base = Path(cell_file).parent
    part = []
    if cell.part.mesh:
        scale = _mesh_scale("part.mesh_units", cell.part.mesh_units, cell.part.name)
        part.append(mesh_shape(cell.part.name, base / cell.part.mesh, scale, key="part.mesh"))
    if cell.part.model:  # STEP (tessellated) or a mesh: the model the seams come from
        from offline_prog.scene.part_model import model_mesh

        try:
            mesh_file, scale = model_mesh(cell, base)
        except ValueError as error:
            raise ShapeError("part.model", str(error)) from None
        part.append(mesh_shape(cell.part.name, mesh_file, scale, key="part.model"))
    part += _shapes(cell.part.geometry, base, "part.geometry")
    tool = _shapes(cell.tool.geometry, base, "tool.geometry")
    obstacles = _shapes(cell.obstacles, base, "obstacles")
    allowed = []
    for i, pair in enumerate(cell.allowed_contact):
        if len(pair) != 2:
            raise ShapeError(f"allowed_contact[{i}]", f"expected [name, name], got {pair!r}")
        allowed.append((pair[0], pair[1]))
    return CellGeometry(part, tool, obstacles, allowed, gripper_shapes(cell, base))


def _shapes(configs, base: Path, key: str) -> list[CellShape]:
    return [load_shape(c, base, key=f"{key}[{i}]") for i, c in enumerate(configs)]


def gripper_shapes(cell: Cell, base: Path) -> list[CellShape]:
    """The gripper's shapes in E: its mesh (named "gripper") and its geometry."""
    gripper = cell.gripper
    if gripper is None:
        return []
    shapes = []
    if gripper.mesh:
        scale = _mesh_scale("gripper.mesh_units", gripper.mesh_units, GRIPPER_MESH_NAME)
        shapes.append(mesh_shape(GRIPPER_MESH_NAME, base / gripper.mesh, scale, key="gripper.mesh"))
    return shapes + _shapes(gripper.geometry, base, "gripper.geometry")
