"""Where processing-path points come from: CSV points, analytic curves, DXF files.

Every source yields the points r_j of paper §2 in the part frame P, in metres,
with optional surface normals (into the surface), ready for the B-spline fit.
Errors are ValueErrors whose text names the offending key or file content; the
cell loader prefixes the file name.
"""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path

import numpy as np

from offline_prog.constants import UNIT_SCALE
from offline_prog.path.closing import DUPLICATE_POINT_M, repeats_first

# Analytic and DXF curves are sampled at this spacing before fitting [m].
CURVE_SAMPLE_SPACING_M = 1e-3


@dataclasses.dataclass(frozen=True)
class PathPoints:
    """Points on the part: p_PR (N, 3) in P [m]; normals_P (N, 3) unit or None;
    rows (N,) each point's 0-based data row in its source (repeats dropped); exact: the
    seam on the part's model (path.exact_seam.ExactSeam) for a cad: seam, else None."""

    p_PR: np.ndarray
    normals_P: np.ndarray | None
    closed: bool
    rows: np.ndarray | None = None
    exact: object | None = None


def clean_points(p, normals, *, closed: bool) -> PathPoints:
    """Drop repeated consecutive points and, for closed paths, a repeated first point."""
    keep = np.concatenate([[True], np.linalg.norm(np.diff(p, axis=0), axis=1) > DUPLICATE_POINT_M])
    if closed and len(p) > 1 and np.linalg.norm(p[-1] - p[0]) <= DUPLICATE_POINT_M:
        keep[-1] = False
    p = p[keep]
    normals = None if normals is None else normals[keep]
    return PathPoints(p, normals, closed, np.flatnonzero(keep))


def read_csv_points(
    file: Path,
    *,
    units: str,
    closed: bool,
    close_tolerance_m: float = DUPLICATE_POINT_M,
    seam: str | None = None,
) -> PathPoints:
    """Read ``x,y,z[,nx,ny,nz][,seam]`` rows (header required) in P, scaled to metres.

    With a ``seam`` column the file holds several seams: ``seam`` picks the rows of one
    (in file order); without ``seam`` all rows must name the same one.
    A closed path's last row may repeat its first (within close_tolerance_m [m]):
    that row is dropped. Or the rows stop one step short: a gap up to twice the larger
    of the first and last steps is kept for the periodic fit to close
    (``path.closing``); a larger one is a missing stretch, OpenEndsError.
    """
    with open(file, newline="", encoding="utf-8") as stream:
        reader = csv.reader(row for row in stream if row.strip() and not row.startswith("#"))
        header = [h.strip().lower() for h in next(reader, [])]
        rows = list(reader)
    if header[:3] != ["x", "y", "z"]:
        raise ValueError(f"header must start with x,y,z (got {','.join(header) or 'nothing'})")
    has_normals = header[3:6] == ["nx", "ny", "nz"]
    extra = header[6:] if has_normals else header[3:]
    has_seams = extra == ["seam"]
    if extra and not has_seams:
        raise ValueError(f"unknown columns {extra}; allowed: x,y,z[,nx,ny,nz][,seam]")
    width = (6 if has_normals else 3) + has_seams
    for number, row in enumerate(rows, start=2):
        if len(row) != width:
            raise ValueError(f"line {number} has {len(row)} values, expected {width}")
    numbers = list(range(len(rows)))
    if has_seams:
        labels = [row[-1].strip() for row in rows]
        names = list(dict.fromkeys(labels))
        if seam is None and len(names) > 1:
            raise ValueError(f"holds seams {', '.join(names)}: choose one (a seam's name)")
        if seam is not None and seam not in names:
            raise ValueError(f"has no seam {seam!r} (seam column: {', '.join(names)})")
        numbers = [i for i, label in enumerate(labels) if seam is None or label == seam]
        rows = [rows[i][:-1] for i in numbers]
        width -= 1
    try:
        data = np.array([[float(v) for v in row] for row in rows], dtype=float).reshape(-1, width)
    except ValueError as error:
        raise ValueError(f"a value is not a number ({error})") from None
    bad_rows = np.flatnonzero(~np.isfinite(data).all(axis=1))
    if bad_rows.size:
        raise ValueError(f"line {numbers[bad_rows[0]] + 2} holds NaN or infinity")
    p = data[:, :3] * UNIT_SCALE[units]
    normals = None
    if has_normals:
        lengths = np.linalg.norm(data[:, 3:], axis=1)
        if lengths.min() < 1e-9:
            line = numbers[int(np.argmin(lengths))] + 2
            raise ValueError(f"line {line}: normal (nx,ny,nz) is zero")
        normals = data[:, 3:] / lengths[:, None]
    if closed and repeats_first(p, close_tolerance_m):
        p, normals = p[:-1], None if normals is None else normals[:-1]
        numbers = numbers[:-1]
    points = clean_points(p, normals, closed=closed)
    return dataclasses.replace(points, rows=np.asarray(numbers)[points.rows])


def _count(length: float) -> int:
    return max(64, int(np.ceil(length / CURVE_SAMPLE_SPACING_M)) + 1)


