"""Path sources: CSV (units, normals), DXF entities, analytic curves, mesh normals."""

import ezdxf
import numpy as np
import pytest
import trimesh

from offline_prog.path import sources as path_sources
from offline_prog.path.arc_length import ArcLengthPath
from offline_prog.path.bspline_fit import fit_bspline
from offline_prog.path.process_frames import mesh_normals, process_frames, spline_normal


def test_csv_in_mm_with_normals(tmp_path):
    file = tmp_path / "p.csv"
    file.write_text("# comment\nx,y,z,nx,ny,nz\n0,0,0,0,0,-2\n1000,0,0,0,0,-1\n1000,0,0,0,0,-1\n")
    points = path_sources.read_csv_points(file, units="mm", closed=False)
    np.testing.assert_allclose(points.p_PR, [[0, 0, 0], [1, 0, 0]])  # duplicate dropped
    np.testing.assert_allclose(points.normals_P, [[0, 0, -1], [0, 0, -1]])


def test_closed_csv_drops_repeated_first_point(tmp_path):
    file = tmp_path / "p.csv"
    file.write_text("x,y,z\n0,0,0\n1,0,0\n1,1,0\n0,0,0\n")
    assert len(path_sources.read_csv_points(file, units="m", closed=True).p_PR) == 3


def test_closed_csv_repeated_point_within_the_tolerance(tmp_path):
    file = tmp_path / "p.csv"
    file.write_text("x,y,z\n0,0,0\n1,0,0\n1,1,0\n0,0.00005,0\n")
    points = path_sources.read_csv_points(file, units="m", closed=True, close_tolerance_m=1e-4)
    assert len(points.p_PR) == 3  # the closing point, within the tolerance, dropped
    # Beyond the tolerance it is a point of its own, 0.05 mm short of the start: kept.
    points = path_sources.read_csv_points(file, units="m", closed=True, close_tolerance_m=1e-5)
    np.testing.assert_array_equal(points.rows, [0, 1, 2, 3])


def test_analytic_lengths():
    line = path_sources.line_points([0, 0, 0], [0.3, 0.4, 0])
    assert np.linalg.norm(line[-1] - line[0]) == pytest.approx(0.5)
    arc = path_sources.arc_points([0, 0, 0], 0.2, 0, 90, closed=False)
    np.testing.assert_allclose(np.linalg.norm(arc, axis=1), 0.2)
    rect = path_sources.rounded_rectangle_points([0, 0, 0], [0.4, 0.3], 0.05)
    fit = fit_bspline(rect, closed=True)
    expected = 2 * (0.4 + 0.3) - 8 * 0.05 + 2 * np.pi * 0.05
    assert ArcLengthPath(fit).length == pytest.approx(expected, abs=2e-4)


def test_rounded_rectangle_rejects_large_radius():
    with pytest.raises(ValueError, match="corner_radius"):
        path_sources.rounded_rectangle_points([0, 0, 0], [0.4, 0.3], 0.2)


def _dxf(tmp_path, add):
    document = ezdxf.new()
    add(document.modelspace())
    file = tmp_path / "p.dxf"
    document.saveas(file)
    return file


def test_dxf_closed_polyline_in_mm(tmp_path):
    file = _dxf(
        tmp_path, lambda msp: msp.add_lwpolyline([(0, 0), (100, 0), (100, 50), (0, 50)], close=True)
    )
    points = path_sources.read_dxf_points(file, layer=None, closed=True, units="mm")
    assert points.p_PR[:, 0].max() == pytest.approx(0.1)
    perimeter = np.linalg.norm(
        np.diff(np.vstack([points.p_PR, points.p_PR[:1]]), axis=0), axis=1
    ).sum()
    assert perimeter == pytest.approx(0.3)


def test_dxf_circle_and_layer_choice(tmp_path):
    def add(msp):
        msp.add_circle((0, 0), 100, dxfattribs={"layer": "PATH"})
        msp.add_line((0, 0), (1, 1), dxfattribs={"layer": "OTHER"})

    file = _dxf(tmp_path, add)
    points = path_sources.read_dxf_points(file, layer="PATH", closed=True, units="mm")
    np.testing.assert_allclose(np.linalg.norm(points.p_PR, axis=1), 0.1, atol=1e-6)
    with pytest.raises(ValueError, match="exactly one path entity, found 2"):
        path_sources.read_dxf_points(file, layer=None, closed=True, units="mm")
    with pytest.raises(ValueError, match="is closed but path.closed is false"):
        path_sources.read_dxf_points(file, layer="PATH", closed=False, units="mm")


def test_dxf_spline_matches_ezdxf_curve(tmp_path):
    fit_points = [(0, 0, 0), (50, 20, 0), (100, 0, 0), (150, -20, 0)]
    file = _dxf(tmp_path, lambda msp: msp.add_spline(fit_points))
    points = path_sources.read_dxf_points(file, layer=None, closed=False, units="mm")
    np.testing.assert_allclose(points.p_PR[0], [0, 0, 0], atol=1e-9)
    np.testing.assert_allclose(points.p_PR[-1], [0.15, -0.02, 0], atol=1e-9)
    assert np.linalg.norm(np.diff(points.p_PR, axis=0), axis=1).max() <= 1e-3 + 1e-12


def test_unreadable_dxf(tmp_path):
    file = tmp_path / "bad.dxf"
    file.write_text("not a dxf")
    with pytest.raises(ValueError, match="not a readable DXF"):
        path_sources.read_dxf_points(file, layer=None, closed=False, units="mm")


def test_mesh_normals_point_into_a_cylinder():
    radius = 0.3
    mesh = trimesh.creation.cylinder(radius=radius, height=1.0, sections=720)
    theta = np.linspace(-0.5, 0.5, 60)
    points = np.stack(
        [radius * np.cos(theta), radius * np.sin(theta), np.linspace(-0.2, 0.2, 60)], axis=1
    )
    normals = mesh_normals(mesh, points)
    inward = -points * [1, 1, 0] / radius
    assert np.all(np.einsum("ij,ij->i", normals, inward) > np.cos(np.deg2rad(0.5)))
    # Along the path the process frame's n is that inward normal (tangential part removed).
    path = ArcLengthPath(fit_bspline(points, closed=False))
    field = spline_normal(path, normals)
    s = np.linspace(0, path.length, 50)
    R, _, _ = process_frames(path, field, s)
    p = path(s, order=0)[0]
    expected = -p * [1, 1, 0] / np.linalg.norm(p[:, :2], axis=1, keepdims=True)
    assert np.all(np.einsum("ij,ij->i", R[:, :, 1], expected) > np.cos(np.deg2rad(1.0)))
