"""Wireframe outlines of the cell's primitive shapes, for the report's SVG views.

Visualization only. A shape is given as report.json keeps it (``kind``, ``size_m`` as
``CellShape.size_m``: box (x, y, z), sphere (r,), cylinder and capsule (r, length along
z); a mesh by its bounding box) and drawn as polylines in its owner's frame: a box's
twelve edges, a cylinder's end circles and four sides, a sphere's three great circles.
"""

from __future__ import annotations

import numpy as np

CIRCLE_POINTS = 33  # per drawn circle (closed)


def _circle(radius: float, z: float, plane: str = "xy") -> np.ndarray:
    """(CIRCLE_POINTS, 3) a circle of ``radius`` about the z axis at height z (plane xy),
    or in the plane xz / yz through the origin."""
    a = np.linspace(0.0, 2 * np.pi, CIRCLE_POINTS)
    c, s, zero = radius * np.cos(a), radius * np.sin(a), np.zeros_like(a)
    return {
        "xy": np.column_stack([c, s, zero + z]),
        "xz": np.column_stack([c, zero, s]),
        "yz": np.column_stack([zero, c, s]),
    }[plane]


def shape_outline(kind: str, size_m) -> list[np.ndarray]:
    """Polylines (K, 3) [m] outlining a shape in its own frame G (centred on G)."""
    if kind in ("box", "mesh"):
        half = np.asarray(size_m, float) / 2
        corners = half[:2] * np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]])
        lines = [np.column_stack([corners, np.full(5, z)]) for z in (-half[2], half[2])]
        lines += [np.array([[x, y, -half[2]], [x, y, half[2]]]) for x, y in corners[:4]]
        return lines
    if kind == "sphere":
        return [_circle(size_m[0], 0.0, plane) for plane in ("xy", "xz", "yz")]
    radius, length = size_m
    ends = (-length / 2, length / 2)
    lines = [_circle(radius, z) for z in ends]
    for x, y in radius * np.array([[1, 0], [-1, 0], [0, 1], [0, -1]]):
        lines.append(np.array([[x, y, ends[0]], [x, y, ends[1]]]))
    if kind == "capsule":  # its round ends
        lines += [_circle(radius, 0.0, "xz") + [0.0, 0.0, z] for z in ends]
    return lines


def outline_in(frame_pose: np.ndarray, shapes: list[dict]) -> list[np.ndarray]:
    """Polylines of ``shapes`` (each {kind, size_m, X_OG (4, 4)} in a frame O) in the
    frame A where O sits at ``frame_pose`` = X_AO (4, 4) [m]."""
    lines = []
    for shape in shapes:
        X_AG = frame_pose @ np.asarray(shape["X_OG"], float)
        for p_G in shape_outline(shape["kind"], shape["size_m"]):
            lines.append(p_G @ X_AG[:3, :3].T + X_AG[:3, 3])
    return lines
