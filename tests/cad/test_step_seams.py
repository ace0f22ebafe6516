"""Seams from STEP parts built here with Open CASCADE, written, read back through a cell
file and fitted as plan does: compared with the analytic edge (issue 26's acceptance:
path within 0.01 mm, normal within 0.05°, arc length within 0.01 %)."""

import numpy as np
import pytest
from cad_parts import (
    BRACKET_R,
    CYLINDER,
    PLATE,
    PLATE_R,
    angle_deg,
    bracket_profile,
    cad_cell,
    chamfered_cylinder,
    filleted_plate,
    l_bracket,
    rounded_rectangle,
    sampled,
    write_step,
)

from offline_prog.job.seams import seam_inputs
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import fit_path, flange_paths, load_inputs

PATH_TOL_MM = 0.01
NORMAL_TOL_DEG = 0.05
LENGTH_TOL_REL = 1e-4


@pytest.fixture(scope="module")
def parts(tmp_path_factory):
    folder = tmp_path_factory.mktemp("parts")
    for name, build in (
        ("plate", filleted_plate),
        ("bracket", l_bracket),
        ("cylinder", chamfered_cylinder),
    ):
        write_step(build(), folder / f"{name}.step")
    return folder


def fitted_seams(folder, model, seams):
    file = cad_cell(folder, model, seams)
    inputs = load_inputs(file, ROBOTS_DIR)
    return [fit_path(seam_inputs(inputs, k)) for k in range(len(seams))]


def test_plate_top_loop_with_the_top_face_normal(parts):
    (fit,) = fitted_seams(
        parts, "plate.step", [{"cad": {"loop": {"face_near_mm": [150, 100, 10]}}}]
    )
    p, n = sampled(fit)
    distance, _ = rounded_rectangle(p, PLATE[2])
    assert distance.max() < PATH_TOL_MM
    assert angle_deg(n, [0.0, 0.0, -1.0]).max() < NORMAL_TOL_DEG  # into the top face
    length = 2 * (PLATE[0] + PLATE[1] - 4 * PLATE_R) + 2 * np.pi * PLATE_R
    assert abs(fit.path.length * 1e3 - length) / length < LENGTH_TOL_REL
    assert fit.normal_fit.source == "cad"
    assert fit.normal_fit.edge_max_error_mm < PATH_TOL_MM


def test_plate_bottom_chain_round_a_fillet_keeps_the_side_normal(parts):
    """Three edges (line, fillet arc, line) joined G1: one seam; the side face's
    normal follows the fillet (the faces tangent to it)."""
    seam = {
        "cad": {
            "chain": {"near_mm": [[100, 0, 0], [300, 100, 0]]},
            "normal": {"face_near_mm": [150, 0, 5]},
        }
    }
    (fit,) = fitted_seams(parts, "plate.step", [seam])
    p, n = sampled(fit)
    distance, outward = rounded_rectangle(p, 0.0)
    assert distance.max() < PATH_TOL_MM
    assert angle_deg(n, -outward).max() < NORMAL_TOL_DEG
    length = PLATE[0] + PLATE[1] - 4 * PLATE_R + np.pi * PLATE_R / 2  # whole edges
    assert abs(fit.path.length * 1e3 - length) / length < LENGTH_TOL_REL
    assert p[0] == pytest.approx([PLATE_R, 0, 0], abs=PATH_TOL_MM)  # the whole first edge


def test_bracket_chain_across_the_fillet_between_its_legs(parts):
    seam = {
        "cad": {
            "chain": {"near_mm": [[60, 0, 10], [10, 0, 60]]},
            "normal": {"face_near_mm": [20 - 7.0711, 30, 20 - 7.0711]},
        }
    }
    (fit,) = fitted_seams(parts, "bracket.step", [seam])
    p, n = sampled(fit)
    distance, outward = bracket_profile(p)
    assert distance.max() < PATH_TOL_MM
    assert angle_deg(n, -outward).max() < NORMAL_TOL_DEG
    length = 2 * (100.0 - 10.0 - BRACKET_R) + np.pi * BRACKET_R / 2
    assert abs(fit.path.length * 1e3 - length) / length < LENGTH_TOL_REL


