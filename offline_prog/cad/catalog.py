"""What a model offers as seams, numbered so a user can pick one by looking: its faces,
the faces' outer loops and its edge chains, each with a length and the ``near_mm``
point(s) that pick it in a cell file (``offline-prog seams PART``).

Numbers are the models' own position order (faces by centroid, edges by midpoint),
stable when a CAD system writes the same part in another order. A STEP chain is a run
of edges joined without a corner (G1: a line, its fillet arc and the next line); a mesh
chain is a run of feature edges between corners and branches.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from offline_prog.cad.seam_samples import CORNER_DEG


@dataclasses.dataclass(frozen=True)
class Entry:
    """One pickable thing: ``kind`` face | loop | chain, its number, a description,
    its size (area [mm²] or length [mm]), the cell-file keys that pick it, where to draw
    its label (3,) and its polyline (K, 3) [mm] (empty for faces)."""

    kind: str
    number: int
    description: str
    size: float
    keys: dict
    label_at: np.ndarray
    polyline: np.ndarray


@dataclasses.dataclass(frozen=True)
class Catalog:
    """A model's entries and its triangles [mm] for drawing."""

    file: Path
    entries: list[Entry]
    vertices: np.ndarray
    triangles: np.ndarray


def _mm(p) -> list[float]:
    return [float(v) + 0.0 for v in np.round(np.asarray(p, float), 2)]  # no -0.0


def interior_point(points: np.ndarray, boundary: np.ndarray) -> np.ndarray:
    """(3,) the candidate point farthest from the boundary points (a point that picks
    its face without ambiguity)."""
    from scipy.spatial import cKDTree

    if len(boundary) == 0:
        return points[0]
    distance, _ = cKDTree(boundary).query(points)
    return points[int(np.argmax(distance))]


