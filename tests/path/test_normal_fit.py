"""Issue 12: the normal-fit residual is measured, reported and bounded.

The normal field rides on the position fit's few control points, so a few wrong
per-point normals used to tilt the tool along the whole path without a word.
"""

import re

import numpy as np
import pytest

from offline_prog.errors import InputError
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import fit_path, load_inputs

from conftest import CELLS, random_curve_points

TAPE = CELLS / "tape_cylinder_ur10e.yaml"
BAD_ROWS = {101: 30.0, 201: 20.0}  # 1-based CSV data row: tilt [deg]


def _smooth_normals(n: int) -> np.ndarray:
    """(n, 3) unit normals, mostly −z, turning slowly along the path."""
    phase = np.linspace(0.0, 1.0, n)
    normals = np.stack([0.3 * np.sin(3 * phase), 0.2 * np.cos(2 * phase), -np.ones(n)], axis=1)
    return normals / np.linalg.norm(normals, axis=1, keepdims=True)


def _tilted(normal: np.ndarray, degrees: float) -> np.ndarray:
    """normal turned by degrees about an axis perpendicular to it."""
    axis = np.cross(normal, [1.0, 0.0, 0.0])
    axis /= np.linalg.norm(axis)
    a = np.deg2rad(degrees)
    return normal * np.cos(a) + np.cross(axis, normal) * np.sin(a)


def _cell(tmp_path, normals, extra: str = ""):
    """The tape demo cell on a seeded random smooth path with the given normals."""
    points = random_curve_points(np.random.default_rng(12), closed=False) * 1e3  # mm
    rows = np.hstack([points, normals])
    csv = tmp_path / "path.csv"
    np.savetxt(csv, rows, delimiter=",", header="x,y,z,nx,ny,nz", comments="", fmt="%.9f")
    text = TAPE.read_text()
    text = text.replace("data/tape_cylinder.csv", str(csv))
    text = text.replace("data/cylinder_shell.stl", str(CELLS / "data/cylinder_shell.stl"))
    text = text.replace("  closed: false\n", f"  closed: false\n{extra}")
    cell = tmp_path / "cell.yaml"
    cell.write_text(text)
    return cell


def _fit(cell):
    return fit_path(load_inputs(cell, ROBOTS_DIR))


def test_consistent_normals_fit_with_a_small_residual(tmp_path):
    fit = _fit(_cell(tmp_path, _smooth_normals(300))).normal_fit
    assert fit.source == "points"
    assert fit.max_error_deg < 0.1
    assert 0.0 < fit.rms_error_deg <= fit.max_error_deg


def test_two_tilted_normals_fail_naming_the_worst_row(tmp_path):
    normals = _smooth_normals(300)
    for row, degrees in BAD_ROWS.items():
        normals[row - 1] = _tilted(normals[row - 1], degrees)
    with pytest.raises(InputError) as caught:
        _fit(_cell(tmp_path, normals))
    message = str(caught.value)
    assert "\n" not in message
    assert caught.value.key == "path.normal_tolerance_deg"
    assert "row 101 of" in message and "(file line 102)" in message
    angle = float(re.search(r"is ([0-9.]+)° off", message).group(1))
    assert 15.0 < angle < 30.0


def test_a_looser_tolerance_passes_and_reports_the_tilt(tmp_path):
    normals = _smooth_normals(300)
    normals[100] = _tilted(normals[100], 30.0)
    fit = _fit(_cell(tmp_path, normals, "  normal_tolerance_deg: 45\n")).normal_fit
    assert fit.worst_row == 101
    assert 15.0 < fit.max_error_deg < 30.0


def test_normal_tolerance_must_be_positive(tmp_path):
    cell = _cell(tmp_path, _smooth_normals(300), "  normal_tolerance_deg: 0\n")
    with pytest.raises(InputError, match=r"path\.normal_tolerance_deg: must be > 0"):
        load_inputs(cell, ROBOTS_DIR)


def test_tape_demo_reports_the_normal_residual():
    from offline_prog.plan import plan_cell
    from offline_prog.results.report import report

    fit = report(plan_cell(TAPE))["fit"]
    assert fit["normal_source"] == "points"
    assert fit["normal_tolerance_deg"] == 2.0
    assert 0.0 < fit["normal_rms_error_deg"] <= fit["normal_max_error_deg"] < 0.1
    assert fit["normal_worst_row"] is not None
