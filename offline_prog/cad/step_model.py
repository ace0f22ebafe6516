"""A STEP part model read with Open CASCADE (OCP): its solid, faces, edges and vertices,
numbered by position (not by file order), and the topology between them.

Lengths are millimetres, as the STEP reader gives them (it converts the file's unit);
the seam source scales to metres at the edge. Faces are numbered by their centroid,
edges by their midpoint, both sorted by (x, y, z) rounded to 1 µm, so that the numbers
stay when a CAD system writes the same part in another order.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepGProp import BRepGProp
from OCP.GCPnts import GCPnts_AbscissaPoint
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_FORWARD, TopAbs_SHELL, TopAbs_SOLID
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS

POSITION_DECIMALS = 3  # numbering rounds positions to 1 µm [mm]


class ModelError(ValueError):
    """A model that cannot give seams (unreadable, not a solid); str() is one line."""


def sub_shapes(shape, kind) -> list:
    """The distinct sub-shapes of one kind (TopAbs_FACE, ...), in file order."""
    found, seen = [], set()
    explorer = TopExp_Explorer(shape, kind)
    while explorer.More():
        current = explorer.Current()
        if hash(current) not in seen:
            seen.add(hash(current))
            found.append(current)
        explorer.Next()
    return found


def _xyz(point) -> np.ndarray:
    return np.array([point.X(), point.Y(), point.Z()])


def edge_length(edge) -> float:
    """The edge's exact length [mm] (Gauss integration on its curve)."""
    return float(GCPnts_AbscissaPoint.Length_s(BRepAdaptor_Curve(edge)))


def edge_midpoint(edge) -> np.ndarray:
    """(3,) the point halfway along the edge by arc length [mm]."""
    curve = BRepAdaptor_Curve(edge)
    first, last = curve.FirstParameter(), curve.LastParameter()
    half = GCPnts_AbscissaPoint(curve, edge_length(edge) / 2, first)
    return _xyz(curve.Value(half.Parameter() if half.IsDone() else (first + last) / 2))


def face_centroid(face) -> tuple[np.ndarray, float]:
    """(3,) the face's area centroid [mm] (off the face if it is curved) and its area [mm²]."""
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props)
    return _xyz(props.CentreOfMass()), float(props.Mass())


def _order(positions: list[np.ndarray]) -> list[int]:
    keys = [tuple(np.round(p, POSITION_DECIMALS)) for p in positions]
    return sorted(range(len(keys)), key=lambda i: keys[i])


@dataclasses.dataclass
class StepModel:
    """A solid's B-rep, numbered by position.

    Attributes:
        shape: the TopoDS_Shape read.
        faces: TopoDS_Face, face k is number k (sorted by centroid).
        face_areas: (F,) [mm²]; face_centroids: (F, 3) [mm].
        edges: TopoDS_Edge oriented FORWARD (its curve's own direction), number k,
            sorted by midpoint; degenerate edges (a cone's apex) left out.
        edge_faces: the face numbers each edge bounds (one face twice for a seam edge).
        edge_ends: (first, last) vertex numbers of each edge in its curve's direction.
        edge_lengths: (E,) [mm].
    """

    shape: object
    faces: list
    face_areas: np.ndarray
    face_centroids: np.ndarray
    edges: list
    edge_faces: list[tuple[int, ...]]
    edge_ends: list[tuple[int, int]]
    edge_lengths: np.ndarray

    def face_number(self, face) -> int:
        return self._face_numbers[hash(face)]

    def __post_init__(self):
        self._face_numbers = {hash(f): k for k, f in enumerate(self.faces)}


def read_step(file: Path) -> StepModel:
    """Read a STEP file (AP203/AP214/AP242) holding at least one valid solid.

    Raises:
        ModelError: not readable as STEP, no solid in it, or an invalid B-rep.
    """
    reader = STEPControl_Reader()
    if not Path(file).is_file() or reader.ReadFile(str(file)) != IFSelect_RetDone:
        raise ModelError("not a readable STEP file")
    reader.TransferRoots()
    shape = reader.OneShape()
    if shape.IsNull() or not sub_shapes(shape, TopAbs_FACE):
        raise ModelError("the STEP file holds no surfaces")
    if not sub_shapes(shape, TopAbs_SOLID):
        shells = len(sub_shapes(shape, TopAbs_SHELL))
        faces = len(sub_shapes(shape, TopAbs_FACE))
        raise ModelError(
            f"not a solid ({faces} faces in {shells} shells, no closed solid): export the "
            "part as a solid body"
        )
    if not BRepCheck_Analyzer(shape).IsValid():
        raise ModelError("the solid is not valid (Open CASCADE's BRepCheck): repair it in CAD")
    return model_of(shape)


def model_of(shape) -> StepModel:
    """Number the faces and edges of a shape (see :class:`StepModel`)."""
    faces = [TopoDS.Face(f) for f in sub_shapes(shape, TopAbs_FACE)]
    geometry = [face_centroid(f) for f in faces]
    order = _order([c for c, _ in geometry])
    faces = [faces[i] for i in order]
    centroids = np.array([geometry[i][0] for i in order]).reshape(-1, 3)
    areas = np.array([geometry[i][1] for i in order])
    edge_faces: dict[int, list[int]] = {}
    for k, face in enumerate(faces):
        for edge in sub_shapes(face, TopAbs_EDGE):
            edge_faces.setdefault(hash(edge), []).append(k)
    edges = [
        TopoDS.Edge(TopoDS.Edge(e).Oriented(TopAbs_FORWARD))
        for e in sub_shapes(shape, TopAbs_EDGE)
        if not BRep_Tool.Degenerated_s(TopoDS.Edge(e))
    ]
    edges = [edges[i] for i in _order([edge_midpoint(e) for e in edges])]
    vertex_numbers: dict[int, int] = {}
    ends = []
    for edge in edges:
        pair = []
        for vertex in (TopExp.FirstVertex_s(edge), TopExp.LastVertex_s(edge)):
            pair.append(vertex_numbers.setdefault(hash(vertex), len(vertex_numbers)))
        ends.append(tuple(pair))
    return StepModel(
        shape,
        faces,
        areas,
        centroids,
        edges,
        [tuple(edge_faces.get(hash(e), ())) for e in edges],
        ends,
        np.array([edge_length(e) for e in edges]),
    )
