"""Several seams from one file: a CSV's ``seam`` column (a seam entry takes the rows
named like it) and a DXF's entities (``dxf_layer`` / ``dxf_entity``)."""

import numpy as np
import pytest

from offline_prog.config.cell import load_cell
from offline_prog.errors import InputError
from offline_prog.job.seams import seam_inputs
from offline_prog.path.sources import read_csv_points, read_dxf_points
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import load_inputs

from conftest import CELLS


def two_seam_csv(tmp_path):
    phi = np.linspace(0, np.pi, 40)
    rows = ["x,y,z,seam"]
    rows += [f"{-100 + 30 * np.cos(a)},{30 * np.sin(a)},0,left" for a in phi]
    rows += [f"{100 + 30 * np.cos(a)},{30 * np.sin(a)},0,right" for a in phi]
    file = tmp_path / "seams.csv"
    file.write_text("\n".join(rows) + "\n")
    return file


def test_csv_seam_column_picks_rows_and_keeps_row_numbers(tmp_path):
    file = two_seam_csv(tmp_path)
    right = read_csv_points(file, units="mm", closed=False, seam="right")
    assert len(right.p_PR) == 40
    assert np.all(right.p_PR[:, 0] > 0.06)
    np.testing.assert_array_equal(right.rows, np.arange(40, 80))  # data rows in the file
    with pytest.raises(ValueError, match="holds seams left, right"):
        read_csv_points(file, units="mm", closed=False)
    with pytest.raises(ValueError, match="no seam 'middle'"):
        read_csv_points(file, units="mm", closed=False, seam="middle")


def test_seam_entries_take_their_rows_by_name(tmp_path):
    two_seam_csv(tmp_path)
    text = (CELLS / "seal_job_kr16.yaml").read_text()
    head = text[: text.index("\nseams:") + 1]
    tail = text[text.index("\njob:") + 1 :]
    seams = (
        "seams:\n"
        "  - {name: left, points: seams.csv, units: mm, normal: [0, 0, 1]}\n"
        "  - {name: right, points: seams.csv, units: mm, normal: [0, 0, 1]}\n"
    )
    cell = tmp_path / "job.yaml"
    cell.write_text(head + seams + tail)
    inputs = load_inputs(cell, ROBOTS_DIR)
    left, right = (seam_inputs(inputs, k).points.p_PR for k in (0, 1))
    assert np.all(left[:, 0] < -0.06) and np.all(right[:, 0] > 0.06)
    # Reversed: the same points the other way.
    np.testing.assert_allclose(seam_inputs(inputs, 1, reverse=True).points.p_PR, right[::-1])


def test_dxf_entities_by_index_and_layer(tmp_path):
    ezdxf = pytest.importorskip("ezdxf")
    document = ezdxf.new()
    space = document.modelspace()
    space.add_circle((-100, 0), 30, dxfattribs={"layer": "holes"})
    space.add_circle((100, 0), 20, dxfattribs={"layer": "holes"})
    space.add_line((-120, 80), (120, 80), dxfattribs={"layer": "stripe"})
    file = tmp_path / "part.dxf"
    document.saveas(file)
    second = read_dxf_points(file, layer="holes", closed=True, units="mm", entity=1)
    center = second.p_PR.mean(axis=0)
    assert center[0] == pytest.approx(0.1, abs=1e-4)
    radius = np.linalg.norm(second.p_PR - center, axis=1)
    assert radius == pytest.approx(np.full(len(radius), 0.02), abs=1e-4)
    stripe = read_dxf_points(file, layer="stripe", closed=False, units="mm")
    assert stripe.p_PR[0] == pytest.approx([-0.12, 0.08, 0.0])
    with pytest.raises(ValueError, match="found 2"):
        read_dxf_points(file, layer="holes", closed=True, units="mm")
    with pytest.raises(ValueError, match="no entity 2"):
        read_dxf_points(file, layer="holes", closed=True, units="mm", entity=2)


def test_a_seam_source_error_names_the_seam(tmp_path):
    two_seam_csv(tmp_path)
    text = (CELLS / "seal_job_kr16.yaml").read_text()
    head, tail = text[: text.index("\nseams:") + 1], text[text.index("\njob:") + 1 :]
    seams = "seams:\n  - {name: middle, points: seams.csv, units: mm, normal: [0, 0, 1]}\n"
    cell = tmp_path / "job.yaml"
    cell.write_text(head + seams + tail)
    with pytest.raises(InputError, match=r"seams\[0\]\.points: .*no seam 'middle'"):
        seam_inputs(load_inputs(cell, ROBOTS_DIR), 0)
    assert load_cell(cell).seams[0].csv_seam is None
