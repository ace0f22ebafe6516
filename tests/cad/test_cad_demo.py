"""The CAD demo cell (cells/cad_seal_kr16.yaml): its part's seams, collision and visual
geometry all come from one STEP file; it plans, exports and previews."""

import json
import subprocess
import sys

import numpy as np
import pytest
from gripper_clearance import GRIPPER_CLEARANCE_TOL_M, gripper_clearance

from offline_prog.config.cell import load_cell
from offline_prog.job.seams import seam_inputs
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.scene.shapes import cell_geometry
from offline_prog.stages import load_inputs

from conftest import CELLS, REPO

CELL = CELLS / "cad_seal_kr16.yaml"
# The demo plate (scripts/make_cad_demo.py): 400 x 300 mm, corners R30, chamfer 3 mm.
RIM_MM = 2 * (400 - 6 + 300 - 6 - 4 * 27) + 2 * np.pi * 27
BEAD_MM = 400 - 60 + np.pi * 30


def test_the_seams_are_the_model_edges():
    inputs = load_inputs(CELL, ROBOTS_DIR)
    rim, bead = (seam_inputs(inputs, k).points for k in range(2))
    assert rim.closed and not bead.closed
    assert rim.exact.length_m * 1e3 == pytest.approx(RIM_MM, rel=1e-9)
    assert bead.exact.length_m * 1e3 == pytest.approx(BEAD_MM, rel=1e-9)
    np.testing.assert_allclose(rim.normals_P, [[0, 0, 1]] * len(rim.normals_P), atol=1e-12)
    # the chamfer's normal, into the part: up and inwards at 45° on the straight part
    middle = np.abs(bead.p_PR[:, 0]) < 0.1
    np.testing.assert_allclose(
        bead.normals_P[middle], [[0, 2**-0.5, 2**-0.5]] * middle.sum(), atol=1e-9
    )
    assert rim.exact.corners == () and bead.exact.corners == ()  # one G1 seam each


def test_the_part_geometry_is_the_tessellated_model():
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    from offline_prog.cad.step_model import read_step

    (plate,) = cell_geometry(load_cell(CELL), CELL).part
    assert plate.name == "plate" and plate.kind == "mesh" and plate.mesh.is_watertight
    assert plate.pieces  # convex pieces for Drake, as for any mesh
    np.testing.assert_allclose(plate.mesh.extents, [0.4, 0.3, 0.008], atol=1e-7)
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(read_step(CELLS / "data" / "seal_plate.step").shape, props)
    assert plate.mesh.volume == pytest.approx(props.Mass() * 1e-9, rel=1e-3)


@pytest.mark.slow
def test_the_demo_plans_exports_and_previews(tmp_path):
    out = tmp_path / "plan"
    done = subprocess.run(
        [sys.executable, "-m", "offline_prog", "plan", str(CELL), "--out", str(out)],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=900,
    )
    assert done.returncode == 0, done.stderr
    report = json.loads((out / "report.json").read_text())
    assert report["feasible"]
    for seam, length in zip(report["seams"], (RIM_MM, BEAD_MM), strict=True):
        assert seam["fit"]["normal_source"] == "cad"
        assert seam["fit"]["edge_max_error_mm"] <= seam["fit"]["tolerance_mm"] * 1.01
        assert seam["path"]["length_m"] * 1e3 == pytest.approx(length, abs=0.1)
        assert seam["path"]["cad"]["length_m"] * 1e3 == pytest.approx(length, rel=1e-9)
        assert seam["path"]["cad"]["corners"] == []
    assert (out / "preview.html").stat().st_size > 100_000  # the scene, robot and part
    # The gripper keeps the clearance on every row (python-fcl, tests/gripper_clearance.py).
    distance, pair, row = gripper_clearance(CELL, out / "trajectory.csv")
    assert distance >= load_cell(CELL).motion.clearance - GRIPPER_CLEARANCE_TOL_M, (pair, row)
    exported = subprocess.run(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "export",
            str(out),
            "--format",
            "csv",
            "--out",
            str(tmp_path / "csv"),
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=300,
    )
    assert exported.returncode == 0, exported.stderr
    assert (tmp_path / "csv" / "joint_trajectory.csv").is_file()


def test_a_placement_worker_gets_the_model():
    """``offline-prog place`` sends the cell and its data files to its workers: the
    STEP model must be among them, re-pointed in the cell text."""
    from offline_prog.placement.payload import cell_payload, unpack

    payload = cell_payload(CELL, load_cell(CELL))
    assert any(name.endswith("seal_plate.step") for name, _ in payload.files)
    inputs = load_inputs(unpack(payload), ROBOTS_DIR)
    assert seam_inputs(inputs, 0).points.exact.length_m * 1e3 == pytest.approx(RIM_MM)
