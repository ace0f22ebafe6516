"""The payload record: each body's mass properties from its keys, else its shapes (checked
against trimesh's integrals over meshes of the same shapes), and the load as one body."""

from pathlib import Path

import numpy as np
import pytest
import trimesh
from config.test_cell_errors import BASE, write_cell  # tests/config
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.tree import RotationalInertia, SpatialInertia

from offline_prog.config.cell import load_cell
from offline_prog.config.checks import check_cell
from offline_prog.export.payload import payload
from offline_prog.results.report import payload_summary
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.scene.payload import (
    MassProperties,
    combined,
    inertia_matrix,
    mass_properties,
    payload_record,
    shapes_mass_properties,
)
from offline_prog.scene.shapes import CellShape

from conftest import CELLS, random_transform

REL_TOL = 2e-3  # trimesh integrates polygons: 256-gon cylinders, subdivided spheres
DEMOS = sorted(CELLS.glob("*.yaml")) + sorted((CELLS / "placement").glob("*.yaml"))


def _trimesh_of(shape: CellShape) -> trimesh.Trimesh:
    """The same shape as a closed triangle mesh, posed in its owner's frame."""
    pose = shape.X_OG.GetAsMatrix4()
    if shape.kind == "box":
        return trimesh.creation.box(extents=shape.size_m, transform=pose)
    if shape.kind == "sphere":
        return trimesh.creation.icosphere(5, radius=shape.size_m[0]).apply_transform(pose)
    radius, length = shape.size_m
    return trimesh.creation.cylinder(radius, length, sections=256, transform=pose)


def _random_shapes(rng) -> list[CellShape]:
    shapes = []
    for i in range(rng.integers(1, 5)):
        kind = rng.choice(["box", "sphere", "cylinder"])
        size = {"box": 3, "sphere": 1, "cylinder": 2}[kind]
        shapes.append(
            CellShape(
                f"s{i}", kind, random_transform(rng, 0.2), tuple(rng.uniform(0.01, 0.2, size))
            )
        )
    return shapes


def test_shapes_give_trimesh_mass_properties(rng):
    """Volume, centre of volume and inertia about it (unit density) of posed boxes,
    spheres and cylinders equal trimesh's over their meshes (overlaps count twice in
    both: trimesh integrates each closed surface)."""
    for _ in range(30):
        shapes = _random_shapes(rng)
        volume, p_OC, I_C = shapes_mass_properties(shapes)
        mesh = trimesh.util.concatenate([_trimesh_of(s) for s in shapes])
        assert volume == pytest.approx(mesh.volume, rel=REL_TOL)
        scale = max(mesh.extents)
        np.testing.assert_allclose(p_OC, mesh.center_mass, atol=REL_TOL * scale)
        inertia = mesh.moment_inertia  # about the centre of mass, density 1
        np.testing.assert_allclose(I_C, inertia, atol=REL_TOL * np.abs(inertia).max())


def _mesh_shape(mesh: trimesh.Trimesh, file: Path, X_OG=None) -> CellShape:
    """A mesh CellShape as shapes.mesh_shape makes it, without its convex pieces (the
    payload reads the mesh and its OBJ only; CoACD would take minutes here)."""
    mesh.export(file)
    return CellShape(file.stem, "mesh", X_OG or RigidTransform(), (), mesh, (), file)


def test_a_mesh_counts_as_its_volume_or_else_its_hull(tmp_path):
    """A closed mesh (two boxes apart) by its own volume; an open one (a face of a box
    removed) as its convex hull: the closed box."""
    upright = trimesh.creation.box(
        [0.1, 0.1, 0.3], transform=RigidTransform([0.1, 0, 0.25]).GetAsMatrix4()
    )
    two = trimesh.util.concatenate([trimesh.creation.box([0.3, 0.1, 0.1]), upright])
    shape = _mesh_shape(two, tmp_path / "two.obj", RigidTransform([0.1, 0.0, 0.0]))
    volume, p_OC, I_C = shapes_mass_properties([shape])
    assert volume == pytest.approx(two.volume, rel=1e-9)
    np.testing.assert_allclose(p_OC, two.center_mass + [0.1, 0, 0], atol=1e-9)
    np.testing.assert_allclose(I_C, two.moment_inertia, rtol=1e-9, atol=1e-15)
    box = trimesh.creation.box([0.2, 0.1, 0.05])
    open_box = trimesh.Trimesh(box.vertices, box.faces[2:])  # one face (two triangles) less
    assert not open_box.is_watertight
    volume, _, I_C = shapes_mass_properties([_mesh_shape(open_box, tmp_path / "open.obj")])
    assert volume == pytest.approx(box.volume, rel=1e-9)
    np.testing.assert_allclose(I_C, box.moment_inertia, rtol=1e-9, atol=1e-15)


