"""The README documents the cell file's keys and the folder ``plan`` writes to by
default, and the code does what it says."""

import dataclasses
import re
import typing

from test_cell_errors import BASE, write_cell

from offline_prog.cli import main
from offline_prog.cli_flags import parser
from offline_prog.config.cell import Cell

from conftest import REPO

README = (REPO / "README.md").read_text()


def schema_keys(schema, prefix: str = ""):
    """(dotted key, field name) of every field of the cell schema, nested ones too."""
    for field in dataclasses.fields(schema):
        key = f"{prefix}{field.name}"
        yield key, field.name
        for outer in (field.type, *typing.get_args(field.type)):
            for inner in (outer, *typing.get_args(outer)):
                if dataclasses.is_dataclass(inner):
                    yield from schema_keys(inner, f"{key}.")


def test_every_cell_key_is_in_the_readme():
    missing = [  # named somewhere: in the cell file example, or in the text
        key for key, name in schema_keys(Cell) if not re.search(rf"\b{name}\b", README)
    ]
    assert not missing, f"cell keys the README does not name: {missing}"
    example = README.split("## Cell file")[1].split("```")[1]  # the cell file example
    job_example = README.split("## Whole jobs")[1].split("```")[1]
    for key in ("name: ", "description: ", "csv_seam: ", "units: "):
        assert f"\n{key}" in example or f"\n  {key}" in example or f"# {key}" in example, key
    assert "\n  link_time_s: " in job_example


def test_the_default_folder_is_out_slash_the_file_stem(tmp_path, monkeypatch, capsys):
    """README and --help say ``out/<file stem>``, and that is where ``plan`` writes
    (here the stem ``my_cell`` and the cell's name ``test`` differ)."""
    assert "`plan` writes to `DIR` (default `out/<file stem>`" in README
    plan_help = next(
        action.help
        for action in parser()._subparsers._group_actions[0].choices["plan"]._actions
        if "--out" in action.option_strings
    )
    assert plan_help.startswith("output folder (default: out/<file stem>")
    cell = write_cell(tmp_path, BASE)
    cell = cell.rename(tmp_path / "my_cell.yaml")
    monkeypatch.chdir(tmp_path)
    assert main(["plan", str(cell)]) == 0
    assert (tmp_path / "out" / "my_cell" / "report.json").is_file()
    assert not (tmp_path / "out" / "test").exists()
    assert capsys.readouterr().out.endswith("; outputs in out/my_cell\n")
