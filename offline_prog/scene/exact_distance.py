"""Exact distances between solids posed in I, with python-fcl.

SceneGraph sees a mesh as its convex pieces; the verdict on a close pair is decided here on
the original triangles (an FCL BVH) or on the exact primitive. Frames: I inertial, G the
shape's own frame (primitives centred on G, cylinders and capsules along G's z).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import fcl
import numpy as np
from pydrake.geometry import Box, Capsule, Convex, Cylinder, Mesh, Shape, Sphere
from pydrake.math import RigidTransform

if TYPE_CHECKING:  # trimesh costs ~0.5 s to import; loaded where a mesh is used
    import trimesh


class ConvexSolid:
    """The convex hull of points (N, 3) in G [m] as a closed triangle mesh (qhull, through
    scipy): what :class:`ExactShape` needs of a mesh (``vertices``, ``faces``,
    ``is_watertight``, ``contains``) without trimesh, ~0.3 s of import a plan saves
    (Drake gives a Convex or Mesh geometry's hull; its exact shape is that hull)."""

    is_watertight = True  # a hull is closed

    def __init__(self, points: np.ndarray):
        from scipy.spatial import ConvexHull

        hull = ConvexHull(np.asarray(points, dtype=float))
        used = np.sort(hull.vertices)  # only the hull's vertices, re-indexed
        index = np.zeros(len(hull.points), dtype=np.int64)
        index[used] = np.arange(len(used))
        self.vertices = hull.points[used]
        self.faces = index[hull.simplices]
        self._planes = hull.equations  # (F, 4): n·p + c ≤ 0 inside, n outward unit

    def contains(self, p_GQ: np.ndarray) -> np.ndarray:
        """(M,) whether each point (M, 3) in G [m] is inside or on the solid."""
        n, c = self._planes[:, :3], self._planes[:, 3]
        return np.all(np.asarray(p_GQ) @ n.T + c <= CONTAINS_TOL_M, axis=1)


CONTAINS_TOL_M = 1e-12  # a point this far outside a hull's face still counts as on it


@dataclasses.dataclass(frozen=True, eq=False)
class ExactShape:
    """A solid for exact distances: an FCL geometry in G and a point-inside test."""

    geometry: fcl.CollisionGeometry
    kind: str
    size_m: tuple[float, ...]
    mesh: trimesh.Trimesh | ConvexSolid | None = None

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


MESH_SHAPES_KEPT = 8
_mesh_shapes: dict[int, tuple] = {}  # id(mesh) ↦ (mesh, its ExactShape)


def exact_shape(
    kind: str, size_m: tuple[float, ...], mesh: trimesh.Trimesh | ConvexSolid | None
) -> ExactShape:
    """The ExactShape of a primitive (kind, size_m) or a triangle mesh in G [m].

    A mesh's BVH is built once per mesh object (the last MESH_SHAPES_KEPT): every
    collision check of a session's re-plans measures the same part mesh."""
    if kind == "mesh":
        kept = _mesh_shapes.get(id(mesh))
        if kept is not None and kept[0] is mesh:
            return kept[1]
        model = fcl.BVHModel()
        model.beginModel(len(mesh.vertices), len(mesh.faces))
        model.addSubModel(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int32))
        model.endModel()
        shape = ExactShape(model, kind, (), mesh)
        _mesh_shapes[id(mesh)] = (mesh, shape)  # the mesh kept with it: its id stays its
        while len(_mesh_shapes) > MESH_SHAPES_KEPT:
            _mesh_shapes.pop(next(iter(_mesh_shapes)), None)
        return shape
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
        return exact_shape("mesh", (), ConvexSolid(points))
    raise ValueError(f"shape: no exact distance for Drake {type(shape).__name__}")


def bounding_radius(shape: Shape) -> float:
    """Radius [m] of a sphere about the shape frame's origin that holds the Drake shape."""
    if isinstance(shape, Convex | Mesh):  # the farthest point of a hull is one of its
        # vertices: Drake's hull points give it without building the mesh (nor trimesh)
        hull = shape.GetConvexHull()
        points = np.array([hull.vertex(i) for i in range(hull.num_vertices())])
        return float(np.linalg.norm(points, axis=1).max())
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
