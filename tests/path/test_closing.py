"""Closed contours as CAD and measuring tools write them: the last point repeats the
first, or stops one step short (closed by the periodic fit); a missing stretch is
refused, naming the gap and the spacing."""

import subprocess
import sys
import tempfile
from pathlib import Path

import ezdxf
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from offline_prog.errors import InputError
from offline_prog.path import sources as path_sources
from offline_prog.path.bspline_fit import fit_bspline
from offline_prog.path.closing import OpenEndsError

from conftest import REPO

TOLERANCE_M = 1e-4  # path.fit_tolerance_mm's default, 0.1 mm
SEAM_STEP = 1e-7  # [m of the parameter] either side of the closure


def rounded_rectangle_distance(p: np.ndarray, size, r: float) -> np.ndarray:
    """(N,) distance [m] of points p (N, 3) in z = 0 to a rounded rectangle's outline
    centred at the origin (its signed distance field, taken absolute)."""
    q = np.abs(p[:, :2]) - (np.asarray(size) / 2 - r)
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    inside = np.minimum(q.max(axis=1), 0.0)
    return np.abs(outside + inside - r)


def plate_border(n=160, size=(0.3, 0.2), r=0.022, h_min=2.3e-3, h_max=26e-3, gap=15.86e-3):
    """(n, 3) points [m] on a plate's rounded border as a measuring tool writes it:
    dense (h_min) on the corners, sparse (up to h_max) mid-edge, and the first point
    not repeated: the last is one step (about ``gap``) short of it."""
    dense = path_sources.rounded_rectangle_points([0, 0, 0], size, r)
    dense = np.vstack([dense, dense[:1]])
    s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(dense, axis=0), axis=1))])
    from_corner = np.maximum(np.max(np.asarray(size) / 2 - r - np.abs(dense[:, :2]), axis=1), 0)
    spacing = np.minimum(h_max, h_min + 0.2 * from_corner)
    count = np.concatenate([[0], np.cumsum(np.diff(s) / spacing[:-1])])
    s_k = np.interp(np.arange(n) * count[-1] / n, count, s)
    p = np.column_stack([np.interp(s_k, s, dense[:, i]) for i in range(3)])
    closing = np.linalg.norm(p - np.roll(p, 1, axis=0), axis=1)
    return np.roll(p, -int(np.argmin(np.abs(closing - gap))), axis=0)


def write_csv(file: Path, p: np.ndarray) -> Path:
    file.write_text("x,y,z\n" + "".join(f"{x:.4f},{y:.4f},{z:.4f}\n" for x, y, z in p * 1e3))
    return file


def assert_closes_smoothly(fitted, degree: int = 5) -> None:
    """The periodic fit is C^{p−1} across the closure: each derivative up to p − 1 is
    the same just before and just after it (within what the next one changes there:
    the closure is a knot, the only one this close)."""
    near = np.array([-1.0, -0.5, 0.5, 1.0]) * SEAM_STEP
    for order in range(degree):
        before = fitted(np.array([fitted.period - SEAM_STEP]), order)[0]
        after = fitted(np.array([SEAM_STEP]), order)[0]
        change = np.linalg.norm(fitted(near, order + 1), axis=1).max() * 2 * SEAM_STEP
        assert np.linalg.norm(after - before) <= 1.01 * change + 1e-12, order
    jump = fitted(np.array([SEAM_STEP]), degree) - fitted(np.array([-SEAM_STEP]), degree)
    assert np.linalg.norm(jump) > 0  # a degree-p spline: its p-th derivative may jump