def line_points(start, end) -> np.ndarray:
    """(N, 3) points on the segment start → end (same units as given)."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    s = np.linspace(0.0, 1.0, _count(np.linalg.norm(end - start)))
    return start + s[:, None] * (end - start)


def arc_points(center, radius, start_deg, end_deg, *, closed: bool) -> np.ndarray:
    """(N, 3) points on a circle arc in the plane z = center[2] (counter-clockwise
    for end_deg > start_deg); a closed arc is the full circle without its last point."""
    center = np.asarray(center, float)
    sweep = np.deg2rad(end_deg - start_deg)
    n = _count(abs(sweep) * radius)
    phi = np.deg2rad(start_deg) + np.linspace(0.0, sweep, n, endpoint=not closed)
    return center + radius * np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=1)


def rounded_rectangle_points(center, size, corner_radius) -> np.ndarray:
    """(N, 3) points, counter-clockwise, on a closed rectangle with rounded corners
    in the plane z = center[2], starting at the middle of the bottom edge (not repeated
    at the end)."""
    center = np.asarray(center, float)
    w, h, r = float(size[0]), float(size[1]), float(corner_radius)
    if not (r > 0.0 and 2 * r <= min(w, h)):
        raise ValueError(f"corner_radius {r} must be > 0 and at most half of size {list(size)}")
    hx, hy = w / 2 - r, h / 2 - r
    outline = [np.array([[0.0, -h / 2]])]
    for k, (cx, cy) in enumerate([(hx, -hy), (hx, hy), (-hx, hy), (-hx, -hy)]):
        phi = np.deg2rad(np.linspace(-90.0 + 90.0 * k, 90.0 * k, 181))  # 0.5° steps
        outline.append(np.stack([cx + r * np.cos(phi), cy + r * np.sin(phi)], axis=1))
    outline.append(np.array([[0.0, -h / 2]]))
    xy = np.vstack(outline)
    points = resample_polyline(np.column_stack([xy, np.zeros(len(xy))]), CURVE_SAMPLE_SPACING_M)
    return points[:-1] + center


def read_dxf_points(
    file: Path,
    *,
    layer: str | None,
    closed: bool,
    units: str,
    entity: int | None = None,
    close_tolerance_m: float = DUPLICATE_POINT_M,
) -> PathPoints:
    """Sample one path entity (LINE, ARC, CIRCLE, (LW)POLYLINE, SPLINE, ELLIPSE) of a
    DXF file's modelspace, scaled to metres: the only one (optionally on one layer), or
    the ``entity``-th (0-based, in drawing order) of several.

    ``closed`` with an entity not flagged closed: its ends must meet (within
    close_tolerance_m [m]) or be one vertex step apart (``path.closing``), and the
    straight closing side is added, as the closed flag would draw it; else
    OpenEndsError. A flagged entity with ``closed`` false is refused."""
    import ezdxf

    try:
        document = ezdxf.readfile(file)
    except (OSError, ezdxf.DXFError) as error:
        raise ValueError(f"not a readable DXF file ({error})") from None
    kinds = ("LINE", "ARC", "CIRCLE", "LWPOLYLINE", "POLYLINE", "SPLINE", "ELLIPSE")
    entities = [e for e in document.modelspace() if e.dxftype() in kinds]
    if layer is not None:
        entities = [e for e in entities if e.dxf.layer == layer]
    where = f" on layer {layer!r}" if layer is not None else ""
    if entity is not None:
        if not 0 <= entity < len(entities):
            raise ValueError(f"has {len(entities)} path entities{where}, no entity {entity}")
        entities = [entities[entity]]
    if len(entities) != 1:
        raise ValueError(
            f"expected exactly one path entity{where}, found {len(entities)} "
            f"({', '.join(e.dxftype() for e in entities) or 'none'}); set dxf_layer or dxf_entity"
        )
    entity = entities[0]
    scale = UNIT_SCALE[units]
    vertices = _flatten(entity, 1e-6 / scale)
    is_closed = (
        entity.dxftype() == "CIRCLE"
        or bool(getattr(entity, "closed", False))
        or (getattr(entity, "is_closed", False) is True)
    )
    if is_closed and not closed:
        raise ValueError(f"the DXF {entity.dxftype()} is closed but path.closed is false")
    if closed and not is_closed and repeats_first(vertices * scale, close_tolerance_m):
        vertices = vertices[:-1]
    if closed:
        vertices = np.vstack([vertices, vertices[:1]])
    points = resample_polyline(vertices * scale, CURVE_SAMPLE_SPACING_M)
    return clean_points(points, None, closed=closed)


def _flatten(entity, sagitta: float) -> np.ndarray:
    """(N, 3) vertices on the entity's exact curve (arcs and splines are not
    replaced by Bézier approximations), within ``sagitta`` in drawing units."""
    kind = entity.dxftype()
    if kind in ("LWPOLYLINE", "POLYLINE"):
        pieces = [_flatten(piece, sagitta) for piece in entity.virtual_entities()]
        joined = [pieces[0]] + [piece[1:] for piece in pieces[1:]]
        return np.vstack(joined)
    if kind == "LINE":
        return np.array([tuple(entity.dxf.start), tuple(entity.dxf.end)], dtype=float)
    if kind in ("ARC", "CIRCLE"):
        return np.array([tuple(v) for v in entity.flattening(sagitta)], dtype=float)
    return np.array([tuple(v) for v in entity.flattening(distance=sagitta)], dtype=float)


def resample_polyline(points: np.ndarray, spacing: float) -> np.ndarray:
    """(M, 3) points on the polyline with chords at most ``spacing``; keeps vertices."""
    out = [points[:1]]
    for a, b in zip(points[:-1], points[1:], strict=True):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / spacing)))
        out.append(a + np.outer(np.arange(1, n + 1) / n, b - a))
    return np.vstack(out)
