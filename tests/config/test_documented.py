"""The documentation names the cell file's keys and the folder ``plan`` writes to by
default, and the code does what it says."""

import dataclasses
import typing

from test_cell_errors import BASE, write_cell

from offline_prog.cli import main
from offline_prog.cli_flags import parser
from offline_prog.config.cell import Cell

from conftest import REPO

DOCS = REPO / "docs"
EXAMPLE = (REPO / "cells" / "examples" / "reference.yaml").read_text(encoding="utf-8")


def schema_keys(schema, prefix: str = ""):
    """(dotted key, field name) of every field of the cell schema, nested ones too."""
    for field in dataclasses.fields(schema):
        key = f"{prefix}{field.name}"
        yield key, field.name
        for outer in (field.type, *typing.get_args(field.type)):
            for inner in (outer, *typing.get_args(outer)):
                if dataclasses.is_dataclass(inner):
                    yield from schema_keys(inner, f"{key}.")


def test_every_cell_key_is_in_the_generated_reference():
    """The cell file page's table (docs/hooks/cell_reference.py writes it at build time)
    names every key of the schema, nested ones with their dotted path, and no other."""
    from offline_prog.config.key_reference import cell_key_rows

    documented = {row.key.replace("[]", "") for row in cell_key_rows()}
    assert documented == {key for key, _ in schema_keys(Cell)}
    page = (DOCS / "cell-file.md").read_text(encoding="utf-8")
    assert "<!-- cell-key-reference -->" in page
    assert '--8<-- "cells/examples/reference.yaml"' in page  # the example is the real file


def test_the_examples_show_the_keys_newcomers_ask_for():
    """The cell file example names the optional keys, and the jobs page's example the
    job's link time."""
    for key in ("name: ", "description: ", "csv_seam: ", "units: "):
        assert f"\n{key}" in EXAMPLE or f"\n  {key}" in EXAMPLE or f"# {key}" in EXAMPLE, key
    job_example = (DOCS / "jobs.md").read_text(encoding="utf-8").split("```")[1]
    assert "\n  link_time_s: " in job_example


def test_the_default_folder_is_out_slash_the_file_stem(tmp_path, monkeypatch, capsys):
    """The docs and --help say ``out/<file stem>``, and that is where ``plan`` writes
    (here the stem ``my_cell`` and the cell's name ``test`` differ)."""
    commands = (DOCS / "commands.md").read_text(encoding="utf-8")
    assert "`plan` writes to `DIR` (default `out/<file stem>`" in commands
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