def test_plate_border_one_step_short_is_closed_by_the_fit(tmp_path):
    size, r = (0.3, 0.2), 0.022
    p = plate_border(size=size, r=r)
    steps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    gap = np.linalg.norm(p[-1] - p[0])
    assert len(p) == 160 and 2.1e-3 < steps.min() < 2.4e-3 and 23e-3 < steps.max() < 24e-3
    assert 15e-3 < gap < 16e-3  # like its neighbours, far beyond the fit tolerance
    points = path_sources.read_csv_points(
        write_csv(tmp_path / "border.csv", p),
        units="mm",
        closed=True,
        close_tolerance_m=TOLERANCE_M,
    )
    assert len(points.p_PR) == 160  # nothing dropped: the last point is a point
    fitted = fit_bspline(points.p_PR, closed=True, tolerance_m=TOLERANCE_M)
    assert fitted.max_error_m <= TOLERANCE_M
    assert_closes_smoothly(fitted)
    # Across the gap, where no point is given, the curve stays on the plate's border.
    u_gap = np.linspace(fitted.u_data[-1], fitted.period, 200)
    assert rounded_rectangle_distance(fitted(u_gap), size, r).max() <= TOLERANCE_M


CELL = """\
robot: {model: kuka_kr16_2, X_IB: {translation: [0, 0, 0], rotation: !Rpy {deg: [0, 0, 0]}}}
tool: {X_IT: {translation: [1.0, 0, 0.5], rotation: !Rpy {deg: [90, 0, 0]}}}
part: {X_PE: {translation: [0, 0, 0.1], rotation: !Rpy {deg: [180, 0, 0]}}}
path: {points: border.csv, units: mm, closed: true, normal: [0, 0, 1]}
motion: {speed: 0.1, max_acceleration: 1.0, max_jerk: 10.0}
"""


def test_missing_stretch_is_refused_naming_gap_and_spacing(tmp_path):
    write_csv(tmp_path / "border.csv", plate_border()[:-12])  # 12 points lost at the end
    cell = tmp_path / "cell.yaml"
    cell.write_text(CELL)
    from offline_prog.config.cell import load_cell
    from offline_prog.path.inputs import load_points

    with pytest.raises(InputError) as info:
        load_points(cell, load_cell(cell))
    message = str(info.value)
    assert message.startswith(f"{cell}: path.closed: true, but the ends of border.csv are ")
    assert "mm apart, more than twice the point spacing there (first step " in message
    assert "a stretch of the contour is missing" in message
    run = subprocess.run(
        [sys.executable, "-m", "offline_prog", "plan", str(cell), "--out", str(tmp_path / "o")],
        cwd=REPO,
        capture_output=True,
        text=True,
    )
    assert run.returncode == 2 and run.stdout == ""
    assert run.stderr.strip() == f"error: {message}" and not (tmp_path / "o").exists()


def _dxf(tmp_path: Path, vertices, *, close: bool) -> Path:
    document = ezdxf.new()
    document.modelspace().add_lwpolyline(vertices, close=close)
    file = tmp_path / "p.dxf"
    document.saveas(file)
    return file


RECTANGLE = [(0, 0), (100, 0), (100, 50), (0, 50)]  # mm


def _perimeter(points) -> float:
    loop = np.vstack([points.p_PR, points.p_PR[:1]])
    return float(np.linalg.norm(np.diff(loop, axis=0), axis=1).sum())


@pytest.mark.parametrize(
    ("vertices", "close"),
    [
        (RECTANGLE, True),  # the closed flag set
        (RECTANGLE, False),  # no flag, the fourth side implied (one side short)
        (RECTANGLE + [(0, 0)], False),  # no flag, the last vertex repeats the first
    ],
)
def test_dxf_polyline_with_and_without_its_closed_flag(tmp_path, vertices, close):
    file = _dxf(tmp_path, vertices, close=close)
    points = path_sources.read_dxf_points(
        file, layer=None, closed=True, units="mm", close_tolerance_m=TOLERANCE_M
    )
    # Closed by the straight side the flag would draw: the rectangle's 300 mm.
    assert _perimeter(points) == pytest.approx(0.3)
    assert np.linalg.norm(np.diff(points.p_PR, axis=0), axis=1).max() <= 1e-3 + 1e-12
    fitted = fit_bspline(points.p_PR, closed=True, tolerance_m=TOLERANCE_M)
    assert_closes_smoothly(fitted)


