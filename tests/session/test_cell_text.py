"""Save: the changed values written into the original text; comments and layout stay,
the file loads to the session's cell, and no file is ever replaced."""

import shutil

import pytest
from pydrake.common.yaml import yaml_dump_typed

from offline_prog.config.cell import load_cell
from offline_prog.config.cell_text import save_cell
from offline_prog.config.edits import apply, initial_values
from offline_prog.session.state import with_value

from conftest import CELLS

CHANGES = [
    ("X_IT.x", 1020),
    ("X_IT.pitch", 2.5),
    ("X_PE.z", 95),
    ("speed", 80),
    ("clearance", 7),
    ("free_rotation", 30),
    ("turn_smoothing", 12),
]


@pytest.mark.parametrize("name", ["seal_plate_kr16", "seal_job_kr16", "tape_cylinder_ur10e"])
def test_save_keeps_comments_and_loads_to_the_same_cell(tmp_path, name):
    shutil.copytree(CELLS / "data", tmp_path / "data")
    original = tmp_path / f"{name}.yaml"
    shutil.copyfile(CELLS / f"{name}.yaml", original)
    cell = load_cell(original)
    initial = state = initial_values(cell)
    for key, value in CHANGES:
        state = with_value(state, key, value)
    saved = save_cell(original, initial, state, apply(cell, initial, state))
    assert saved == tmp_path / f"{name}-1.yaml"
    assert yaml_dump_typed(load_cell(saved)) == yaml_dump_typed(apply(cell, initial, state))
    before, after = original.read_text().splitlines(), saved.read_text().splitlines()
    comments = [line for line in before if line.lstrip().startswith("#")]
    assert comments and all(line in after for line in comments)
    changed = [line for line in before if line not in after]
    assert len(changed) <= 5, changed  # X_IT, X_PE, speed (, the tool's turn) lines only
    # A second save never replaces the first.
    faster = with_value(state, "speed", 90)
    again = save_cell(original, initial, faster, apply(cell, initial, faster))
    assert again == tmp_path / f"{name}-2.yaml" and saved.read_text() == "\n".join(after) + "\n"
