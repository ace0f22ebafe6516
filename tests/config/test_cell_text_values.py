"""with_values (placement's placed.yaml): poses, text and numbers written into the cell
file's text in place, a missing top-level text key added; the text loads as the cell
with those values and keeps its comments."""

import pytest

from offline_prog.config.cell import load_cell
from offline_prog.config.cell_text import with_values

from conftest import CELLS

DEMO = CELLS / "placement" / "seal_out_of_reach_kr16.yaml"


def test_numbers_text_and_poses_are_written_in_place(tmp_path):
    text = DEMO.read_text()
    out = with_values(
        text,
        {"obstacles.1.pose": ((1.0, 0.2, 0.3), (0.0, 0.0, 15.0))},
        {"description": "Placed: the tool at 1 m."},
        {"obstacles.1.size_mm.2": 612.5},
    )
    file = tmp_path / "placed.yaml"
    file.write_text(out)
    cell = load_cell(file)
    stand = cell.obstacles[1]
    assert stand.name == "nozzle_stand" and stand.size_mm == [200.0, 200.0, 612.5]
    assert list(stand.pose.translation) == [1.0, 0.2, 0.3]
    assert cell.description == "Placed: the tool at 1 m."
    assert "# Deliberately poor: 2.2 m from the robot base" in out  # comments kept


def test_a_missing_description_is_added_and_a_missing_number_refused(tmp_path):
    text = "\n".join(
        line for line in DEMO.read_text().splitlines() if not line.startswith("description:")
    )
    out = with_values(text, {}, {"description": "what was placed"})
    file = tmp_path / "placed.yaml"
    file.write_text(out)
    assert load_cell(file).description == "what was placed"
    with pytest.raises(ValueError, match="obstacles.9.length_mm not found"):
        with_values(text, {}, {}, {"obstacles.9.length_mm": 1.0})
