"""The planning pipeline: cell file → processing path → flange trajectory → files.

Each stage lives in its own module (bspline_fit, arc_length, process_frames,
fixed_tcp, time_law, trajectory, cusps); this module checks what the cell asks
for, runs the stages in order, and turns stage failures into PlanErrors that
name the cell file and key.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from offline_prog import path_sources
from offline_prog.arc_length import ArcLengthPath
from offline_prog.bspline_fit import FittedSpline, fit_bspline
from offline_prog.cell import Cell, CellError, load_cell, transform
from offline_prog.cusps import Cusp, SmoothedFlangePath, find_cusps
from offline_prog.fixed_tcp import FlangePath
from offline_prog.process_frames import (
    NormalTangentError,
    constant_normal,
    mesh_normals,
    spline_normal,
)
from offline_prog.trajectory import WorkspaceTrajectory, plan_workspace_trajectory

log = logging.getLogger(__name__)

ROBOTS_DIR = Path(__file__).resolve().parents[1] / "robots"
# Grid spacing for the checks of the fitted path [m] and the largest tangent turn
# between neighbours on it before the path counts as doubling back.
CHECK_GRID_SPACING_M = 2.5e-4
MAX_TANGENT_TURN_RAD = np.deg2rad(90.0)


@dataclasses.dataclass
class Plan:
    """Everything a plan produced, for the writers and the tests."""

    cell_file: Path
    cell: Cell
    points: path_sources.PathPoints
    fitted: FittedSpline
    path: ArcLengthPath
    flange: FlangePath | SmoothedFlangePath
    trajectory: WorkspaceTrajectory
    cusps: list[Cusp]
    timings_s: dict[str, float]


def _error(file, key, reason):
    return CellError(file, key, reason)


def _check_cell(file: Path, cell: Cell, robots_dir: Path) -> None:
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
    if motion.cusp_smoothing_mm is not None and not motion.cusp_smoothing_mm > 0:
        raise _error(file, "motion.cusp_smoothing_mm", "must be > 0")


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


def _normal_field(file: Path, cell: Cell, points, path: ArcLengthPath):
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


def _check_turns(file: Path, path: ArcLengthPath) -> None:
    """Reject paths that stop or double back (a tangent flip makes frames undefined)."""
    if path.map.min_speed <= 0.0:
        raise _error(file, "path", "the fitted curve stops (zero tangent)")
    s = np.linspace(0.0, path.length, max(2001, int(path.length / CHECK_GRID_SPACING_M)))
    _, t = path(s, order=1)
    cos_turn = np.einsum("ij,ij->i", t[:-1], t[1:])
    worst = int(np.argmin(cos_turn))
    if cos_turn[worst] < np.cos(MAX_TANGENT_TURN_RAD):
        turn = np.rad2deg(np.arccos(np.clip(cos_turn[worst], -1.0, 1.0)))
        raise _error(
            file,
            "path",
            f"the path stops and turns back (tangent turns {turn:.0f}° "
            f"within {s[1] * 1e3:.2f} mm at σ = {s[worst]:.4f} m); split it or "
            "check the point order",
        )


def plan_cell(
    cell_file: str | Path,
    *,
    robots_dir: Path = ROBOTS_DIR,
    progress: Callable[[str], None] = lambda stage: None,
) -> Plan:
    """Run the fixed-TCP pipeline on a cell file (paper §§2–4).

    Args:
        cell_file: the cell YAML.
        robots_dir: folder of robot descriptions.
        progress: called with the name of each stage as it starts.

    Raises:
        CellError: bad input or geometry the method cannot handle (one line).
    """
    file = Path(cell_file)
    timings: dict[str, float] = {}
    clock = time.perf_counter()

    def lap(name, next_stage=None):
        nonlocal clock
        now = time.perf_counter()
        timings[name] = now - clock
        clock = now
        if next_stage:
            progress(next_stage)

    progress("reading the cell")

    cell = load_cell(file)
    _check_cell(file, cell, robots_dir)
    points = load_points(file, cell)
    lap("load", "fitting the B-spline")
    try:
        fitted = fit_bspline(
            points.p_PR,
            closed=cell.path.closed,
            degree=cell.path.degree,
            tolerance_m=cell.path.fit_tolerance_mm * 1e-3,
            n_control_points=cell.path.n_control_points,
        )
    except ValueError as error:
        raise _error(file, "path", str(error)) from None
    path = ArcLengthPath(fitted)
    _check_turns(file, path)
    lap("fit", "process frames and flange path")
    normal = _normal_field(file, cell, points, path)
    flange = FlangePath(
        path, normal, X_IT=transform(cell.tool.X_IT), X_PE=transform(cell.part.X_PE)
    )
    try:
        flange(np.linspace(0.0, path.length, 2001))  # frames defined everywhere?
        cusps = find_cusps(flange)
    except NormalTangentError as error:
        raise _error(file, "path.normal", str(error)) from None
    if cell.motion.cusp_smoothing_mm is not None:
        try:
            flange = SmoothedFlangePath(flange, cell.motion.cusp_smoothing_mm * 1e-3)
        except ValueError as error:
            raise _error(file, "motion.cusp_smoothing_mm", str(error)) from None
    lap("frames", "timing and sampling the trajectory")
    motion = cell.motion
    if motion.speed_reference == "flange" and any(c.kind == "cusp" for c in cusps):
        first = next(c for c in cusps if c.kind == "cusp")
        raise _error(
            file,
            "motion.speed_reference",
            f"flange: the flange stops at a cusp at "
            f"σ = {first.sigma_m:.4f} m; use tcp or motion.cusp_smoothing_mm",
        )
    trajectory = plan_workspace_trajectory(
        flange,
        v_max=motion.speed,
        a_max=motion.max_acceleration,
        j_max=motion.max_jerk,
        reference=motion.speed_reference,
        rate_hz=motion.sample_rate_hz,
    )
    lap("trajectory")
    return Plan(file, cell, points, fitted, path, flange, trajectory, cusps, timings)
