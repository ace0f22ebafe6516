"""Exact geometry of a STEP model's B-rep: points and tangents on edges, the faces'
normals, distances from a point, and the tessellation for collision and drawing.

Everything in the part frame P, in millimetres (the seam source scales to metres).
Normals here are a face's OUTWARD normal (the surface's normal, reversed where the face
is reversed in its solid); the seam source turns them into the surface as the project's
convention asks.
"""

from __future__ import annotations

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.GCPnts import GCPnts_AbscissaPoint
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.GeomLProp import GeomLProp_SLProps
from OCP.gp import gp_Pnt, gp_Vec
from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS

from offline_prog.cad.step_model import edge_length, sub_shapes

# Chord tolerance of the tessellation for collision and drawing [mm], and its angular
# tolerance [rad]: the part's Drake geometry is within this of the exact solid.
TESSELLATION_TOLERANCE_MM = 0.05
TESSELLATION_ANGLE_RAD = 0.1
GRADING = 1.3  # growth of the point spacing away from an edge's ends


def _xyz(point) -> np.ndarray:
    return np.array([point.X(), point.Y(), point.Z()])


def graded_abscissae(length: float, spacing: float, first: float) -> np.ndarray:
    """(n,) arc lengths from 0 to ``length``: ``spacing`` apart in the middle, growing
    geometrically (×GRADING) from ``first`` at both ends, where an edge meets the next
    and the curvature may jump (the fit's knots follow the points there)."""
    steps = []
    step = min(first, spacing)
    while step < spacing and 2 * (sum(steps) + step) < length:
        steps.append(step)
        step *= GRADING
    end = sum(steps)
    middle = max(1, int(np.ceil((length - 2 * end) / spacing)))
    inner = np.linspace(end, length - end, middle + 1)
    head = np.cumsum([0.0, *steps])[:-1]
    return np.concatenate([head, inner, length - head[::-1]])


def sample_edge(edge, spacing_mm: float, *, reverse: bool = False, first_mm: float | None = None):
    """Points and unit tangents on an edge, spaced by exact arc length.

    Args:
        edge: TopoDS_Edge (its curve's direction unless ``reverse``).
        spacing_mm: largest arc length between neighbours [mm].
        first_mm: the spacing at both ends, growing to ``spacing_mm`` (default: even).

    Returns:
        p: (n, 3) points [mm], both ends included; t: (n, 3) unit tangents along the
        direction of travel; length: the edge's exact length [mm].
    """
    curve = BRepAdaptor_Curve(edge)
    first, last = curve.FirstParameter(), curve.LastParameter()
    length = edge_length(edge)
    if first_mm is None:
        s = np.linspace(0.0, length, max(3, int(np.ceil(length / min(spacing_mm, 1e9))) + 1))
    else:
        s = graded_abscissae(length, spacing_mm, first_mm)
    u = np.empty(len(s))
    u[0], u[-1] = first, last
    for i in range(1, len(s) - 1):
        u[i] = GCPnts_AbscissaPoint(curve, float(s[i]), first).Parameter()
    p, t = np.empty((len(u), 3)), np.empty((len(u), 3))
    point, vector = gp_Pnt(), gp_Vec()
    for i, ui in enumerate(u):
        curve.D1(ui, point, vector)
        p[i], t[i] = _xyz(point), _xyz(vector)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    if reverse:
        p, t = p[::-1], -t[::-1]
    return p, t, length


def point_at_abscissa(edge, fraction: float) -> np.ndarray:
    """(3,) the point a fraction of the way along the edge by arc length [mm]."""
    curve = BRepAdaptor_Curve(edge)
    first = curve.FirstParameter()
    at = GCPnts_AbscissaPoint(curve, fraction * edge_length(edge), first)
    return _xyz(curve.Value(at.Parameter()))


def outward_normals(face, points: np.ndarray) -> np.ndarray:
    """(n, 3) unit outward normals of a face at the foot points of ``points`` (n, 3)
    [mm] on its surface: projected to (u, v), then the surface's normal there (exact)."""
    surface = BRep_Tool.Surface_s(face)
    sign = -1.0 if face.Orientation() == TopAbs_REVERSED else 1.0
    normals = np.empty((len(points), 3))
    projector = GeomAPI_ProjectPointOnSurf()
    for i, p in enumerate(points):
        projector.Init(gp_Pnt(*p), surface)
        u, v = projector.LowerDistanceParameters()
        props = GeomLProp_SLProps(surface, u, v, 1, 1e-9)
        if not props.IsNormalDefined():
            raise ValueError(f"the face has no normal at ({p[0]:.2f}, {p[1]:.2f}, {p[2]:.2f}) mm")
        normals[i] = sign * _xyz(props.Normal())
    return normals


def distance(shape, point_mm) -> float:
    """Exact distance [mm] from a point to a face, edge or solid."""
    vertex = BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, point_mm))).Vertex()
    extrema = BRepExtrema_DistShapeShape(vertex, shape)
    return float(extrema.Value())


def tessellate(shape, tolerance_mm: float = TESSELLATION_TOLERANCE_MM, faces=None):
    """Triangles of the solid within ``tolerance_mm`` of its surface (chord deviation).

    Args:
        faces: the shape's faces in the order to number them (default: file order).

    Returns:
        vertices: (V, 3) [mm]; triangles: (T, 3) vertex indices, counter-clockwise seen
        from outside; face_of: (T,) the position in ``faces`` of each triangle's face.
    """
    BRepMesh_IncrementalMesh(shape, tolerance_mm, False, TESSELLATION_ANGLE_RAD, True)
    vertices, triangles, face_of = [], [], []
    offset = 0
    for k, face in enumerate(sub_shapes(shape, TopAbs_FACE) if faces is None else faces):
        face = TopoDS.Face(face)
        location = TopLoc_Location()
        mesh = BRep_Tool.Triangulation_s(face, location)
        if mesh is None:
            continue
        transform = location.Transformation()
        for i in range(1, mesh.NbNodes() + 1):
            vertices.append(_xyz(mesh.Node(i).Transformed(transform)))
        reverse = face.Orientation() == TopAbs_REVERSED
        for i in range(1, mesh.NbTriangles() + 1):
            a, b, c = (offset + j - 1 for j in mesh.Triangle(i).Get())
            triangles.append([a, c, b] if reverse else [a, b, c])
            face_of.append(k)
        offset += mesh.NbNodes()
    return np.array(vertices), np.array(triangles, dtype=int), np.array(face_of, dtype=int)
