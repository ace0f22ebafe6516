"""``offline-prog seams PART``: faces, loops and chains numbered by position, each with
the cell-file keys that pick it (and they do), and a 3D page with the numbers."""

import numpy as np
import pytest
from cad_parts import PLATE, PLATE_R, cad_cell, filleted_plate, write_step, write_stl

from offline_prog.cad.catalog import step_catalog
from offline_prog.cad.step_model import read_step
from offline_prog.cad.step_seams import pick_edge, pick_face
from offline_prog.cli import main
from offline_prog.job.seams import seam_inputs
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import load_inputs

from browser import WEBGL_ARGS, keep_artifact, require_chromium, screenshot
from conftest import CELLS


@pytest.fixture(scope="module")
def plate(tmp_path_factory):
    folder = tmp_path_factory.mktemp("plate")
    shape = filleted_plate()
    write_stl(shape, folder / "plate.stl", 0.05)
    return write_step(shape, folder / "plate.step")


def test_every_listed_point_picks_its_own_face_and_chain(plate):
    catalog, model = step_catalog(plate), read_step(plate)
    faces = [e for e in catalog.entries if e.kind == "face"]
    assert len(faces) == len(model.faces) == 10
    for entry in faces:
        assert pick_face(model, entry.keys["face_near_mm"], "k") == entry.number
    keys = [tuple(np.round(c, 3)) for c in model.face_centroids]
    assert keys == sorted(keys)  # numbered by position
    chains = [e for e in catalog.entries if e.kind == "chain"]
    outline = [c for c in chains if len(c.keys["chain"]["near_mm"]) == 8]
    assert len(outline) == 2  # top and bottom rounded outlines: 8 edges joined G1 each
    perimeter = 2 * (PLATE[0] + PLATE[1] - 4 * PLATE_R) + 2 * np.pi * PLATE_R
    assert [c.size for c in outline] == pytest.approx([perimeter] * 2, rel=1e-9)
    for chain in chains:
        picked = [pick_edge(model, p, "k") for p in chain.keys["chain"]["near_mm"]]
        assert picked[0] == int(chain.description.split()[1].rstrip(","))


def test_a_listed_loop_plans_as_listed(plate, capsys, tmp_path):
    page = tmp_path / "seams.html"
    assert main(["seams", str(plate), "--out", str(page)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert page.is_file() and any(str(page) in line for line in lines)
    top = next(e for e in step_catalog(plate).entries if e.kind == "loop" and e.size > 900)
    assert any(line.split()[1] == f"L{top.number}" for line in lines)
    file = cad_cell(plate.parent, "plate.step", [{"cad": top.keys}])
    points = seam_inputs(load_inputs(file, ROBOTS_DIR), 0).points
    assert points.exact.length_m * 1e3 == pytest.approx(top.size, rel=1e-9)


def test_a_mesh_lists_its_regions_and_feature_runs(plate, capsys, tmp_path):
    code = main(
        [
            "seams",
            str(plate.with_suffix(".stl")),
            "--mesh-units",
            "mm",
            "--out",
            str(tmp_path / "mesh.html"),
        ]
    )
    lines = capsys.readouterr().out.splitlines()
    assert code == 0
    # top, bottom, 4 sides and 4 fillets form 2 + 1 regions (sides and fillets join
    # without a crease); the top and bottom outlines are the feature runs
    assert sum(line.split()[0] == "face" for line in lines[:-1]) == 3
    assert sum(line.split()[0] == "chain" for line in lines[:-1]) == 2


def test_not_a_model_is_one_line(capsys, tmp_path):
    (tmp_path / "part.step").write_text("nonsense")
    assert main(["seams", str(tmp_path / "part.step")]) == 2
    assert capsys.readouterr().err.count("\n") == 1


@pytest.mark.slow
def test_the_seams_page_shows_the_numbered_model(tmp_path, capsys):
    require_chromium()
    page = tmp_path / "seams.html"
    assert main(["seams", str(CELLS / "data" / "seal_plate.step"), "--out", str(page)]) == 0
    png = screenshot(page, tmp_path / "seams.png", size=(1200, 800), extra=WEBGL_ARGS)
    keep_artifact(png, "seams_seal_plate.png")
    from PIL import Image

    image = np.asarray(Image.open(png).convert("RGB")).astype(float)
    assert image.std() > 20, "the 3D view is blank"
    grey = image.mean(axis=2)
    model = (np.abs(image - [190, 190, 199]).max(axis=2) < 25).mean()
    assert model > 0.05, "the part is not in view"
    text = (grey < 40).mean()  # black label glyphs
    assert text > 0.001, "no numbers drawn"