def test_dxf_polyline_open_or_missing_a_stretch(tmp_path):
    file = _dxf(tmp_path, RECTANGLE, close=False)
    points = path_sources.read_dxf_points(file, layer=None, closed=False, units="mm")
    assert np.linalg.norm(np.diff(points.p_PR, axis=0), axis=1).sum() == pytest.approx(0.25)
    flagged = _dxf(tmp_path, RECTANGLE, close=True)
    with pytest.raises(ValueError, match="LWPOLYLINE is closed but path.closed is false"):
        path_sources.read_dxf_points(flagged, layer=None, closed=False, units="mm")
    # Three quarters of a 36-gon: the gap is a quarter of the circle, 9 sides' worth.
    phi = np.deg2rad(np.arange(0, 280, 10))
    arc = _dxf(tmp_path, list(zip(100 * np.cos(phi), 100 * np.sin(phi), strict=True)), close=False)
    with pytest.raises(OpenEndsError, match="first step 17.431 mm") as info:
        path_sources.read_dxf_points(arc, layer=None, closed=True, units="mm")
    assert info.value.gap_m == pytest.approx(2 * 0.1 * np.sin(np.deg2rad(45)))


def _contour(shape: str, size: float, n: int, rng) -> tuple[np.ndarray, callable]:
    """n points [m] unevenly spaced (±15 % of a step) on a closed contour, first not repeated,
    and the contour's distance function."""
    if shape == "circle":
        phi = (np.arange(n) + rng.uniform(-0.15, 0.15, n)) * 2 * np.pi / n
        p = size * np.column_stack([np.cos(phi), np.sin(phi), np.zeros(n)])
        return p, lambda q: np.abs(np.linalg.norm(q[:, :2], axis=1) - size)
    box, r = (size, 0.7 * size), 0.2 * size
    dense = path_sources.rounded_rectangle_points([0, 0, 0], box, r)
    dense = np.vstack([dense, dense[:1]])
    s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(dense, axis=0), axis=1))])
    s_k = (np.arange(n) + rng.uniform(-0.15, 0.15, n)) * s[-1] / n % s[-1]
    p = np.column_stack([np.interp(np.sort(s_k), s, dense[:, i]) for i in range(3)])
    return p, lambda q: rounded_rectangle_distance(q, box, r)


@settings(max_examples=30, derandomize=True, deadline=None, database=None)
@given(
    shape=st.sampled_from(["circle", "rounded_rectangle"]),
    size=st.floats(0.05, 0.5),
    n=st.integers(40, 200),
    seed=st.integers(0, 2**32 - 1),
    repeat_first=st.booleans(),
)
def test_closed_contours_as_written(shape, size, n, seed, repeat_first):
    """Any closed contour, with or without its first point repeated, is read whole and
    fitted closed (C^{p−1}, within tolerance, the circle's closing stretch on the
    circle); the same contour missing a quarter is refused."""
    p, distance = _contour(shape, size, n, np.random.default_rng(seed))
    written = np.vstack([p, p[:1]]) if repeat_first else p
    with tempfile.TemporaryDirectory() as folder:
        file = write_csv(Path(folder) / "c.csv", written)
        points = path_sources.read_csv_points(
            file, units="mm", closed=True, close_tolerance_m=TOLERANCE_M
        )
        assert len(points.p_PR) == n
        with pytest.raises(OpenEndsError):
            path_sources.read_csv_points(
                write_csv(file, p[: 3 * n // 4]),
                units="mm",
                closed=True,
                close_tolerance_m=TOLERANCE_M,
            )
    fitted = fit_bspline(points.p_PR, closed=True, tolerance_m=TOLERANCE_M)
    assert fitted.max_error_m <= TOLERANCE_M
    assert_closes_smoothly(fitted)
    assert distance(fitted(fitted.u_data)).max() <= TOLERANCE_M + 1e-6  # CSV rounding
    if shape == "circle":
        u_gap = np.linspace(fitted.u_data[-1], fitted.period, 50)
        assert distance(fitted(u_gap)).max() <= TOLERANCE_M