def step_catalog(file: Path) -> Catalog:
    """The faces, loops and G1 chains of a STEP model (read exactly)."""
    from offline_prog.cad.step_geometry import sample_edge, tessellate
    from offline_prog.cad.step_model import read_step
    from offline_prog.cad.step_seams import around_itself, face_label, outer_loop, sample_run

    model = read_step(file)
    vertices, triangles, face_of = tessellate(model.shape, faces=model.faces)
    polylines = [sample_edge(e, 1.0)[0] for e in model.edges]
    entries = []
    for k in range(len(model.faces)):
        centres = vertices[triangles[face_of == k]].mean(axis=1)
        edges = [e for e, faces in enumerate(model.edge_faces) if k in faces]
        boundary = np.vstack([polylines[e] for e in edges]) if edges else np.empty((0, 3))
        near = (
            _mm(interior_point(centres, boundary)) if len(centres) else _mm(model.face_centroids[k])
        )
        entries.append(
            Entry(
                "face",
                k,
                face_label(model, k).split(" ", 2)[2].strip("()"),
                float(model.face_areas[k]),
                {"face_near_mm": near},
                np.array(near),
                np.empty((0, 3)),
            )
        )
        run = outer_loop(model, k)
        if run and not around_itself(run):  # a cylinder's side has no one contour
            loop = sample_run(model, run, k, closed=True, offset_mm=0.0)
            entries.append(
                Entry(
                    "loop",
                    k,
                    f"outer loop of face {k}, {len(run)} edges",
                    loop.length_mm,
                    {"loop": {"face_near_mm": near}},
                    loop.p[0],
                    loop.p,
                )
            )
    for number, chain in enumerate(g1_chains(model)):
        points = np.vstack([polylines[e][::-1] if back else polylines[e] for e, back in chain])
        mids = [_mm(polylines[e][len(polylines[e]) // 2]) for e, _ in chain]
        length = float(sum(model.edge_lengths[e] for e, _ in chain))
        edges = ", ".join(str(e) for e, _ in chain)
        entries.append(
            Entry(
                "chain",
                number,
                f"edges {edges}",
                length,
                {"chain": {"near_mm": mids if len(mids) > 1 else mids * 2}},
                points[len(points) // 2],
                points,
            )
        )
    return Catalog(Path(file), entries, vertices, triangles)


def g1_chains(model) -> list[list[tuple[int, bool]]]:
    """Runs of (edge, reversed) joined end to end without a corner, each edge once."""
    from offline_prog.cad.step_geometry import sample_edge

    tangents = {}
    for e, edge in enumerate(model.edges):
        _, t, _ = sample_edge(edge, 1e9)
        tangents[e] = (t[0], t[-1])  # at its first and last vertex, along the curve
    at_vertex: dict[int, list[tuple[int, int]]] = {}
    for e, (a, b) in enumerate(model.edge_ends):
        at_vertex.setdefault(a, []).append((e, 0))
        at_vertex.setdefault(b, []).append((e, 1))
    cos_limit = np.cos(np.deg2rad(CORNER_DEG))

    def continues(e: int, end: int):
        """The one edge leaving ``end`` of e tangentially, and whether it runs reversed."""
        vertex = model.edge_ends[e][end]
        out = tangents[e][end] * (1 if end == 1 else -1)
        found = []
        for other, other_end in at_vertex[vertex]:
            if other == e:
                continue
            direction = tangents[other][other_end] * (1 if other_end == 0 else -1)
            if out @ direction > cos_limit:
                found.append((other, other_end == 1))
        return found[0] if len(found) == 1 else None

    seen: set[int] = set()
    chains = []
    for e in range(len(model.edges)):
        if e in seen:
            continue
        run = [(e, False)]
        seen.add(e)
        for forward in (True, False):
            edge, back = e, not forward
            while True:
                nxt = continues(edge, 0 if back else 1)
                if nxt is None or nxt[0] in seen:
                    break
                seen.add(nxt[0])
                edge, back = nxt
                run = run + [(edge, back)] if forward else [(edge, not back)] + run
        chains.append(run)
    return chains


def mesh_catalog(file: Path, mm_per_unit: float, *, set_units: str) -> Catalog:
    """The regions ("faces"), their outer loops and the feature-edge runs of a mesh
    (``set_units``: how the user gives the file's unit, see ``mesh_model.read_mesh``)."""
    from offline_prog.cad.mesh_model import read_mesh
    from offline_prog.cad.mesh_seams import region_loops

    model = read_mesh(file, mm_per_unit, set_units=set_units)
    mesh = model.mesh
    v = mesh.vertices
    entries = []
    for k, area in enumerate(model.region_areas):
        faces = np.flatnonzero(model.face_region == k)
        loops = region_loops(model, k)
        boundary = v[np.concatenate(loops)] if loops else np.empty((0, 3))
        near = _mm(interior_point(mesh.triangles_center[faces], boundary))
        entries.append(
            Entry(
                "face",
                k,
                f"{len(faces)} triangles",
                float(area),
                {"face_near_mm": near},
                np.array(near),
                np.empty((0, 3)),
            )
        )
        if loops:
            loop = max(loops, key=lambda r: np.linalg.norm(np.diff(v[r], axis=0), axis=1).sum())
            length = float(np.linalg.norm(np.diff(v[loop], axis=0), axis=1).sum())
            keys = {"loop": {"face_near_mm": near}}
            entries.append(
                Entry("loop", k, f"outer loop of face {k}", length, keys, v[loop[0]], v[loop])
            )
    for number, run in enumerate(model.runs):
        points = v[run]
        third = [_mm(points[len(points) // 3]), _mm(points[2 * len(points) // 3])]
        entries.append(
            Entry(
                "chain",
                number,
                f"{len(run) - 1} feature edges",
                float(model.edge_lengths[number]),
                {"chain": {"near_mm": third}},
                points[len(points) // 2],
                points,
            )
        )
    return Catalog(Path(file), entries, np.asarray(v), np.asarray(mesh.faces))
