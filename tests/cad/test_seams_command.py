"""``offline-prog seams PART``: faces, loops and chains numbered by position, each with
the cell-file keys that pick it (and they do), and a 3D page with the numbers."""

import numpy as np
import pytest
from cad_parts import PLATE, PLATE_R, cad_cell, filleted_plate, write_step, write_stl

from offline_prog.cad.catalog import step_catalog
from offline_prog.cad.step_model import read_step
from offline_prog.cad.step_seams import pick_edge, pick_face
from offline_prog.cli import main
from offline_prog.errors import InputError
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


def test_a_mesh_in_mm_read_as_metres_is_refused_as_plan_refuses_it(plate, capsys, tmp_path):
    """One size rule for ``seams`` and ``plan`` (config.unit_slips): the plate's STL in mm
    without --mesh-units is a 300 m part; ``seams`` listed it (its face_near_mm keys
    1000× too large) where ``plan`` refused it. Both now refuse, with the unit hint."""
    stl = plate.with_suffix(".stl")
    code = main(["seams", str(stl), "--out", str(tmp_path / "mesh.html")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "300 m across, more than a cell's 20 m" in err[0]
    assert err[0].endswith("(the file looks like mm: give --mesh-units mm)")
    assert not (tmp_path / "mesh.html").exists()
    file = cad_cell(tmp_path, str(stl), [{"cad": {"loop": {"face_near_mm": [150, 100, 10]}}}])
    code = main(["plan", str(file), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "300 m across, more than a cell's 20 m" in err[0] and "mesh_units: mm" in err[0]


def test_the_seams_of_a_mesh_model_in_mm_name_the_units_key(plate, tmp_path):
    """The seam's own reading of the model (before the scene) says it as well."""
    stl = plate.with_suffix(".stl")
    file = cad_cell(tmp_path, str(stl), [{"cad": {"loop": {"face_near_mm": [150, 100, 10]}}}])
    with pytest.raises(InputError) as error:
        seam_inputs(load_inputs(file, ROBOTS_DIR), 0)
    assert error.value.key == "part.model"
    assert error.value.reason.endswith("(the file looks like mm: set part.mesh_units: mm)")


def test_the_page_goes_to_out_by_default_and_never_over_an_input(
    plate, capsys, tmp_path, monkeypatch
):
    """Default: out/<part stem>_seams.html under the current folder, not beside the model
    (it landed in cells/data/); an --out that is the model, a folder or a file the
    command did not write is refused, nothing written; its own page is replaced."""
    monkeypatch.chdir(tmp_path)
    before = plate.read_bytes()
    assert main(["seams", str(plate)]) == 0
    page = tmp_path / "out" / "plate_seams.html"
    assert page.is_file() and not plate.with_name("plate_seams.html").exists()
    assert main(["seams", str(plate)]) == 0  # its own page: replaced
    (tmp_path / "notes.html").write_text("my notes", encoding="utf-8")
    for out, reason in (
        (plate, "--out: is the part model itself (an input)"),
        (tmp_path / "notes.html", "--out: exists and is not a page offline-prog seams wrote"),
        (tmp_path / "out", "--out: is a folder"),
        (tmp_path / "page.step", "--out: the page is HTML"),
    ):
        capsys.readouterr()
        assert main(["seams", str(plate), "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and reason in err[0], err
    assert plate.read_bytes() == before
    assert (tmp_path / "notes.html").read_text(encoding="utf-8") == "my notes"
    assert not (tmp_path / "page.step").exists()
