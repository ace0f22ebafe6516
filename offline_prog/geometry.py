"""Cell shapes for collision checks: Drake shapes, the original meshes and exact distances.

A :class:`~offline_prog.cell.ShapeConfig` (sizes in mm at the edge) becomes a
:class:`CellShape` in SI units, posed in its owner's frame O (P for the part, T for the
tool, I for obstacles) by X_OG, G being the shape's own frame (primitives centred on G,
cylinders and capsules along G's z, like Drake and FCL). Drake uses a mesh's convex hull
for collision, so a mesh is decomposed into convex pieces with CoACD (Wei et al., "Approximate
Convex Decomposition for 3D Meshes with Collision-Aware Concavity and Tree Search", SIGGRAPH
2022), cached on disk by content hash and scale; the original triangle mesh is kept for the
exact distances of :func:`exact_distance` (python-fcl on a BVH of the triangles).
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import shutil
import tempfile
from pathlib import Path

import fcl
import numpy as np
import trimesh
from pydrake.geometry import Box, Capsule, Convex, Cylinder, Mesh, Shape, Sphere
from pydrake.math import RigidTransform

from offline_prog.cell import Cell, transform

KINDS = ("box", "cylinder", "sphere", "capsule", "mesh")
MESH_SCALES = {"m": 1.0, "mm": 1e-3}
# CoACD's concavity threshold (its default): smaller gives more, tighter pieces.
COACD_THRESHOLD = 0.05
COACD_SEED = 0


class ShapeError(ValueError):
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
        X_OG: the shape frame G in its owner's frame O (P, T or I).
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
        raise ShapeError(key, f"expected {count} positive number(s) for {name!r}, got {value!r}")
    return tuple(float(v) * 1e-3 for v in values)


def _mesh_scale(key: str, units: str, name: str) -> float:
    if units not in MESH_SCALES:
        raise ShapeError(key, f"{units!r} for {name!r} (expected m or mm)")
    return MESH_SCALES[units]


def load_shape(config, base_dir: Path, *, key: str) -> CellShape:
    """The CellShape of a ShapeConfig (sizes in mm, mesh files relative to base_dir).

    Args:
        config: a :class:`~offline_prog.cell.ShapeConfig`.
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
    """A mesh file (STL/OBJ/PLY/GLB) as a CellShape: original mesh plus convex pieces [m]."""
    from offline_prog.drake_cell import as_obj

    file = Path(file)
    try:
        if not file.is_file():
            raise ValueError("no such file")
        mesh = trimesh.load(file, force="mesh")
        if len(mesh.faces) == 0:
            raise ValueError("no triangles")
    except Exception as error:  # trimesh raises many kinds; report one line
        reason = (str(error).splitlines() or [""])[0] or type(error).__name__
        raise ShapeError(key, f"cannot read {str(file)!r} for {name!r} ({reason})") from None
    mesh.apply_scale(scale)
    visual = as_obj(file, scale)
    pieces = (visual,) if mesh.is_convex else convex_pieces(file, scale, mesh)
    return CellShape(name, "mesh", X_OG or RigidTransform(), (), mesh, pieces, visual)


def convex_pieces(file: Path, scale: float, mesh: trimesh.Trimesh) -> tuple[Path, ...]:
    """CoACD convex pieces of a mesh as OBJ files [m], cached by content hash and scale.

    Args:
        file: the mesh file (its bytes are the cache key, with scale and CoACD's settings).
        scale: metres per file unit.
        mesh: the file's mesh already scaled to metres.
    """
    import coacd

    from offline_prog.drake_cell import mesh_cache_dir

    settings = f"{scale!r} coacd {COACD_THRESHOLD!r} {COACD_SEED}".encode()
    key = hashlib.sha256(Path(file).read_bytes() + settings).hexdigest()[:20]
    target = mesh_cache_dir() / f"{key}.coacd"
    if not target.is_dir():
        coacd.set_log_level("error")
        parts = coacd.run_coacd(
            coacd.Mesh(mesh.vertices, mesh.faces), threshold=COACD_THRESHOLD, seed=COACD_SEED
        )
        target.parent.mkdir(parents=True, exist_ok=True)
        temp = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{key}."))
        for i, (vertices, faces) in enumerate(parts):
            piece = trimesh.Trimesh(vertices, faces, process=False)
            (temp / f"piece_{i:03d}.obj").write_text(trimesh.exchange.obj.export_obj(piece))
        try:
            os.rename(temp, target)
        except OSError:  # another process cached it first
            shutil.rmtree(temp, ignore_errors=True)
    return tuple(sorted(target.glob("piece_*.obj")))


@dataclasses.dataclass(frozen=True)
class CellGeometry:
    """The cell's shapes by owner, and the pairs of names whose contact is intended."""

    part: list[CellShape]
    tool: list[CellShape]
    obstacles: list[CellShape]
    allowed_contact: list[tuple[str, str]]


def cell_geometry(cell: Cell, cell_file: Path) -> CellGeometry:
    """The shapes a cell file gives (part.mesh named part.name, then part/tool/obstacles).

    Raises:
        ShapeError: a bad shape entry (one line, naming the key).
    """
    base = Path(cell_file).parent
    part = []
    if cell.part.mesh:
        scale = _mesh_scale("part.mesh_units", cell.part.mesh_units, cell.part.name)
        part.append(mesh_shape(cell.part.name, base / cell.part.mesh, scale, key="part.mesh"))
    part += [
        load_shape(c, base, key=f"part.geometry[{i}]") for i, c in enumerate(cell.part.geometry)
    ]
    tool = [
        load_shape(c, base, key=f"tool.geometry[{i}]") for i, c in enumerate(cell.tool.geometry)
    ]
    obstacles = [load_shape(c, base, key=f"obstacles[{i}]") for i, c in enumerate(cell.obstacles)]
    allowed = []
    for i, pair in enumerate(cell.allowed_contact):
        if len(pair) != 2:
            raise ShapeError(f"allowed_contact[{i}]", f"expected [name, name], got {pair!r}")
        allowed.append((pair[0], pair[1]))
    return CellGeometry(part, tool, obstacles, allowed)


