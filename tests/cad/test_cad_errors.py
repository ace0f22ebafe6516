"""Bad CAD input ends with one line naming the file, the key and the reason (exit 2);
a cell without CAD keys never imports Open CASCADE."""

import shutil
import subprocess
import sys

import pytest
from cad_parts import cad_cell, filleted_plate, write_step, write_stl

from offline_prog.cli import main
from offline_prog.config.cell import load_cell
from offline_prog.errors import InputError
from offline_prog.job.seams import seam_inputs
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import load_inputs

from conftest import CELLS, REPO

LOOP = {"cad": {"loop": {"face_near_mm": [150, 100, 10]}}}


@pytest.fixture(scope="module")
def plate(tmp_path_factory):
    folder = tmp_path_factory.mktemp("plate")
    shape = filleted_plate()
    write_step(shape, folder / "plate.step")
    write_stl(shape, folder / "plate.stl", 0.05)
    return folder


def seam_error(folder, model, seam) -> InputError:
    file = cad_cell(folder, model, [seam])
    with pytest.raises(InputError) as error:
        seam_inputs(load_inputs(file, ROBOTS_DIR), 0)
    assert "\n" not in str(error.value)
    return error.value


def test_a_file_that_is_not_step(tmp_path):
    (tmp_path / "part.step").write_text("ISO-10303-21;\nnot really\n")
    error = seam_error(tmp_path, "part.step", LOOP)
    assert error.key == "part.model" and "not a readable STEP file" in error.reason


def test_a_step_that_is_not_a_solid(tmp_path):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.gp import gp_Pln

    write_step(BRepBuilderAPI_MakeFace(gp_Pln(), 0, 100, 0, 50).Shape(), tmp_path / "sheet.step")
    error = seam_error(tmp_path, "sheet.step", LOOP)
    assert error.key == "part.model" and "not a solid" in error.reason


def test_a_point_on_the_edge_between_two_faces_is_ambiguous(plate):
    seam = {"cad": {"loop": {"face_near_mm": [150, 0, 10]}}}
    error = seam_error(plate, "plate.step", seam)
    assert error.key == "seams[0].cad.loop.face_near_mm"
    assert "[150, 0, 10] is ambiguous" in error.reason and "face" in error.reason


def test_a_point_far_from_the_model(plate):
    seam = {"cad": {"loop": {"face_near_mm": [150, 100, 30]}}}
    error = seam_error(plate, "plate.step", seam)
    assert error.key == "seams[0].cad.loop.face_near_mm"
    assert "20.00 mm from the nearest face, more than 5 mm" in error.reason


def test_a_chain_whose_edges_do_not_connect(tmp_path):
    from OCP.BRep import BRep_Builder
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.gp import gp_Pnt
    from OCP.TopoDS import TopoDS_Compound

    compound, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(compound)
    builder.Add(compound, BRepPrimAPI_MakeBox(100, 100, 10).Shape())
    builder.Add(compound, BRepPrimAPI_MakeBox(gp_Pnt(200, 0, 0), 100, 100, 10).Shape())
    write_step(compound, tmp_path / "two.step")
    seam = {
        "cad": {
            "chain": {"near_mm": [[50, 0, 10], [250, 0, 10]]},
            "normal": {"face_near_mm": [50, 50, 10]},
        }
    }
    error = seam_error(tmp_path, "two.step", seam)
    assert error.key == "seams[0].cad.chain.near_mm"
    assert "do not connect" in error.reason


def test_a_chain_needs_its_normal_face(plate):
    file = cad_cell(plate, "plate.step", [{"cad": {"chain": {"near_mm": [[100, 0, 0]] * 2}}}])
    with pytest.raises(InputError, match=r"seams\[0\]\.cad\.normal\.face_near_mm: missing"):
        load_inputs(file, ROBOTS_DIR)


def test_the_command_line_says_it_in_one_line(plate, capsys, tmp_path):
    file = cad_cell(plate, "plate.step", [{"cad": {"loop": {"face_near_mm": [150, 0, 10]}}}])
    code = main(["plan", str(file), "--out", str(tmp_path / "out")])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1
    assert "seams[0].cad.loop.face_near_mm" in lines[0] and "ambiguous" in lines[0]


