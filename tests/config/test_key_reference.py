"""The cell key reference is written from the schema: every key with its type, whether
it is required, its default and the schema's comment; a key added to a schema is in it
at once."""

import dataclasses

from offline_prog.config.key_reference import cell_key_reference, cell_key_rows


def test_rows_follow_the_schema():
    rows = {row.key: row for row in cell_key_rows()}
    assert rows["robot.model"].required and "folder name in robots/" in rows["robot.model"].doc
    assert rows["tool.X_IT"].type == "transform" and rows["tool.X_IT"].required
    assert rows["tool.free_rotation_deg"].default == "0.0"
    assert "pressing direction" in rows["tool.free_rotation_deg"].doc  # the comment above it
    assert rows["seams"].type == "list[mapping]" and "seams[].speed" in rows
    assert rows["tool.geometry[].radius_mm"].type == "float | null"
    assert "process.bead.area_mm2" in rows  # a process model's own section


def test_a_new_key_is_documented_with_its_comment():
    @dataclasses.dataclass
    class Inner:
        width_mm: float = 3.0  # how wide

    @dataclasses.dataclass
    class Outer:
        # the inner section
        inner: Inner | None = None
        count: int = dataclasses.field(default=None, metadata={"required": True})

    rows = [(r.key, r.type, r.required, r.default, r.doc) for r in cell_key_rows(Outer)]
    assert rows == [
        ("inner", "mapping | null", False, "", "the inner section"),
        ("inner.width_mm", "float", False, "3.0", "how wide"),
        ("count", "int", True, "", ""),
    ]


def test_the_table_has_one_row_per_key_and_escapes_pipes():
    table = cell_key_reference().splitlines()
    assert len(table) == 2 + len(cell_key_rows())
    shape = next(line for line in table if line.startswith("| `tool.geometry[].shape` |"))
    assert "box \\| cylinder" in shape and shape.count(" | ") == 3