@dataclasses.dataclass(frozen=True, eq=False)
class ExactShape:
    """A solid for exact distances: an FCL geometry in G and a point-inside test."""

    geometry: fcl.CollisionGeometry
    kind: str
    size_m: tuple[float, ...]
    mesh: trimesh.Trimesh | None = None

    def contains(self, p_GQ: np.ndarray) -> bool:
        """Whether the point Q (3,), from Go, expressed in G [m], is inside the solid."""
        x, y, z = p_GQ
        if self.kind == "box":
            return bool(np.all(np.abs(p_GQ) <= np.asarray(self.size_m) / 2))
        if self.kind == "sphere":
            return bool(np.linalg.norm(p_GQ) <= self.size_m[0])
        if self.kind == "cylinder":
            return bool(np.hypot(x, y) <= self.size_m[0] and abs(z) <= self.size_m[1] / 2)
        if self.kind == "capsule":
            z_axis = np.clip(z, -self.size_m[1] / 2, self.size_m[1] / 2)
            return bool(np.linalg.norm([x, y, z - z_axis]) <= self.size_m[0])
        return bool(self.mesh.is_watertight and self.mesh.contains(p_GQ[None])[0])

    @property
    def p_GR(self) -> np.ndarray:
        """(3,) a point R of the solid, in G [m] (its centre, or a mesh vertex)."""
        return np.zeros(3) if self.mesh is None else np.asarray(self.mesh.vertices[0])


def exact_shape(kind: str, size_m: tuple[float, ...], mesh: trimesh.Trimesh | None) -> ExactShape:
    """The ExactShape of a primitive (kind, size_m) or a triangle mesh in G [m]."""
    if kind == "mesh":
        model = fcl.BVHModel()
        model.beginModel(len(mesh.vertices), len(mesh.faces))
        model.addSubModel(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int32))
        model.endModel()
        return ExactShape(model, kind, (), mesh)
    factory = {
        "box": fcl.Box,
        "sphere": fcl.Sphere,
        "cylinder": fcl.Cylinder,
        "capsule": fcl.Capsule,
    }
    return ExactShape(factory[kind](*size_m), kind, tuple(size_m))


def exact_shape_of_drake(shape: Shape) -> ExactShape:
    """The ExactShape of a Drake shape (primitives exactly; Convex/Mesh by their hull)."""
    if isinstance(shape, Box):
        return exact_shape("box", (shape.width(), shape.depth(), shape.height()), None)
    if isinstance(shape, Sphere):
        return exact_shape("sphere", (shape.radius(),), None)
    if isinstance(shape, Cylinder | Capsule):
        kind = "cylinder" if isinstance(shape, Cylinder) else "capsule"
        return exact_shape(kind, (shape.radius(), shape.length()), None)
    if isinstance(shape, Convex | Mesh):
        hull = shape.GetConvexHull()
        points = np.array([hull.vertex(i) for i in range(hull.num_vertices())])
        return exact_shape("mesh", (), trimesh.convex.convex_hull(points))
    raise ValueError(f"shape: no exact distance for Drake {type(shape).__name__}")


def bounding_radius(shape: Shape) -> float:
    """Radius [m] of a sphere about the shape frame's origin that holds the Drake shape."""
    exact = exact_shape_of_drake(shape) if isinstance(shape, Convex | Mesh) else None
    if exact is not None:
        return float(np.linalg.norm(exact.mesh.vertices, axis=1).max())
    if isinstance(shape, Box):
        return float(np.linalg.norm([shape.width(), shape.depth(), shape.height()]) / 2)
    if isinstance(shape, Sphere):
        return shape.radius()
    if isinstance(shape, Cylinder):
        return float(np.hypot(shape.radius(), shape.length() / 2))
    if isinstance(shape, Capsule):
        return shape.radius() + shape.length() / 2
    raise ValueError(f"shape: no bounding radius for Drake {type(shape).__name__}")


def exact_distance(
    a: ExactShape, X_IA: RigidTransform, b: ExactShape, X_IB: RigidTransform
) -> float:
    """Exact signed distance [m] of two solids posed in I (python-fcl).

    Separated primitives get FCL's closed-form or GJK distance, overlapping ones its
    signed (EPA) distance, −depth. A triangle mesh is a surface to FCL, so a pair with a
    mesh returns 0.0 when the surfaces touch or cross, and also when one solid lies wholly
    inside the other (tested with a point of each); the depth is then unknown.
    """
    objects = [
        fcl.CollisionObject(s.geometry, fcl.Transform(X.rotation().matrix(), X.translation()))
        for s, X in ((a, X_IA), (b, X_IB))
    ]
    distance = float(fcl.distance(*objects, fcl.DistanceRequest(), fcl.DistanceResult()))
    if distance <= 0.0 and a.mesh is None and b.mesh is None:  # -1: overlapping
        request = fcl.DistanceRequest(enable_signed_distance=True)
        distance = float(fcl.distance(*objects, request, fcl.DistanceResult()))
    if a.mesh is None and b.mesh is None:
        return distance
    nested = b.contains(X_IB.inverse() @ (X_IA @ a.p_GR)) or a.contains(
        X_IA.inverse() @ (X_IB @ b.p_GR)
    )
    return 0.0 if nested else max(distance, 0.0)
