"""How far a seam may move into the part: ``cad.offset_mm`` within the part's depth.

A positive offset moves the seam along n, into the part. Where the part is thinner than
the offset (a plate 8 mm thick and an offset of 12 mm), the moved seam lies outside the
part, past its far side: a seam no tool can follow on the part. The depth at a seam point
is how far a ray from it along n runs inside the part, cast against the model's
triangles (a STEP solid tessellated within its tolerance). All in the part frame P [mm].
"""

from __future__ import annotations

import numpy as np

from offline_prog.cad.picking import PickError
from offline_prog.cad.seam_samples import SeamSamples

MAX_RAYS = 200  # seam points whose depth is measured (evenly along the seam)
START_MM = 1e-3  # a ray starts this far inside, past the surface it leaves from


def depths_mm(vertices: np.ndarray, triangles: np.ndarray, p: np.ndarray, inward: np.ndarray):
    """(N,) distance [mm] from each point p (N, 3) along its unit ``inward`` direction
    (N, 3) to where the ray leaves the solid of ``triangles`` (T, 3) on ``vertices``
    (V, 3) [mm]; inf where it never does (an open mesh)."""
    import trimesh

    mesh = trimesh.Trimesh(vertices, triangles, process=False)
    origins = p + START_MM * inward
    hits, rays, _ = mesh.ray.intersects_location(origins, inward, multiple_hits=True)
    depth = np.full(len(p), np.inf)
    distance = np.einsum("ij,ij->i", hits - origins[rays], inward[rays])
    ahead = distance > 0.0
    np.minimum.at(depth, rays[ahead], distance[ahead] + START_MM)
    return depth


def check_offset(
    vertices: np.ndarray,
    triangles: np.ndarray,
    samples: SeamSamples,
    offset_mm: float,
    *,
    key: str,
    tolerance_mm: float = 0.0,
) -> None:
    """Refuse an offset into the part (``offset_mm`` > 0) deeper than the part is along
    n at any of the seam's points (``samples``, already offset).

    Args:
        tolerance_mm: how far the triangles may be from the exact surface.

    Raises:
        PickError: naming ``<key>.offset_mm``, the depth and where it is least.
    """
    if offset_mm <= 0.0:
        return
    every = max(1, len(samples.p) // MAX_RAYS)
    outward = samples.outward[::every]
    on_surface = samples.p[::every] + offset_mm * outward
    depth = depths_mm(vertices, triangles, on_surface, -outward)
    thinnest = int(np.argmin(depth))
    if offset_mm > depth[thinnest] + tolerance_mm:
        where = ", ".join(f"{v:.2f}" for v in on_surface[thinnest])
        raise PickError(
            f"{key}.offset_mm",
            f"{offset_mm:g} mm into the part is beyond its depth along n: "
            f"{depth[thinnest]:.2f} mm at [{where}] (the seam would leave the part)",
        )
