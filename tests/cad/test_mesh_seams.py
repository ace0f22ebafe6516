"""Seams from a mesh export of the same STEP parts: the same seam as from the STEP
model, within the tessellation's chord error the mesh seam reports."""

import numpy as np
import pytest
import trimesh
from cad_parts import (
    PLATE,
    angle_deg,
    bracket_profile,
    cad_cell,
    filleted_plate,
    l_bracket,
    rounded_rectangle,
    sampled,
    write_step,
    write_stl,
)

from offline_prog.errors import InputError
from offline_prog.job.seams import seam_inputs
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import fit_path, load_inputs

TESSELLATION_MM = 0.01  # the STL's chord tolerance
FIT_MM = 0.02  # the mesh seams' fit tolerance (the polyline's kinks are rounded)
NORMAL_DEG = 6.0  # region normals of a tessellated fillet: within its angular step


@pytest.fixture(scope="module")
def parts(tmp_path_factory):
    folder = tmp_path_factory.mktemp("meshes")
    for name, build in (("plate", filleted_plate), ("bracket", l_bracket)):
        shape = build()
        write_step(shape, folder / f"{name}.step")
        write_stl(shape, folder / f"{name}.stl", TESSELLATION_MM)
    return folder


def fitted(folder, model, seam):
    seam = {**seam, "fit_tolerance_mm": FIT_MM, "normal_tolerance_deg": 2.0}
    file = cad_cell(folder, model, [seam], mesh_units="mm")
    inputs = seam_inputs(load_inputs(file, ROBOTS_DIR), 0)
    return inputs.points.exact, fit_path(inputs)


@pytest.mark.slow  # a 0.01 mm tessellation's seam fit (CI runs the slow tests too)
def test_plate_top_loop_from_the_mesh_is_the_step_loop(parts):
    seam = {"cad": {"loop": {"face_near_mm": [150, 100, 10]}}}
    (exact, mesh), (_, step) = fitted(parts, "plate.stl", seam), fitted(parts, "plate.step", seam)
    chord_mm = exact.tolerance_m * 1e3  # the tessellation's chord error, as reported
    assert 0.0 < chord_mm <= TESSELLATION_MM
    ref = exact.reference_P * 1e3
    middles = (ref + np.roll(ref, -1, axis=0)) / 2  # the chords' middles: their worst
    assert rounded_rectangle(middles, PLATE[2])[0].max() <= chord_mm * 1.05
    tolerance = chord_mm + mesh.normal_fit.edge_max_error_mm
    p, n = sampled(mesh)
    assert rounded_rectangle(p, PLATE[2])[0].max() < tolerance
    assert angle_deg(n, [0.0, 0.0, -1.0]).max() < 0.01
    assert mesh.path.length == pytest.approx(step.path.length, abs=tolerance * 1e-3 * 2 * np.pi)


def test_bracket_chain_from_the_mesh_runs_between_the_same_corners(parts):
    """A mesh keeps no tangent edge boundaries: the chain is the whole run of feature
    edges between corners, which here is the STEP chain's three edges."""
    seam = {
        "cad": {
            "chain": {"near_mm": [[60, 0, 10], [10, 0, 60]]},
            "normal": {"face_near_mm": [20 - 7.0711, 30, 20 - 7.0711]},
        }
    }
    (exact, mesh), (_, step) = (
        fitted(parts, "bracket.stl", seam),
        fitted(parts, "bracket.step", seam),
    )
    p, n = sampled(mesh)
    distance, outward = bracket_profile(p)
    assert mesh.normal_fit.edge_max_error_mm <= FIT_MM * 1.01
    assert distance.max() < exact.tolerance_m * 1e3 + mesh.normal_fit.edge_max_error_mm
    assert angle_deg(n, -outward).max() < NORMAL_DEG
    assert mesh.path.length == pytest.approx(step.path.length, rel=1e-4)


def test_a_mesh_without_the_chosen_feature(tmp_path):
    trimesh.creation.icosphere(subdivisions=4, radius=50.0).export(tmp_path / "ball.stl")
    seam = {
        "cad": {
            "chain": {"near_mm": [[50, 0, 0], [0, 50, 0]]},
            "normal": {"face_near_mm": [50, 0, 0]},
        }
    }
    file = cad_cell(tmp_path, "ball.stl", [seam], mesh_units="mm")
    with pytest.raises(InputError) as error:
        seam_inputs(load_inputs(file, ROBOTS_DIR), 0)
    assert error.value.key == "seams[0].cad.chain.near_mm"
    assert "no feature edges" in error.value.reason


def test_a_chain_on_a_closed_run_of_a_mesh_asks_for_closed(parts):
    """The plate's bottom outline is one run of feature edges with no corner (a mesh
    keeps no tangent edge ends): as a chain it is the whole outline, closed."""
    seam = {
        "cad": {
            "chain": {"near_mm": [[100, 0, 0], [300, 100, 0]]},
            "normal": {"face_near_mm": [150, 0, 5]},
        }
    }
    file = cad_cell(parts, "plate.stl", [seam], mesh_units="mm")
    with pytest.raises(InputError) as error:
        seam_inputs(load_inputs(file, ROBOTS_DIR), 0)
    assert error.value.key == "seams[0].closed" and "closed run" in error.value.reason
    exact, fit = fitted(parts, "plate.stl", {**seam, "closed": True})
    perimeter = 2 * (PLATE[0] + PLATE[1] - 4 * 20.0) + 2 * np.pi * 20.0
    assert exact.closed and fit.path.length * 1e3 == pytest.approx(perimeter, rel=1e-4)
    p, _ = sampled(fit)
    assert rounded_rectangle(p, 0.0)[0].max() < exact.tolerance_m * 1e3 + FIT_MM


def _turn_about(p: np.ndarray, n: np.ndarray) -> float:
    """The sign of a closed polyline's (N, 3) turning about the direction n: +1
    counter-clockwise seen from where n points (right-hand rule), -1 clockwise."""
    centre = p.mean(axis=0)
    area = np.cross(p - centre, np.roll(p, -1, axis=0) - centre).sum(axis=0)
    return float(np.sign(area @ n))


def test_a_loop_runs_the_same_way_on_the_step_model_and_its_mesh(parts):
    """One direction rule for both model kinds: a loop runs with its face on its left
    seen from outside the part (counter-clockwise about the face's outward normal, as a
    STEP face's outer wire runs). The mesh's loops ran the other way."""
    from offline_prog.cad import mesh_seams, step_seams
    from offline_prog.cad.mesh_model import read_mesh
    from offline_prog.cad.step_model import read_step

    step, mesh = read_step(parts / "plate.step"), read_mesh(parts / "plate.stl", 1.0)
    for point, outward in (([150, 100, 10], [0, 0, 1]), ([150, 100, 0], [0, 0, -1])):
        for model, seams in ((step, step_seams), (mesh, mesh_seams)):
            loop = seams.loop_seam(model, point, None, offset_mm=0.0, key="k")
            assert _turn_about(loop.p, np.array(outward, float)) == 1.0, (seams, point)
