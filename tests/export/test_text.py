"""Strings from the cell file never become program statements (code injection)."""

import dataclasses
import re

import numpy as np
import pytest
from krl_lint import assert_krllint_clean

from offline_prog.export.abb.rapid import write_rapid
from offline_prog.export.kuka.krl import write_krl
from offline_prog.export.program import ProgramData
from offline_prog.export.text import (
    RAPID_STRING_MAX,
    identifier,
    identifier_from,
    plain_ascii,
    rapid_string,
    urscript_string,
)
from offline_prog.export.ur.urscript import write_urscript

# Each carries a statement after a line break of some kind, and the characters that
# mean something to one of the languages: quotes, ; (KRL comment), % (RAPID late
# binding), ! and # (comments), & (KRL meta lines), non-ASCII, a BOM, tabs.
HOSTILE = [
    'x\nsocket_open("10.0.0.1", 80, "evil")',
    "x\r\nINJECTED_LINE = 1",
    "x\rINJECTED_LINE = 1",
    'x\u2028INJECTED_LINE "q" ; % ! # & \\ \t é € 日本 \ufeff\x00\x1b[2J',
    '";\n%"INJECTED_LINE"%\n!\n#',
]


def hostile(data: ProgramData, text: str) -> ProgramData:
    return dataclasses.replace(
        data,
        cell_name=text,
        cell_file=f"/tmp/{text}.yaml",
        tool=text,
        part=text,
        robot=data.robot,
        failure=text,
        joint_names=tuple(f"{name}{text}" for name in data.joint_names),
    )


def code_lines(text: str, marker: str) -> list[str]:
    """The program's lines that are not comments."""
    return [line for line in text.splitlines() if not line.strip().startswith(marker)]


def assert_only_in_comments(files, marker: str, normalize=lambda line: line) -> None:
    for file in files:
        text = file.read_bytes().decode("ascii")  # ASCII only
        for line in map(normalize, code_lines(text, marker)):
            assert "INJECTED" not in line and "socket_open" not in line, (file, line)


def test_plain_ascii_is_one_printable_line():
    rng = np.random.default_rng(0)
    alphabet = [chr(c) for c in range(0, 0x3000)] + ["\u2028", "\u2029", "\x85", "\ufeff"]
    for _ in range(200):
        text = "".join(rng.choice(alphabet, size=40))
        clean = plain_ascii(text)
        assert all(" " <= c <= "~" for c in clean), clean
        assert clean == clean.strip() and "  " not in clean
    assert plain_ascii("σ ≤ 5°, café\r\nnext") == "sigma <= 5 deg, cafe next"


def test_string_literals_are_escaped():
    assert rapid_string('say "hi" \\ bye') == '"say ""hi"" \\\\ bye"'
    assert len(rapid_string('"' * 200)) <= RAPID_STRING_MAX + 2
    assert rapid_string('"' * 200).count('"') % 2 == 0  # never cut inside an escape
    assert urscript_string('a"b\\c\nd') == '"a\'b/c d"'


def test_identifiers_are_checked_or_derived():
    assert identifier("Main_1", max_chars=8, what="name") == "Main_1"
    for bad in ("1abc", "a b", "a\nb", "é", "", "a;b", "toolong12"):
        with pytest.raises(ValueError, match="name="):
            identifier(bad, max_chars=8, what="name")
    assert identifier_from("tool", 'x\n"é;%', max_chars=32) == "tool_x__e__"


@pytest.fixture(scope="module")
def kuka(planned_folder):
    return ProgramData.load(planned_folder("seal_plate_kr16")[1])


@pytest.fixture(scope="module")
def abb(planned_folder):
    return ProgramData.load(planned_folder("weld_seam_irb2400")[1])


@pytest.fixture(scope="module")
def ur(planned_folder):
    return ProgramData.load(planned_folder("tape_cylinder_ur10e")[1])


@pytest.mark.parametrize("text", HOSTILE)
def test_krl_code_is_unchanged_by_hostile_names(kuka, tmp_path, text):
    clean = write_krl(kuka, tmp_path / "clean", line_limit=200, forced=True)
    dirty = write_krl(hostile(kuka, text), tmp_path / "dirty", line_limit=200, forced=True)
    assert_only_in_comments(dirty.files, ";")
    for a, b in zip(clean.files, dirty.files, strict=True):
        assert code_lines(a.read_text(), ";") == code_lines(b.read_text(), ";")


@pytest.mark.parametrize("text", HOSTILE)
def test_rapid_code_is_unchanged_by_hostile_names(abb, tmp_path, text):
    clean = write_rapid(abb, tmp_path / "clean", forced=True)
    dirty = write_rapid(hostile(abb, text), tmp_path / "dirty", forced=True)

    def names(line):  # tool and wobj identifiers derive from the names: compare the rest
        return re.sub(r"\b(tool|wobj)_\w+", r"\1_", line)

    def normalized(file):
        return [names(line) for line in code_lines(file.read_text(), "!")]

    assert_only_in_comments(dirty.files, "!", names)

    for a, b in zip(clean.files, dirty.files, strict=True):
        assert normalized(a) == normalized(b)


@pytest.mark.parametrize("mode", ["servoj", "movel"])
@pytest.mark.parametrize("text", HOSTILE)
def test_urscript_code_is_unchanged_by_hostile_names(ur, tmp_path, text, mode):
    clean = write_urscript(ur, tmp_path / "clean", mode=mode, forced=True)
    dirty = write_urscript(hostile(ur, text), tmp_path / "dirty", mode=mode, forced=True)
    assert_only_in_comments([dirty.file], "#")
    assert code_lines(clean.file.read_text(), "#") == code_lines(dirty.file.read_text(), "#")


def test_program_names_are_identifiers(kuka, abb, ur, tmp_path):
    with pytest.raises(ValueError):
        write_krl(kuka, tmp_path, name="x\nEND")
    with pytest.raises(ValueError):
        write_rapid(abb, tmp_path, module='M"; ENDMODULE')
    with pytest.raises(ValueError):
        write_urscript(ur, tmp_path, name="x():\n  popup")
    assert not list(tmp_path.iterdir())


def test_krllint_accepts_hostile_headers(kuka, tmp_path):
    write_krl(hostile(kuka, "".join(HOSTILE)), tmp_path / "krl", forced=True)
    assert_krllint_clean(tmp_path / "krl", tmp_path)


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # rapidchecker's pyparsing calls
def test_rapidchecker_accepts_hostile_headers(abb, tmp_path):
    rapidchecker = pytest.importorskip(
        "rapidchecker.cli", reason="rapidchecker (pip install rapidchecker) not installed"
    )
    result = write_rapid(hostile(abb, "".join(HOSTILE)), tmp_path, forced=True, line_limit=60)
    for file in result.files:
        if file.suffix == ".mod":
            assert [str(e) for e in rapidchecker.check_file(file.read_text())] == []