@pytest.mark.slow
def test_a_bad_point_in_the_second_process_is_one_line_too(tmp_path, capsys):
    """The demo's second seam, its chain point between two edges: planned on the forked
    second process (two cores), the same exit 2 and line as on one (was exit 3)."""
    text = (CELLS / "cad_seal_kr16.yaml").read_text(encoding="utf-8")
    point = "[-191.21, -141.21, 3], [191.21, -141.21, 3]"
    assert point in text
    (tmp_path / "cell.yaml").write_text(
        text.replace(point, "[0, -148.5, 1.5], [191.21, -141.21, 3]"), encoding="utf-8"
    )
    (tmp_path / "data").mkdir()
    shutil.copy(CELLS / "data" / "seal_plate.step", tmp_path / "data")
    code = main(["plan", str(tmp_path / "cell.yaml"), "--out", str(tmp_path / "out")])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1, lines
    assert "seams[1].cad.chain.near_mm[0]" in lines[0] and "is ambiguous" in lines[0]
    assert not (tmp_path / "out").exists()


def test_a_cell_without_cad_keys_does_not_import_open_cascade():
    """Open CASCADE takes seconds to import: loading, fitting and building the scene of
    an ordinary cell (and the command line's modules) must not pull it in."""
    probe = (
        "import sys\n"
        "import offline_prog.cli\n"
        "from offline_prog.stages import load_inputs, fit_path, build_scene\n"
        "from offline_prog.robot.model import ROBOTS_DIR\n"
        f"inputs = load_inputs(__import__('pathlib').Path({str(CELLS / 'seal_plate_kr16.yaml')!r}),"
        " ROBOTS_DIR)\n"
        "fit_path(inputs); build_scene(inputs)\n"
        "print(sorted(m for m in sys.modules if m == 'OCP' or m.startswith('OCP.')"
        " or m.startswith('offline_prog.cad')))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], cwd=REPO, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def test_closed_false_on_a_loop_is_refused(plate):
    """A loop comes back to its start: ``closed: false`` on it was ignored (the seam
    planned closed); it is refused, naming the key. Left out, a loop is closed."""
    error = seam_error(plate, "plate.step", {**LOOP, "closed": False})
    assert error.key == "seams[0].closed" and "a loop comes back to its start" in error.reason
    file = cad_cell(plate, "plate.step", [LOOP])
    assert load_cell(file).seams[0].closed is True  # as loaded, not only once checked


@pytest.mark.parametrize("model", ["plate.step", "plate.stl"])
def test_an_offset_deeper_than_the_part_is_refused(plate, model):
    """``offset_mm`` moves the seam along n into the part: 12 mm into a 10 mm plate put
    the seam 2 mm past its far side, accepted without a word; refused now, STEP and
    mesh alike. 9.5 mm stays inside."""
    units = {"mesh_units": "mm"} if model.endswith(".stl") else {}
    deep = {"cad": {**LOOP["cad"], "offset_mm": 12.0}}
    file = cad_cell(plate, model, [deep], **units)
    with pytest.raises(InputError) as error:
        seam_inputs(load_inputs(file, ROBOTS_DIR), 0)
    assert error.value.key == "seams[0].cad.offset_mm"
    assert "12 mm into the part is beyond its depth along n: 10.00 mm" in error.value.reason
    inside = {"cad": {**LOOP["cad"], "offset_mm": 9.5}}
    points = seam_inputs(load_inputs(cad_cell(plate, model, [inside], **units), ROBOTS_DIR), 0)
    assert points.points.p_PR[:, 2] == pytest.approx(0.0005, abs=1e-6)  # 0.5 mm above z = 0


def test_a_face_closed_around_itself_offers_no_loop(tmp_path):
    """A cylinder's side (and a cone's) has a seam edge its boundary runs along there and
    back: its "loop" was listed by ``seams`` and then failed to plan (a singularity).
    It is not listed, and picking it is refused with the way to the rim."""
    from cad_parts import CYLINDER, chamfered_cylinder

    from offline_prog.cad.catalog import step_catalog

    step = write_step(chamfered_cylinder(), tmp_path / "cylinder.step")
    catalog = step_catalog(step)
    faces = {e.number: e.description for e in catalog.entries if e.kind == "face"}
    loops = {e.number for e in catalog.entries if e.kind == "loop"}
    sides = {k for k, kind in faces.items() if kind in ("cylinder", "cone")}
    assert len(sides) == 2 and not sides & loops and loops == set(faces) - sides
    radius, height, _ = CYLINDER
    side = {"cad": {"loop": {"face_near_mm": [radius, 0, height / 2]}}}
    error = seam_error(tmp_path, "cylinder.step", side)
    assert error.key == "seams[0].cad.loop.face_near_mm"
    assert "(cylinder) closes around itself" in error.reason and "closed: true" in error.reason
