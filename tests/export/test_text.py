"""Strings from the cell file never become program statements (code injection)."""

import dataclasses
import re

import numpy as np
import pytest
from krl_lint import assert_krllint_clean

from offline_prog.export.formats import export
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.text import (
    RAPID_STRING_MAX,
    identifier,
    identifier_from,
    plain_ascii,
    rapid_string,
    urscript_string,
)

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


def hostile(data: JobProgramData, text: str) -> JobProgramData:
    """The job with ``text`` in every name its programs print (a failed plan: the
    failure is printed too)."""
    rows = dataclasses.replace(
        data.job,
        cell_name=text,
        cell_file=f"/tmp/{text}.yaml",
        tool=text,
        part=text,
        feasible=False,
        failure=text,
        joint_names=tuple(f"{name}{text}" for name in data.job.joint_names),
    )
    return dataclasses.replace(data, job=rows)


def forced(data: JobProgramData) -> JobProgramData:
    """The job as a failed plan without a failure text of its own."""
    return dataclasses.replace(data, job=dataclasses.replace(data.job, feasible=False))


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


def written(data: JobProgramData, fmt: str, folder) -> list:
    """The program files of a forced export (the manifest left out)."""
    return [f for f in export(data, fmt, folder, force=True) if f.suffix != ".json"]


@pytest.fixture(scope="module")
def kuka(planned_job):
    return JobProgramData.load(planned_job("seal_plate_kr16")[1])


@pytest.fixture(scope="module")
def abb(planned_job):
    return JobProgramData.load(planned_job("weld_seam_irb2400")[1])


@pytest.fixture(scope="module")
def ur(planned_job):
    return JobProgramData.load(planned_job("tape_cylinder_ur10e")[1])


@pytest.mark.parametrize("text", HOSTILE)
def test_krl_code_is_unchanged_by_hostile_names(kuka, tmp_path, text):
    clean = written(forced(kuka), "krl", tmp_path / "clean")
    dirty = written(hostile(kuka, text), "krl", tmp_path / "dirty")
    assert_only_in_comments(dirty, ";")
    for a, b in zip(clean, dirty, strict=True):
        assert code_lines(a.read_text(), ";") == code_lines(b.read_text(), ";")


@pytest.mark.parametrize("text", HOSTILE)
def test_rapid_code_is_unchanged_by_hostile_names(abb, tmp_path, text):
    clean = written(forced(abb), "rapid", tmp_path / "clean")
    dirty = written(hostile(abb, text), "rapid", tmp_path / "dirty")

    def names(line):  # tool and wobj identifiers derive from the names: compare the rest
        return re.sub(r"\b(tool|wobj)_\w+", r"\1_", line)

    def normalized(file):
        return [names(line) for line in code_lines(file.read_text(), "!")]

    assert_only_in_comments(dirty, "!", names)

    for a, b in zip(clean, dirty, strict=True):
        assert normalized(a) == normalized(b)


@pytest.mark.parametrize("text", HOSTILE)
def test_urscript_code_is_unchanged_by_hostile_names(ur, tmp_path, text):
    (clean,) = written(forced(ur), "urscript", tmp_path / "clean")
    (dirty,) = written(hostile(ur, text), "urscript", tmp_path / "dirty")
    assert_only_in_comments([dirty], "#")
    assert code_lines(clean.read_text(), "#") == code_lines(dirty.read_text(), "#")


def test_program_names_are_identifiers(kuka, abb, ur, tmp_path):
    with pytest.raises(ValueError):
        export(forced(kuka), "krl", tmp_path, force=True, name="x\nEND")
    with pytest.raises(ValueError):
        export(forced(abb), "rapid", tmp_path, force=True, module='M"; ENDMODULE')
    with pytest.raises(ValueError):
        export(forced(ur), "urscript", tmp_path, force=True, name="x():\n  popup")
    assert not list(tmp_path.iterdir())


def test_krllint_accepts_hostile_headers(kuka, tmp_path):
    written(hostile(kuka, "".join(HOSTILE)), "krl", tmp_path / "krl")
    (tmp_path / "krl" / "offline_prog.manifest.json").unlink()
    assert_krllint_clean(tmp_path / "krl", tmp_path)


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # rapidchecker's pyparsing calls
def test_rapidchecker_accepts_hostile_headers(abb, tmp_path):
    rapidchecker = pytest.importorskip(
        "rapidchecker.cli", reason="rapidchecker (pip install rapidchecker) not installed"
    )
    for file in written(hostile(abb, "".join(HOSTILE)), "rapid", tmp_path):
        if file.suffix == ".mod":
            assert [str(e) for e in rapidchecker.check_file(file.read_text())] == []
