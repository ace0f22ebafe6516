"""Seams on a mesh model: a region's outer boundary loop, or a chain of feature-edge
runs, with normals from the chosen region's triangles (area-weighted at each vertex).

The seam is the mesh's own polyline of feature edges: it lies on the part's edge at
the vertices and within the tessellation's chord error between them, which is
estimated from the polyline's turning (:func:`chord_error`) and reported. All in the
part frame P [mm].
"""

from __future__ import annotations

import numpy as np

from offline_prog.cad.edge_chain import chain
from offline_prog.cad.mesh_model import CORNER_DEG, MeshModel
from offline_prog.cad.offset_depth import check_offset
from offline_prog.cad.picking import PickError, pick
from offline_prog.cad.seam_samples import (
    FIT_SPACING_MM,
    REFERENCE_SPACING_MM,
    SeamSamples,
    corners,
)


def region_distances(model: MeshModel, point_mm) -> np.ndarray:
    """(R,) distance [mm] from a point to each region's triangles."""
    import trimesh

    mesh = model.mesh
    p = np.broadcast_to(np.asarray(point_mm, float), (len(mesh.faces), 3))
    closest = trimesh.triangles.closest_point(mesh.triangles, p)
    d = np.linalg.norm(closest - p, axis=1)
    per_region = np.full(len(model.region_areas), np.inf)
    np.minimum.at(per_region, model.face_region, d)
    return per_region


def pick_region(model: MeshModel, point_mm, key: str) -> int:
    labels = [f"face {k} ({a:.0f} mm²)" for k, a in enumerate(model.region_areas)]
    return pick(point_mm, region_distances(model, point_mm), labels, what="face", key=key)


def _segment_distances(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=1)


def pick_run(model: MeshModel, point_mm, key: str) -> int:
    v = model.mesh.vertices
    p = np.asarray(point_mm, float)
    d = [_segment_distances(p[None], v[r[:-1]], v[r[1:]]).min() for r in model.runs]
    labels = [f"edge {k} ({length:.1f} mm)" for k, length in enumerate(model.edge_lengths)]
    return pick(point_mm, d, labels, what="feature edge", key=key)


def region_vertex_normals(model: MeshModel, region: int, vertices: np.ndarray) -> np.ndarray:
    """(n, 3) outward unit normals at mesh vertices from the region's triangles there
    (area-weighted); a vertex the region does not touch takes its nearest triangle's."""
    import trimesh

    mesh = model.mesh
    normals = np.empty((len(vertices), 3))
    in_region = model.face_region == region
    for i, v in enumerate(vertices):
        faces = [f for f in mesh.vertex_faces[v] if f >= 0 and in_region[f]]
        if faces:
            normals[i] = (mesh.face_normals[faces] * mesh.area_faces[faces, None]).sum(0)
        else:
            sub = np.flatnonzero(in_region)
            p = np.broadcast_to(mesh.vertices[v], (len(sub), 3))
            closest = trimesh.triangles.closest_point(mesh.triangles[sub], p)
            normals[i] = mesh.face_normals[sub[np.argmin(np.linalg.norm(closest - p, axis=1))]]
    return normals / np.linalg.norm(normals, axis=1, keepdims=True)


def region_loops(model: MeshModel, region: int) -> list[np.ndarray]:
    """The region's boundary as closed vertex loops (first vertex repeated at the end),
    each with the region on its left seen from outside the part: along its edges as the
    region's triangles run them (counter-clockwise seen from outside), as a STEP face's
    outer wire runs."""
    mesh = model.mesh
    inside = model.face_region == region
    pairs = mesh.face_adjacency
    crossing = inside[pairs[:, 0]] != inside[pairs[:, 1]]
    edges = [mesh.face_adjacency_edges[crossing]]
    counts = np.bincount(mesh.edges_unique_inverse, minlength=len(mesh.edges_unique))
    open_edges = np.flatnonzero(counts == 1)
    faces_of_edge = mesh.edges_face[np.isin(mesh.edges_unique_inverse, open_edges)]
    edges.append(
        mesh.edges_unique[open_edges][inside[faces_of_edge]]
        if open_edges.size
        else np.empty((0, 2), int)
    )
    neighbours: dict[int, list[int]] = {}
    for a, b in np.vstack(edges):
        neighbours.setdefault(int(a), []).append(int(b))
        neighbours.setdefault(int(b), []).append(int(a))
    loops, seen = [], set()
    for start in sorted(neighbours):
        if start in seen:
            continue
        loop = [start, neighbours[start][0]]
        while loop[-1] != start:
            step = next((n for n in neighbours[loop[-1]] if n != loop[-2]), None)
            if step is None or len(loop) > len(neighbours) + 1:
                break
            loop.append(step)
        seen.update(loop)
        if loop[-1] == start:
            loops.append(_region_on_the_left(mesh, inside, np.array(loop)))
    return loops