def test_keys_win_over_shapes_and_point_mass_without_either(tmp_path):
    gripper = (
        "gripper:\n  mass_kg: 4\n  geometry:\n    - {name: g_body, shape: box, "
        "size_mm: [100, 80, 60], pose: {translation: [0, 0, 0.03]}}\n"
    )
    cell = load_cell(write_cell(tmp_path, BASE.replace("part:\n", gripper + "part:\n")))
    record = payload_record(cell, tmp_path / "cell.yaml")
    assert record["gripper_com_from"] == record["gripper_inertia_from"] == "shapes"
    np.testing.assert_allclose(record["gripper_com_E_m"], [0, 0, 0.03], atol=1e-12)
    box = SpatialInertia.SolidBoxWithMass(4.0, 0.1, 0.08, 0.06).CalcRotationalInertia()
    np.testing.assert_allclose(
        record["gripper_inertia_E_kgm2"], box.CopyToFullMatrix3(), atol=1e-12
    )
    assert "part_mass_kg" not in record and "total" not in record  # no part mass
    given = gripper.replace(
        "  geometry:",
        "  center_of_mass_mm: [0, 5, 70]\n"
        "  inertia_kgm2: [0.02, 0.03, 0.04, 0.001, 0, 0]\n  geometry:",
    )
    text = BASE.replace("part:\n", given + "part:\n  mass_kg: 1.5\n")
    cell = load_cell(write_cell(tmp_path, text))
    record = payload_record(cell, tmp_path / "cell.yaml")
    assert (record["gripper_com_from"], record["gripper_inertia_from"]) == (
        "gripper.center_of_mass_mm",
        "gripper.inertia_kgm2",
    )
    np.testing.assert_allclose(record["gripper_com_E_m"], [0, 0.005, 0.07])
    np.testing.assert_allclose(
        record["gripper_inertia_E_kgm2"], [[0.02, 0.001, 0], [0.001, 0.03, 0], [0, 0, 0.04]]
    )
    # The part of BASE has no shapes: a point mass at P's origin.
    assert (record["part_com_from"], record["part_inertia_from"]) == ("frame origin", "point mass")
    assert record["part_inertia_P_kgm2"] == np.zeros((3, 3)).tolist()
    assert record["total"]["mass_kg"] == pytest.approx(5.5)


def test_the_load_as_one_body_is_drakes_sum(rng):
    """Gripper (in E) and part (in P at X_EP) as one body: centre of mass and inertia
    about it equal Drake's spatial inertias summed about E's origin, and the principal
    moments and axes rebuild the inertia."""
    for _ in range(20):
        bodies = []
        for _ in range(2):
            moments = rng.uniform(0.01, 0.1, 3)
            moments[2] = rng.uniform(abs(moments[0] - moments[1]), moments[0] + moments[1])
            R = RollPitchYaw(rng.uniform(-np.pi, np.pi, 3)).ToRotationMatrix().matrix()
            mass = rng.uniform(0.5, 5.0)
            bodies.append(
                MassProperties(mass, rng.uniform(-0.2, 0.2, 3), R @ np.diag(moments) @ R.T, "", "")
            )
        X_EP = random_transform(rng, 0.3)
        total = combined(*bodies, X_EP)
        M_EEo_E = SpatialInertia.Zero()
        for body, X in zip(bodies, (RigidTransform(), X_EP), strict=True):
            central = SpatialInertia.MakeFromCentralInertia(
                body.mass_kg, body.p_OC, RotationalInertia(*_six(body.I_C))
            )  # about O's origin, axes of O
            M_EEo_E += central.ReExpress(X.rotation()).Shift(-X.translation())
        p_EC = M_EEo_E.get_com()
        I_C = M_EEo_E.Shift(p_EC).CalcRotationalInertia().CopyToFullMatrix3()
        assert total["mass_kg"] == pytest.approx(M_EEo_E.get_mass())
        np.testing.assert_allclose(total["com_E_m"], p_EC, atol=1e-11)
        np.testing.assert_allclose(total["inertia_E_kgm2"], I_C, atol=1e-11)
        R_EA, moments = np.array(total["R_E_principal"]), np.array(total["principal_inertia_kgm2"])
        assert np.linalg.det(R_EA) == pytest.approx(1.0)
        np.testing.assert_allclose(R_EA @ np.diag(moments) @ R_EA.T, I_C, atol=1e-11)


def _six(inertia: np.ndarray) -> list[float]:
    """[Ixx, Iyy, Izz, Ixy, Ixz, Iyz] of a (3, 3) inertia (the cell key's order)."""
    six = [inertia[(i, j)] for i, j in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))]
    np.testing.assert_allclose(inertia_matrix(six), (inertia + inertia.T) / 2, atol=1e-15)
    return six


@pytest.mark.parametrize("file", DEMOS, ids=lambda p: p.stem)
def test_every_demo_gives_its_payload(file: Path):
    """The demo cells give both masses and gripper shapes: the programs set the load and
    a first run prints no payload warning."""
    cell = load_cell(file)
    check_cell(file, cell, ROBOTS_DIR)
    summary = payload_summary(cell, file)
    assert summary["set"] and summary["warning"] is None
    assert payload(summary) is not None and cell.gripper.geometry
    assert summary["gripper_inertia_from"] == summary["part_inertia_from"] == "shapes"
    total = summary["total"]
    assert total["mass_kg"] == pytest.approx(summary["gripper_mass_kg"] + summary["part_mass_kg"])
    assert 0 < total["com_E_m"][2] < 0.3  # in front of the flange, between it and the part


def test_mass_properties_point_mass():
    body = mass_properties(2.0, com_mm=None, inertia_kgm2=None, shapes=[], key="gripper")
    assert (body.com_from, body.inertia_from) == ("frame origin", "point mass")
    assert not body.p_OC.any() and not body.I_C.any()
