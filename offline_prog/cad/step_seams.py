"""Seams on a STEP model: a face's outer loop, or a chain of connected edges, sampled on
the exact B-rep curves with the normal of a chosen face (paper §2's points r_j and the
normals of §3.1, straight from the model).

A normal face picked by a point gives the normal on the edges it bounds; on edges it
does not bound, the face joined to it without a crease (a fillet tangent to it) does,
so a seam running along a plate's side and round its filleted corners keeps the side's
normal all the way. All in the part frame P [mm].
"""

from __future__ import annotations

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepTools import BRepTools, BRepTools_WireExplorer
from OCP.TopAbs import TopAbs_REVERSED

from offline_prog.cad.edge_chain import chain
from offline_prog.cad.offset_depth import check_offset
from offline_prog.cad.picking import PickError, pick
from offline_prog.cad.seam_samples import (
    FIT_END_SPACING_MM,
    FIT_SPACING_MM,
    REFERENCE_SPACING_MM,
    SeamSamples,
    corners,
    join_pieces,
)
from offline_prog.cad.step_geometry import (
    TESSELLATION_TOLERANCE_MM,
    distance,
    outward_normals,
    point_at_abscissa,
    sample_edge,
    tessellate,
)
from offline_prog.cad.step_model import StepModel

SMOOTH_FACES_DEG = 1.0  # faces whose normals differ less across an edge meet smoothly
SURFACE_KINDS = (
    "plane",
    "cylinder",
    "cone",
    "sphere",
    "torus",
    "Bezier",
    "B-spline",
    "revolution",
    "extrusion",
    "offset",
    "other",
)


def face_label(model: StepModel, k: int) -> str:
    kind = SURFACE_KINDS[min(int(BRepAdaptor_Surface(model.faces[k]).GetType()), 10)]
    return f"face {k} ({kind})"


def pick_face(model: StepModel, point_mm, key: str) -> int:
    """The number of the face nearest the point (see :func:`picking.pick`)."""
    d = [distance(face, point_mm) for face in model.faces]
    labels = [face_label(model, k) for k in range(len(model.faces))]
    return pick(point_mm, d, labels, what="face", key=key)


def pick_edge(model: StepModel, point_mm, key: str) -> int:
    d = [distance(edge, point_mm) for edge in model.edges]
    labels = [f"edge {k} ({model.edge_lengths[k]:.1f} mm)" for k in range(len(model.edges))]
    return pick(point_mm, d, labels, what="edge", key=key)


def outer_loop(model: StepModel, face_number: int) -> list[tuple[int, bool]]:
    """(edge number, reversed) of the face's outer loop, in order around it."""
    face = model.faces[face_number]
    numbers = {hash(e): k for k, e in enumerate(model.edges)}
    explorer = BRepTools_WireExplorer(BRepTools.OuterWire_s(face), face)
    run = []
    while explorer.More():
        edge = explorer.Current()
        if hash(edge) in numbers:  # degenerate edges (a cone's apex) are not run
            run.append((numbers[hash(edge)], edge.Orientation() == TopAbs_REVERSED))
        explorer.Next()
    return run


def smooth_group(model: StepModel, face_number: int) -> set[int]:
    """The faces reachable from one across edges where they meet without a crease."""
    group, todo = {face_number}, [face_number]
    while todo:
        k = todo.pop()
        for e, faces in enumerate(model.edge_faces):
            if k not in faces or len(set(faces)) != 2:
                continue
            other = next(f for f in faces if f != k)
            if other in group:
                continue
            mid = point_at_abscissa(model.edges[e], 0.5)
            n_k = outward_normals(model.faces[k], mid[None])[0]
            n_o = outward_normals(model.faces[other], mid[None])[0]
            if np.rad2deg(np.arccos(np.clip(n_k @ n_o, -1, 1))) < SMOOTH_FACES_DEG:
                group.add(other)
                todo.append(other)
    return group


