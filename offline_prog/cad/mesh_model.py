"""A part model given as a triangle mesh (STL/OBJ/PLY): its feature edges, smooth
regions ("faces") and runs of feature edges ("edges"), numbered by position.

A mesh keeps no B-rep: an edge between triangles is a feature where their dihedral
angle exceeds FEATURE_DEG (a sharp edge of the part; a fillet's tessellation turns
less per triangle), a face is a region of triangles joined across non-feature edges,
and an edge is a run of feature edges between branches and corners (a turn above
CORNER_DEG). So a mesh edge spans what the CAD model splits at tangent junctions (a
line, its fillet arc and the next line): a chain picks whole runs. Lengths in mm.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from offline_prog.cad.step_model import ModelError
from offline_prog.config.unit_slips import MM, large_mesh

FEATURE_DEG = 30.0  # dihedral angle above which a mesh edge is a feature (sharp) edge
CORNER_DEG = 20.0  # a run of feature edges ends where it turns more than this


@dataclasses.dataclass
class MeshModel:
    """A mesh in P [mm] with its regions and runs, numbered by position.

    Attributes:
        mesh: trimesh.Trimesh [mm], vertices merged.
        face_region: (T,) region number of each triangle (sorted by area centroid).
        region_areas: (R,) [mm²]; region_centroids: (R, 3) [mm].
        runs: vertex indices of each run of feature edges, in order (a closed run
            repeats its first vertex at the end); sorted by midpoint.
        edge_ends: (first, last) vertex of each run; edge_lengths: (E,) [mm].
    """

    mesh: object
    face_region: np.ndarray
    region_areas: np.ndarray
    region_centroids: np.ndarray
    runs: list[np.ndarray]
    edge_ends: list[tuple[int, int]]
    edge_lengths: np.ndarray


def read_mesh(
    file: Path, mm_per_unit: float, *, set_units: str = "set mesh_units: mm"
) -> MeshModel:
    """Read a mesh file and find its regions and feature-edge runs.

    Args:
        mm_per_unit: the file's unit [mm].
        set_units: how the user gives the unit (the hint for a file that looks like mm).

    Raises:
        ModelError: not a readable mesh, no triangles, or larger than a cell (the rule
            of ``config.unit_slips``, as for every mesh of a cell).
    """
    import trimesh

    try:
        mesh = trimesh.load(file, force="mesh")
        if len(mesh.faces) == 0:
            raise ValueError("no triangles")
    except Exception as error:  # trimesh raises many kinds; report one line
        reason = (str(error).splitlines() or [""])[0] or type(error).__name__
        raise ModelError(f"not a readable mesh ({reason})") from None
    mesh.apply_scale(mm_per_unit)
    too_large = large_mesh(float(max(mesh.extents)) * MM, set_units=set_units)
    if too_large:
        raise ModelError(too_large)
    mesh.merge_vertices()
    return model_of(mesh)


def _position_order(points: np.ndarray) -> np.ndarray:
    keys = [tuple(np.round(p, 3)) for p in points]
    return np.array(sorted(range(len(keys)), key=lambda i: keys[i]), dtype=int)


def feature_edges(mesh) -> np.ndarray:
    """(K, 2) vertex pairs of the sharp edges and of open (one-triangle) edges."""
    sharp = mesh.face_adjacency_angles > np.deg2rad(FEATURE_DEG)
    edges = [mesh.face_adjacency_edges[sharp]]
    counts = np.bincount(mesh.edges_unique_inverse, minlength=len(mesh.edges_unique))
    edges.append(mesh.edges_unique[counts == 1])
    return np.sort(np.vstack(edges), axis=1)


def model_of(mesh) -> MeshModel:
    import trimesh

    sharp = mesh.face_adjacency_angles > np.deg2rad(FEATURE_DEG)
    components = trimesh.graph.connected_components(
        mesh.face_adjacency[~sharp], nodes=np.arange(len(mesh.faces)), min_len=1
    )
    areas = np.array([mesh.area_faces[c].sum() for c in components])
    centroids = np.array(
        [
            (mesh.triangles_center[c] * mesh.area_faces[c, None]).sum(0) / a
            for c, a in zip(components, areas, strict=True)
        ]
    )
    order = _position_order(centroids)
    face_region = np.empty(len(mesh.faces), dtype=int)
    for number, k in enumerate(order):
        face_region[components[k]] = number
    runs = feature_runs(mesh.vertices, feature_edges(mesh))
    midpoints = [_midpoint(mesh.vertices[r]) for r in runs]
    runs = [runs[i] for i in _position_order(np.array(midpoints).reshape(-1, 3))]
    return MeshModel(
        mesh,
        face_region,
        areas[order],
        centroids[order].reshape(-1, 3),
        runs,
        [(int(r[0]), int(r[-1])) for r in runs],
        np.array([np.linalg.norm(np.diff(mesh.vertices[r], axis=0), axis=1).sum() for r in runs]),
    )


def _midpoint(p: np.ndarray) -> np.ndarray:
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    return np.array([np.interp(s[-1] / 2, s, p[:, k]) for k in range(3)])


def feature_runs(vertices: np.ndarray, edges: np.ndarray) -> list[np.ndarray]:
    """Split the feature edges into runs at branches (degree ≠ 2) and corners."""
    neighbours: dict[int, list[int]] = {}
    for a, b in edges:
        neighbours.setdefault(int(a), []).append(int(b))
        neighbours.setdefault(int(b), []).append(int(a))

    def is_stop(v: int) -> bool:
        if len(neighbours[v]) != 2:
            return True
        a, b = neighbours[v]
        t1, t2 = vertices[v] - vertices[a], vertices[b] - vertices[v]
        cos = t1 @ t2 / (np.linalg.norm(t1) * np.linalg.norm(t2))
        return np.rad2deg(np.arccos(np.clip(cos, -1.0, 1.0))) > CORNER_DEG

    stops = {v for v in neighbours if is_stop(v)}
    used: set[tuple[int, int]] = set()
    runs = []
    starts = sorted(stops) + sorted(set(neighbours) - stops)  # closed loops last
    for start in starts:
        for first in neighbours[start]:
            if (start, first) in used:
                continue
            run = [start, first]
            used.update({(start, first), (first, start)})
            while run[-1] not in stops and run[-1] != start:
                here, before = run[-1], run[-2]
                step = next((n for n in neighbours[here] if n != before), None)
                if step is None or (here, step) in used:
                    break
                used.update({(here, step), (step, here)})
                run.append(step)
            runs.append(np.array(run))
    return runs
