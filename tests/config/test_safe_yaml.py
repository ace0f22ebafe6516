"""Cell files beyond the limits end fast, with one short line (constants.py)."""

import time

import pytest
import yaml
from test_cell_errors import BASE, write_cell

from offline_prog.config.cell import load_cell
from offline_prog.constants import MAX_CELL_FILE_BYTES, MAX_YAML_DEPTH, MAX_YAML_NODES
from offline_prog.errors import InputError
from offline_prog.plan import plan_cell

FAST_S = 5.0  # each refusal takes well under this
MAX_MESSAGE_CHARS = 400

BOMB = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 10)}]\n" for i in range(8)
)


def refused(cell, match: str) -> str:
    started = time.perf_counter()
    with pytest.raises(InputError, match=match) as info:
        load_cell(cell)
    assert time.perf_counter() - started < FAST_S
    message = str(info.value)
    assert "\n" not in message and len(message) < MAX_MESSAGE_CHARS, message[:1000]
    return message


def test_alias_bomb(tmp_path):
    refused(write_cell(tmp_path, BASE + BOMB), f"more than {MAX_YAML_NODES:,} values")


def test_aliases_below_the_limit_are_cut_in_messages(tmp_path):
    levels = "&a [x, x, x, x, x, x, x, x, x, x], &b [*a, *a, *a, *a, *a, *a, *a, *a, *a, *a], "
    levels += "&c [*b, *b, *b, *b, *b, *b, *b, *b, *b, *b], [*c, *c, *c, *c, *c, *c, *c, *c]"
    cell = write_cell(tmp_path, BASE.replace("name: test", f"name: [{levels}]"))
    refused(cell, "name: expected str, got \\[\\['x', 'x'")


def test_self_referencing_alias(tmp_path):
    refused(write_cell(tmp_path, BASE + "loop: &l [*l]\n"), "nested deeper than 50")


def test_large_file(tmp_path):
    cell = write_cell(tmp_path, BASE + "#" + "x" * (50 * 1024 * 1024) + "\n")
    refused(cell, f"a cell file has at most {MAX_CELL_FILE_BYTES:,}")


@pytest.mark.parametrize("depth", [MAX_YAML_DEPTH + 1, 100_000])
def test_deep_nesting(tmp_path, depth):
    refused(write_cell(tmp_path, BASE + "deep: " + "[" * depth + "]" * depth + "\n"), "nested")


def test_unterminated_deep_nesting(tmp_path):
    refused(write_cell(tmp_path, BASE + "deep: " + "[" * 100_000 + "\n"), "nested deeper")


@pytest.mark.parametrize("depth", [MAX_YAML_DEPTH, 2_000, 100_000])
def test_deep_block_nesting_names_its_line(tmp_path, depth):
    """Block sequences nested on one line ("- - - x", under the top mapping: one level
    beyond the limit), and beyond libyaml's own 1,000 levels: our message, its line."""
    lines = BASE.count("\n")
    cell = write_cell(tmp_path, BASE + "deep:\n" + "- " * depth + "x\n")
    message = refused(cell, f"nested deeper than {MAX_YAML_DEPTH} levels")
    assert f"line {lines + 2}:" in message


def test_duplicate_keys(tmp_path):
    cell = write_cell(tmp_path, BASE.replace("  speed: 0.1", "  speed: 0.1\n  speed: 1.0"))
    assert "line 16: key 'speed' given twice" in refused(cell, "given twice")


def test_merge_keys_are_not_duplicates(tmp_path):
    text = BASE.replace("motion:\n", "limits: &m {max_jerk: 10.0}\nmotion:\n  <<: *m\n")
    with pytest.raises(InputError, match="limits: unknown key"):  # the anchor's own key
        load_cell(write_cell(tmp_path, text.replace("  max_jerk: 10.0\n", "")))


def test_latin1_names_the_line(tmp_path):
    cell = write_cell(tmp_path, "")
    cell.write_bytes(BASE.replace("name: test", "name: Düse").encode("latin-1"))
    assert "line 1: byte 0xfc is not UTF-8" in refused(cell, "save the cell file as UTF-8")


def test_utf16_is_named(tmp_path):
    cell = write_cell(tmp_path, "")
    cell.write_bytes(BASE.encode("utf-16"))
    refused(cell, "UTF-16")


def test_utf8_bom_is_accepted(tmp_path):
    cell = write_cell(tmp_path, "")
    cell.write_bytes(b"\xef\xbb\xbf" + BASE.replace("name: test", "name: Düse").encode())
    assert load_cell(cell).name == "Düse"


def test_long_values_are_cut_in_messages(tmp_path):
    cell = write_cell(tmp_path, BASE.replace("speed: 0.1", f"speed: [{', '.join(['1'] * 10**4)}]"))
    refused(cell, "motion.speed: expected float")


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ("speed: 0.1", "speed: 100", "100 mm/s is 0.1"),
        ("max_jerk: 10.0", "max_jerk: 10.0\n  sample_rate_hz: 1.0e+6", "more than 10000 Hz"),
        ("max_jerk: 10.0", "max_jerk: 10.0\n  sample_rate_hz: 1e6", "write 1.0e"),
        ("speed: 0.1", "speed: 0.000001", "more than 2,000,000"),
    ],
)
def test_implausible_motion_is_refused(tmp_path, old, new, match):
    with pytest.raises(InputError, match=match):
        plan_cell(write_cell(tmp_path, BASE.replace(old, new)))


@pytest.mark.parametrize(
    "name",
    [
        '"Sealing, on: the plate"',
        "'demo, on: plate'",
        '"off: yes, no"',
        "'{on: 1}'",
        "|-\n  line one, on: two",
    ],
)
def test_strings_that_look_like_yaml11_booleans_are_kept(tmp_path, name):
    """YAML 1.2 booleans (true/false only) are parsed, not edited into the text: a
    string holding ``on:`` comes out as written, and its line is no error."""
    text = BASE.replace("name: test", f"name: test\ndescription: {name}")
    cell = load_cell(write_cell(tmp_path, text))
    assert cell.description == yaml.safe_load(f"v: {name}")["v"]
    cell = load_cell(write_cell(tmp_path, BASE.replace("name: test", f"name: {name}")))
    assert cell.name == yaml.safe_load(f"v: {name}")["v"]


def test_yaml11_boolean_words_as_keys_and_values(tmp_path):
    """``on:`` / ``off:`` keys are strings (the process_io contract); a bool field
    takes only true / false (``closed: yes`` is YAML 1.1 and refused)."""
    io = "  process_io: {on: {digital_output: 3, lead_mm: 5}, off: {digital_output: 3}}\n"
    cell = load_cell(write_cell(tmp_path, BASE.replace("tool:\n", "tool:\n" + io)))
    assert cell.tool.process_io.on.digital_output == 3
    assert cell.tool.process_io.off.lead_mm == 0.0
    refused(write_cell(tmp_path, BASE.replace("closed: false", "closed: yes")), "expected bool")