def sample_run(model: StepModel, run, normal_face: int, *, closed: bool, offset_mm: float):
    """SeamSamples of a run of (edge, reversed), normals from ``normal_face`` (and the
    faces joined to it without a crease on the edges it does not bound)."""
    group = smooth_group(model, normal_face)
    points, normals, references, ends = [], [], [], []
    for k, (edge, backwards) in enumerate(run):
        on = [f for f in model.edge_faces[edge] if f in group]
        face = model.faces[on[0] if on else normal_face]
        p, t, _ = sample_edge(
            model.edges[edge], FIT_SPACING_MM, reverse=backwards, first_mm=FIT_END_SPACING_MM
        )
        n = outward_normals(face, p)
        reference, _, _ = sample_edge(model.edges[edge], REFERENCE_SPACING_MM, reverse=backwards)
        if offset_mm:
            reference = reference - offset_mm * outward_normals(face, reference)
        points.append(p - offset_mm * n)
        normals.append(n)
        references.append(reference)
        next_edge, next_back = run[(k + 1) % len(run)]
        _, t_next, _ = sample_edge(model.edges[next_edge], 1e9, reverse=next_back)
        ends.append((p[-1], t[-1], t_next[0]))
    return SeamSamples(
        join_pieces(points, closed=closed),
        join_pieces(normals, closed=closed),
        closed,
        float(sum(model.edge_lengths[e] for e, _ in run)),
        join_pieces(references, closed=closed),
        REFERENCE_SPACING_MM**2 / 8 / _smallest_radius(model, run),
        tuple(e for e, _ in run),
        corners(ends, closed=closed),
    )


def _smallest_radius(model: StepModel, run) -> float:
    """The smallest radius of curvature on the run's edges [mm] (sampled; ∞ for lines)."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.BRepLProp import BRepLProp_CLProps

    smallest = np.inf
    for edge, _ in run:
        curve = BRepAdaptor_Curve(model.edges[edge])
        for u in np.linspace(curve.FirstParameter(), curve.LastParameter(), 9):
            props = BRepLProp_CLProps(curve, u, 2, 1e-9)
            curvature = props.Curvature() if props.IsTangentDefined() else 0.0
            if curvature > 0:
                smallest = min(smallest, 1.0 / curvature)
    return smallest


def around_itself(run: list[tuple[int, bool]]) -> list[int]:
    """The edges a face's loop runs twice: the seam edge of a face closed around itself
    (a cylinder's or cone's side), along which its boundary goes there and back."""
    numbers = [e for e, _ in run]
    return sorted({e for e in numbers if numbers.count(e) > 1})


def _offset_checked(model: StepModel, samples: SeamSamples, offset_mm: float, key: str):
    """``samples``, once :func:`offset_depth.check_offset` allows the offset."""
    if offset_mm > 0.0:
        vertices, triangles, _ = tessellate(model.shape)
        check_offset(
            vertices,
            triangles,
            samples,
            offset_mm,
            key=key,
            tolerance_mm=TESSELLATION_TOLERANCE_MM,
        )
    return samples


def loop_seam(model: StepModel, face_near_mm, normal_near_mm, *, offset_mm: float, key: str):
    """The outer loop of the face nearest ``face_near_mm``, normals from the face nearest
    ``normal_near_mm`` (default: the loop's face). The loop runs as Open CASCADE's outer
    wire does: with its face on the left seen from outside the part (counter-clockwise
    about the face's outward normal), as a mesh's loop does (``mesh_seams``).

    Raises:
        PickError: a face closed around itself (its boundary is not one contour), an
            offset deeper than the part, or a point that picks nothing or two faces.
    """
    face = pick_face(model, face_near_mm, f"{key}.loop.face_near_mm")
    run = outer_loop(model, face)
    twice = around_itself(run)
    if twice:
        raise PickError(
            f"{key}.loop.face_near_mm",
            f"{face_label(model, face)} closes around itself: its boundary runs along "
            f"its seam edge {twice[0]} and back, not round one contour; pick one of its "
            "rims as a chain (cad.chain, closed: true)",
        )
    normal_face = face
    if normal_near_mm is not None:
        normal_face = pick_face(model, normal_near_mm, f"{key}.normal.face_near_mm")
    samples = sample_run(model, run, normal_face, closed=True, offset_mm=offset_mm)
    return _offset_checked(model, samples, offset_mm, key)


def chain_seam(
    model: StepModel, near_mm, normal_near_mm, *, offset_mm: float, closed: bool, key: str
):
    """The chain of edges through those nearest the ``near_mm`` points."""
    picked = [pick_edge(model, p, f"{key}.chain.near_mm[{i}]") for i, p in enumerate(near_mm)]
    run = chain(model, picked, key)
    normal_face = pick_face(model, normal_near_mm, f"{key}.normal.face_near_mm")
    first = model.edge_ends[run[0][0]][1 if run[0][1] else 0]
    last = model.edge_ends[run[-1][0]][0 if run[-1][1] else 1]
    if closed and first != last:
        raise PickError(f"{key}.closed", "true, but the chain's ends do not meet")
    samples = sample_run(model, run, normal_face, closed=closed, offset_mm=offset_mm)
    return _offset_checked(model, samples, offset_mm, key)
