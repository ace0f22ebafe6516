"""Turning a checked cell file into the path's inputs.

The processing-path points from the cell's one source (CSV, DXF or analytic curve),
and the surface-normal field. Every failure is a InputError naming the file and key.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from offline_prog.config.cell import CAD_FIT_TOLERANCE_MM, FIT_TOLERANCE_MM, Cell
from offline_prog.errors import InputError
from offline_prog.path import sources as path_sources
from offline_prog.path.arc_length import ArcLengthPath
from offline_prog.path.closing import OpenEndsError
from offline_prog.path.process_frames import (
    NormalField,
    constant_normal,
    mesh_normals,
    normal_fit_angles,
    spline_normal,
)


@dataclasses.dataclass(frozen=True)
class NormalFit:
    """How far the fitted normal field is from the given normals [deg].

    source: "points" (CSV nx,ny,nz: measured), "constant" (path.normal: exact, 0),
    "mesh" (part.mesh: not measured, None) or "cad" (the model's faces at the fit's
    points: measured). worst_row: 1-based CSV data row of the largest angle (row 1 is
    the first point after the header), or None. edge_max_error_mm, edge_rms_error_mm:
    for a cad: seam, the fitted path's distance from the model's exact seam [mm];
    edge_tangent_max_error_deg: the largest angle between the fitted path's tangent and
    the exact seam's [deg].
    """

    source: str
    max_error_deg: float | None
    rms_error_deg: float | None
    worst_row: int | None = None
    edge_max_error_mm: float | None = None
    edge_rms_error_mm: float | None = None
    edge_tangent_max_error_deg: float | None = None


def _error(file, key, reason) -> InputError:
    return InputError(file, key, reason)


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
    if path.cad is not None:  # Open CASCADE (seconds to import) only for these
        from offline_prog.path.cad_source import cad_points

        points = cad_points(file, cell)
        if path.fit_tolerance_mm is None:  # not given: exact, unless corners round it
            corners = points.exact is not None and points.exact.corners
            path.fit_tolerance_mm = FIT_TOLERANCE_MM if corners else CAD_FIT_TOLERANCE_MM
        return points
    key, source = ("path.points", path.points) if path.points else ("path.dxf", path.dxf)
    close_tolerance_m = path.fit_tolerance_mm * 1e-3
    try:
        if path.points:
            return path_sources.read_csv_points(
                file.parent / source,
                units=path.units,
                closed=path.closed,
                close_tolerance_m=close_tolerance_m,
                seam=path.csv_seam,
            )
        return path_sources.read_dxf_points(
            file.parent / source,
            layer=path.dxf_layer,
            closed=path.closed,
            units=path.units,
            entity=path.dxf_entity,
            close_tolerance_m=close_tolerance_m,
        )
    except OpenEndsError as error:
        raise _error(
            file,
            "path.closed",
            f"true, but the ends of {source} are {error.gap_m * 1e3:.3f} mm apart, more "
            f"than twice the point spacing there (first step {error.first_step_m * 1e3:.3f} "
            f"mm, last step {error.last_step_m * 1e3:.3f} mm): a stretch of the contour is "
            "missing; add its points, or set closed: false",
        ) from None
    except ValueError as error:
        raise _error(file, key, f"{source}: {error}") from None


def normal_field(file: Path, cell: Cell, points, path: ArcLengthPath) -> NormalField:
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
    if points.exact is not None:  # a cad: seam: exact normals, fitted to tolerance
        from offline_prog.path.cad_normal import model_normal

        return model_normal(path, points.normals_P, np.deg2rad(cell.path.normal_tolerance_deg))
    if points.normals_P is not None:
        return spline_normal(path, points.normals_P)
    import trimesh

    mesh = trimesh.load(file.parent / cell.part.mesh, force="mesh")
    mesh.apply_scale(path_sources.UNIT_SCALE[cell.part.mesh_units])
    return spline_normal(path, mesh_normals(mesh, points.p_PR))


def check_normal_fit(file: Path, cell: Cell, points, path: ArcLengthPath, field) -> NormalFit:
    """Measure the normal-fit residual; InputError above path.normal_tolerance_deg.

    The normal field has as few control points as the position fit needs, so a few
    wrong normals tilt the tool along the whole path; this makes that loud.
    """
    if cell.path.normal is not None:
        return NormalFit("constant", 0.0, 0.0)
    if points.normals_P is None:
        return NormalFit("mesh", None, None)
    angles = np.rad2deg(normal_fit_angles(path, points.normals_P, field))
    if points.exact is not None:
        return _check_cad_fit(file, cell, points, path, angles)
    worst = int(np.argmax(angles))
    row = int(points.rows[worst] if points.rows is not None else worst) + 1
    fit = NormalFit("points", float(angles[worst]), float(np.sqrt(np.mean(angles**2))), row)
    tolerance = cell.path.normal_tolerance_deg
    if fit.max_error_deg > tolerance:
        raise _error(
            file,
            "path.normal_tolerance_deg",
            f"the fitted surface normal is {fit.max_error_deg:.2f}° off the normal given at "
            f"row {row} of {cell.path.points} (file line {row + 1}), more than {tolerance:g}° "
            f"(RMS {fit.rms_error_deg:.2f}°): check the normals near that row",
        )
    return fit


def _check_cad_fit(file: Path, cell: Cell, points, path: ArcLengthPath, angles) -> NormalFit:
    """A cad: seam's fit: normals against the model's, the path against the exact seam."""
    from offline_prog.path.exact_seam import path_to_reference

    worst = int(np.argmax(angles))
    edge_max, edge_rms, tangent = path_to_reference(points.exact, path)
    fit = NormalFit(
        "cad",
        float(angles[worst]),
        float(np.sqrt(np.mean(angles**2))),
        None,
        edge_max * 1e3,
        edge_rms * 1e3,
        float(np.rad2deg(tangent)),
    )
    tolerance = cell.path.normal_tolerance_deg
    if fit.max_error_deg > tolerance:
        at = np.round(points.p_PR[worst] * 1e3, 2).tolist()
        raise _error(
            file,
            "path.normal_tolerance_deg",
            f"the fitted surface normal is {fit.max_error_deg:.2f}° off the model's at "
            f"{at} mm, more than {tolerance:g}°: the normal turns faster than the fit "
            "follows (lower path.fit_tolerance_mm, or pick another normal face)",
        )
    return fit
