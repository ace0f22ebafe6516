"""Turning a checked cell file into the pipeline's inputs.

Semantic checks the types alone cannot express, the processing-path points from
the cell's one source (CSV, DXF or analytic curve), and the surface-normal field.
Every failure is a CellError naming the file and key.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from offline_prog import path_sources
from offline_prog.arc_length import ArcLengthPath
from offline_prog.cell import Cell, CellError
from offline_prog.process_frames import constant_normal, mesh_normals, spline_normal


def _error(file, key, reason) -> CellError:
    return CellError(file, key, reason)


def check_cell(file: Path, cell: Cell, robots_dir: Path) -> None:
    """Semantic checks the types alone cannot express."""
    robot_dirs = (
        sorted(p.name for p in robots_dir.iterdir() if p.is_dir()) if (robots_dir.is_dir()) else []
    )
    if cell.robot.model not in robot_dirs:
        raise _error(
            file,
            "robot.model",
            f"{cell.robot.model!r} is not a robot folder in "
            f"{robots_dir} (have: {', '.join(robot_dirs) or 'none'})",
        )
    path, motion = cell.path, cell.motion
    for key, value in (("path.units", path.units), ("part.mesh_units", cell.part.mesh_units)):
        if value not in path_sources.UNIT_SCALE:
            raise _error(file, key, f"{value!r} is not a unit (use m or mm)")
    sources = [k for k in ("points", "dxf", "analytic") if getattr(path, k) is not None]
    if len(sources) != 1:
        raise _error(
            file,
            "path",
            f"give exactly one of points, dxf, analytic (got {', '.join(sources) or 'none'})",
        )
    for key in ("points", "dxf"):
        value = getattr(path, key)
        if value is not None and not (file.parent / value).is_file():
            raise _error(file, f"path.{key}", f"file {file.parent / value} does not exist")
    if cell.part.mesh is not None and not (file.parent / cell.part.mesh).is_file():
        raise _error(file, "part.mesh", f"file {file.parent / cell.part.mesh} does not exist")
    if path.normal_from_mesh and cell.part.mesh is None:
        raise _error(file, "path.normal_from_mesh", "needs part.mesh")
    if path.normal is not None and np.linalg.norm(path.normal) < 1e-9:
        raise _error(file, "path.normal", "is the zero vector")
    if path.degree < 5:
        raise _error(file, "path.degree", f"{path.degree} < 5 (the paper needs degree ≥ 5)")
    for key, value in (
        ("path.fit_tolerance_mm", path.fit_tolerance_mm),
        ("motion.speed", motion.speed),
        ("motion.max_acceleration", motion.max_acceleration),
        ("motion.max_jerk", motion.max_jerk),
        ("motion.sample_rate_hz", motion.sample_rate_hz),
    ):
        if not value > 0:
            raise _error(file, key, f"must be > 0, got {value}")
    if motion.speed_reference not in ("tcp", "flange"):
        raise _error(
            file, "motion.speed_reference", f"{motion.speed_reference!r} (use tcp or flange)"
        )
    if not 0.0 <= cell.tool.free_rotation_deg <= 180.0:
        raise _error(file, "tool.free_rotation_deg", "must be within [0, 180]")
    if cell.tool.symmetry_axis not in ("x", "y", "z"):
        raise _error(file, "tool.symmetry_axis", f"{cell.tool.symmetry_axis!r} (use x, y or z)")
    if motion.cusp_smoothing_mm is not None and not motion.cusp_smoothing_mm > 0:
        raise _error(file, "motion.cusp_smoothing_mm", "must be > 0")
    if not motion.clearance >= 0:
        raise _error(file, "motion.clearance", f"must be ≥ 0 m, got {motion.clearance}")
    _check_shapes(file, cell)


def _check_shapes(file: Path, cell: Cell) -> None:
    """Shape names unique, mesh files present, allowed contacts naming known shapes."""
    owners = [
        ("part.geometry", cell.part.geometry),
        ("tool.geometry", cell.tool.geometry),
        ("obstacles", cell.obstacles),
    ]
    names = {cell.part.name} if cell.part.mesh else set()
    for key, shapes in owners:
        for i, shape in enumerate(shapes):
            where = f"{key}[{i}]"
            if shape.name in names:
                raise _error(file, f"{where}.name", f"{shape.name!r} is used twice")
            names.add(shape.name)
            if shape.shape not in ("box", "cylinder", "sphere", "capsule", "mesh"):
                raise _error(
                    file,
                    f"{where}.shape",
                    f"{shape.shape!r} (use box, cylinder, sphere, capsule or mesh)",
                )
            if shape.mesh_units not in path_sources.UNIT_SCALE:
                raise _error(file, f"{where}.mesh_units", f"{shape.mesh_units!r} (use m or mm)")
            if shape.shape == "mesh" and not (shape.mesh and (file.parent / shape.mesh).is_file()):
                raise _error(
                    file, f"{where}.mesh", f"file {file.parent / (shape.mesh or '')} does not exist"
                )
    for i, pair in enumerate(cell.allowed_contact):
        if len(pair) != 2:
            raise _error(file, f"allowed_contact[{i}]", f"expected [name, name], got {pair}")
        for name in pair:
            if name not in names:
                raise _error(
                    file,
                    f"allowed_contact[{i}]",
                    f"{name!r} is not a shape of the "
                    f"cell (have: {', '.join(sorted(names)) or 'none'})",
                )


def _analytic_points(file: Path, cell: Cell) -> path_sources.PathPoints:
    a, scale = cell.path.analytic, path_sources.UNIT_SCALE[cell.path.units]
    needs = {
        "line": ("start", "end"),
        "arc": ("center", "radius", "start_deg", "end_deg"),
        "rounded_rectangle": ("center", "size", "corner_radius"),
    }
    if a.kind not in needs:
        raise _error(file, "path.analytic.kind", f"{a.kind!r} (use {', '.join(needs)})")
    for key in needs[a.kind]:
        if getattr(a, key) is None:
            raise _error(file, f"path.analytic.{key}", f"missing (required for {a.kind})")
    closed = cell.path.closed
    if a.kind == "line":
        if closed:
            raise _error(file, "path.closed", "a line cannot be closed")
        p = path_sources.line_points(np.multiply(a.start, scale), np.multiply(a.end, scale))
    elif a.kind == "arc":
        if closed and not np.isclose(abs(a.end_deg - a.start_deg), 360.0):
            raise _error(file, "path.closed", "a closed arc must sweep 360°")
        if a.radius <= 0 or a.start_deg == a.end_deg:
            raise _error(file, "path.analytic", "an arc needs radius > 0 and start ≠ end")
        p = path_sources.arc_points(
            np.multiply(a.center, scale), a.radius * scale, a.start_deg, a.end_deg, closed=closed
        )
    else:
        if not closed:
            raise _error(file, "path.closed", "a rounded_rectangle is closed: set true")
        try:
            p = path_sources.rounded_rectangle_points(
                np.multiply(a.center, scale), np.multiply(a.size, scale), a.corner_radius * scale
            )
        except ValueError as error:
            raise _error(file, "path.analytic", str(error)) from None
    return path_sources.clean_points(p, None, closed=closed)


def load_points(file: Path, cell: Cell) -> path_sources.PathPoints:
    """The processing-path points in P [m] from the cell's one path source."""
    path = cell.path
    if path.analytic is not None:
        return _analytic_points(file, cell)
    key, source = ("path.points", path.points) if path.points else ("path.dxf", path.dxf)
    try:
        if path.points:
            return path_sources.read_csv_points(
                file.parent / source, units=path.units, closed=path.closed
            )
        return path_sources.read_dxf_points(
            file.parent / source, layer=path.dxf_layer, closed=path.closed, units=path.units
        )
    except ValueError as error:
        raise _error(file, key, f"{source}: {error}") from None


def normal_field(file: Path, cell: Cell, points, path: ArcLengthPath):
    """The surface-normal field, from exactly one of: CSV columns, path.normal, part.mesh."""
    given = [
        k
        for k, v in (
            ("nx,ny,nz columns", points.normals_P is not None),
            ("path.normal", cell.path.normal is not None),
            ("path.normal_from_mesh", cell.path.normal_from_mesh),
        )
        if v
    ]
    if len(given) != 1:
        raise _error(
            file,
            "path.normal",
            "give the surface normal exactly one way: nx,ny,nz "
            f"columns, path.normal, or path.normal_from_mesh (got {given or 'none'})",
        )
    if cell.path.normal is not None:
        return constant_normal(np.asarray(cell.path.normal, float))
    if points.normals_P is not None:
        return spline_normal(path, points.normals_P)
    import trimesh

    mesh = trimesh.load(file.parent / cell.part.mesh, force="mesh")
    mesh.apply_scale(path_sources.UNIT_SCALE[cell.part.mesh_units])
    return spline_normal(path, mesh_normals(mesh, points.p_PR))