def test_cylinder_rim_loop_with_the_chamfer_normal(parts):
    radius, height, chamfer = CYLINDER
    on_chamfer = (radius - chamfer / 2) * np.array([np.cos(0.8), np.sin(0.8), 0.0])
    on_chamfer[2] = height - chamfer / 2
    seams = [
        {
            "cad": {
                "loop": {"face_near_mm": [0, 10, height]},
                "normal": {"face_near_mm": on_chamfer.tolist()},
            }
        },
        {"cad": {"loop": {"face_near_mm": [0, 10, height]}}},
    ]
    chamfered, top = fitted_seams(parts, "cylinder.step", seams)
    for fit in (chamfered, top):
        p, n = sampled(fit)
        r = radius - chamfer
        assert np.hypot(np.linalg.norm(p[:, :2], axis=1) - r, p[:, 2] - height).max() < 0.01
        assert abs(fit.path.length * 1e3 - 2 * np.pi * r) / (2 * np.pi * r) < LENGTH_TOL_REL
    p, n = sampled(chamfered)
    radial = p[:, :2] / np.linalg.norm(p[:, :2], axis=1, keepdims=True)
    outward = np.column_stack([radial, np.ones(len(p))]) / np.sqrt(2.0)
    assert angle_deg(n, -outward).max() < NORMAL_TOL_DEG
    assert angle_deg(sampled(top)[1], [0.0, 0.0, -1.0]).max() < NORMAL_TOL_DEG


def test_a_sharp_corner_is_a_corner_and_a_cusp_as_for_any_path(tmp_path):
    """A box's top loop (the path: shorthand): four 90° corners between its edges,
    reported with the seam, and the flange path's speed peaks there, as for a CSV."""
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

    write_step(BRepPrimAPI_MakeBox(300, 200, 10).Shape(), tmp_path / "box.step")
    file = cad_cell(tmp_path, "box.step", [])
    text = file.read_text().replace(
        "seams: []", "path:\n  cad:\n    loop: {face_near_mm: [150, 100, 10]}"
    )
    file.write_text(text)
    inputs = load_inputs(file, ROBOTS_DIR)
    corners = inputs.points.exact.corners
    assert sorted(tuple(np.round(p * 1e3, 6)) for p, _ in corners) == [
        (0, 0, 10),
        (0, 200, 10),
        (300, 0, 10),
        (300, 200, 10),
    ]
    assert [turn for _, turn in corners] == pytest.approx([90.0] * 4)
    fit = fit_path(inputs)
    cusps = flange_paths(inputs, fit).cusps
    grid = np.linspace(0.0, fit.path.length, 20001)
    on_path = fit.path(grid, 0)[0]
    s_corners = np.array([grid[np.argmin(np.linalg.norm(on_path - p, axis=1))] for p, _ in corners])
    assert cusps
    for cusp in cusps:  # each flange-speed peak at one of the corners, none elsewhere
        gap = np.abs(s_corners - cusp.sigma_m)
        assert np.minimum(gap, fit.path.length - gap).min() < 0.02  # within 20 mm


def test_offset_moves_the_seam_along_the_normal(parts):
    """offset_mm: along n (into the part); negative lifts the seam off the surface. The
    exact reference moves with it (the fit error is still against the moved edge)."""
    seams = [
        {"cad": {"loop": {"face_near_mm": [150, 100, 10]}, "offset_mm": -1.0}},
        {
            "cad": {
                "chain": {"near_mm": [[100, 0, 0], [100, 0, 0]]},
                "normal": {"face_near_mm": [150, 0, 5]},
                "offset_mm": 2.0,
            }
        },
    ]
    lifted, inside = fitted_seams(parts, "plate.step", seams)
    p, _ = sampled(lifted)
    assert rounded_rectangle(p, PLATE[2] + 1.0)[0].max() < PATH_TOL_MM
    p, _ = sampled(inside)  # the bottom edge at y = 0, moved 2 mm into the side face
    np.testing.assert_allclose(p[:, 1:], [[2.0, 0.0]] * len(p), atol=PATH_TOL_MM)
    for fit in (lifted, inside):
        assert fit.normal_fit.edge_max_error_mm < PATH_TOL_MM


def test_a_cad_seam_is_fitted_exactly_by_default_and_its_tangent_error_reported(parts):
    """Issue 37: a cad: seam's source is exact, so its fit tolerance defaults to
    0.01 mm (not 0.1 mm); the tangent of the fitted path against the exact edge's is
    measured, and it is smaller at the exact default than at 0.1 mm."""
    loop = {"loop": {"face_near_mm": [150, 100, 10]}}
    exact, coarse = fitted_seams(
        parts, "plate.step", [{"cad": loop}, {"cad": loop, "fit_tolerance_mm": 0.1}]
    )
    assert exact.normal_fit.edge_max_error_mm <= 0.0101
    assert coarse.normal_fit.edge_max_error_mm > 0.02
    tangent_exact = exact.normal_fit.edge_tangent_max_error_deg
    tangent_coarse = coarse.normal_fit.edge_tangent_max_error_deg
    assert tangent_exact < 1.5 and tangent_coarse > 1.5 * tangent_exact