def _region_on_the_left(mesh, inside: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """The loop (first vertex repeated at the end) reversed unless its first edge runs
    as the region's triangle on it runs that edge (triangles wound counter-clockwise
    seen from outside: the region is then on the loop's left)."""
    a, b = int(loop[0]), int(loop[1])
    for face in mesh.vertex_faces[a]:
        if face < 0 or not inside[face]:
            continue
        corners = [int(v) for v in mesh.faces[face]]
        if b in corners:
            i = corners.index(a)
            return loop if corners[(i + 1) % 3] == b else loop[::-1]
    return loop


def _resample(p: np.ndarray, n: np.ndarray, spacing: float):
    """Points FIT_SPACING_MM apart on the polyline (its vertices kept), normals
    interpolated linearly along it and normalized."""
    out_p, out_n = [p[:1]], [n[:1]]
    for k in range(len(p) - 1):
        count = max(1, int(np.ceil(np.linalg.norm(p[k + 1] - p[k]) / spacing)))
        w = (np.arange(1, count + 1) / count)[:, None]
        out_p.append(p[k] + w * (p[k + 1] - p[k]))
        out_n.append(n[k] + w * (n[k + 1] - n[k]))
    normals = np.vstack(out_n)
    return np.vstack(out_p), normals / np.linalg.norm(normals, axis=1, keepdims=True)


def chord_error(p: np.ndarray) -> float:
    """Estimated largest distance [mm] of a polyline's chords from the smooth curve
    through its vertices: a chord of length L on an arc of radius r turns θ = L/r from
    its neighbour and sits L²/8r = Lθ/8 off the arc. Each vertex's turn is charged to
    its shorter chord (a tessellated line is one long exact chord; the turn where it
    meets a fillet belongs to the fillet's short chords). Corners above the run limit
    are corners, not chord error."""
    chords = np.diff(p, axis=0)
    lengths = np.linalg.norm(chords, axis=1)
    if len(chords) < 2:
        return 0.0
    cos = np.einsum("ij,ij->i", chords[:-1], chords[1:]) / (lengths[:-1] * lengths[1:])
    turn = np.arccos(np.clip(cos, -1.0, 1.0))
    turn = np.where(turn > np.deg2rad(CORNER_DEG), 0.0, turn)
    return float((np.minimum(lengths[:-1], lengths[1:]) * turn / 8).max())


def _samples(model, vertex_runs, region, *, closed, offset_mm, edges) -> SeamSamples:
    v = model.mesh.vertices
    pieces = [np.asarray(r) for r in vertex_runs]
    path = np.concatenate([pieces[0]] + [r[1:] for r in pieces[1:]])
    normals = region_vertex_normals(model, region, path)
    p, n = _resample(v[path], normals, FIT_SPACING_MM)
    reference, reference_n = _resample(v[path], normals, REFERENCE_SPACING_MM)
    reference = reference - offset_mm * reference_n
    ends = []
    for k, r in enumerate(pieces):
        nxt = pieces[(k + 1) % len(pieces)]
        t_end = v[r[-1]] - v[r[-2]]
        t_next = v[nxt[1]] - v[nxt[0]]
        ends.append((v[r[-1]], t_end / np.linalg.norm(t_end), t_next / np.linalg.norm(t_next)))
    if closed:
        p, n, reference = p[:-1], n[:-1], reference[:-1]
    length = float(np.linalg.norm(np.diff(v[path], axis=0), axis=1).sum())
    tolerance = max(chord_error(v[r]) for r in pieces)
    return SeamSamples(
        p - offset_mm * n,
        n,
        closed,
        length,
        reference,
        tolerance,
        tuple(edges),
        corners(ends, closed=closed),
    )


def loop_seam(model: MeshModel, face_near_mm, normal_near_mm, *, offset_mm: float, key: str):
    """The longest boundary loop of the region nearest ``face_near_mm``."""
    region = pick_region(model, face_near_mm, f"{key}.loop.face_near_mm")
    loops = region_loops(model, region)
    if not loops:
        raise PickError(f"{key}.loop.face_near_mm", f"face {region} has no closed boundary")
    v = model.mesh.vertices
    loop = max(loops, key=lambda r: np.linalg.norm(np.diff(v[r], axis=0), axis=1).sum())
    normal_region = region
    if normal_near_mm is not None:
        normal_region = pick_region(model, normal_near_mm, f"{key}.normal.face_near_mm")
    samples = _samples(model, [loop], normal_region, closed=True, offset_mm=offset_mm, edges=())
    mesh = model.mesh
    check_offset(mesh.vertices, mesh.faces, samples, offset_mm, key=key)
    return samples


def chain_seam(
    model: MeshModel, near_mm, normal_near_mm, *, offset_mm: float, closed: bool, key: str
):
    """Whole feature-edge runs from the one nearest the first point to the one nearest
    the last (see :mod:`offline_prog.cad.mesh_model` for what a run is)."""
    if not model.runs:
        raise PickError(f"{key}.chain.near_mm", "the mesh has no feature edges (no sharp edge)")
    picked = [pick_run(model, p, f"{key}.chain.near_mm[{i}]") for i, p in enumerate(near_mm)]
    run = chain(model, picked, key)
    region = pick_region(model, normal_near_mm, f"{key}.normal.face_near_mm")
    vertex_runs = [model.runs[e][::-1] if back else model.runs[e] for e, back in run]
    if closed and vertex_runs[0][0] != vertex_runs[-1][-1]:
        raise PickError(f"{key}.closed", "true, but the chain's ends do not meet")
    if not closed and len(run) == 1 and vertex_runs[0][0] == vertex_runs[0][-1]:
        raise PickError(
            f"{key}.closed",
            f"false, but feature edge {run[0][0]} is a closed run with no corner to start "
            "or end at (a mesh keeps no tangent edge ends): set closed: true, or use the "
            "STEP model",
        )
    samples = _samples(
        model, vertex_runs, region, closed=closed, offset_mm=offset_mm, edges=[e for e, _ in run]
    )
    check_offset(model.mesh.vertices, model.mesh.faces, samples, offset_mm, key=key)
    return samples
