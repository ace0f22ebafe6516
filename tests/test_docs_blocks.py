"""Every fenced block of the README and the documentation site is accounted for. Each
command (```bash, ```sh) and Python snippet runs as written in the slow suite, in order,
from a folder holding a copy of the repository's cells/ (``offline-prog`` as ``python -m
offline_prog`` of this checkout), and does what it promises: exit 0, the files its
``--out``, ``>`` or ``"out/..."`` names exist, else it prints something. Each YAML
snippet of a cell parses and names only cell keys. A text block is a listing, unless it
holds a command: then it is a synopsis the command's parser knows or the output of the
command block above it, compared line by line.

A block that cannot run as written carries a marker, an HTML comment on the last
non-blank line before it (the site renders it as nothing):

- ``<!-- docs-test: needs hardware -->``: not run here (a robot, a controller).
- ``<!-- docs-test: needs ros-industrial-fanuc -->``: run with the ROS-Industrial FANUC
  packages of ../shared linked into the folder; skipped where they are absent.
- ``<!-- docs-test: shrink place --budget 2 --workers 0 place.screen_points=60 -->``:
  the block's ``offline-prog place`` gets the options and its cell file (in the copy of
  cells/) the key, so that a search of minutes takes seconds; the reader's command stays
  as it is (it runs as written, only longer).
- ``<!-- docs-test: output -->`` (text): what the command block above it prints; each
  line is a line of its output, in order (``...`` stands for any text).
- ``<!-- docs-test: synopsis -->`` (text): each ``offline-prog`` line names a command and
  options the parser has.

The README's first two bash blocks (install and plan; install and run the whole suite)
and their copies on other pages run in CI as written (.ci/run), not inside the suite.
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from test_api import ONE_LINER
from test_docs import offline_prog_commands

from offline_prog.cli_flags import parser
from offline_prog.config import safe_yaml
from offline_prog.config.key_reference import cell_key_rows

from conftest import CELLS, REPO

PAGES = [REPO / "README.md", *sorted((REPO / "docs").rglob("*.md"))]
FENCE = re.compile(r"^( *)```(\w*)[^\n]*\n(.*?)^\1```[ \t]*$", re.S | re.M)
MARKER = re.compile(r"^\s*<!-- docs-test: (.+?) -->\s*$")
COMMANDS, LANGUAGES = ("bash", "sh"), ("bash", "sh", "python", "yaml", "text")
# As tests/robot_import/test_import_fanuc.py finds them.
SHARED = next(
    (p for p in (REPO.parent / "shared", Path("/work/shared")) if (p / "robots").is_dir()), None
)
FANUC = SHARED / "robots" / "ros-industrial-fanuc" if SHARED else None


@dataclass
class Block:
    page: Path
    line: int  # of the opening fence, 1-based
    lang: str
    text: str  # the indentation of a block inside a list item removed
    marker: str | None

    def __str__(self) -> str:
        return f"{self.page.relative_to(REPO)}:{self.line} ```{self.lang}"


def blocks(page: Path) -> list[Block]:
    """The page's fenced blocks in order, each with the marker before it (or None)."""
    text = page.read_text(encoding="utf-8")
    found = []
    for match in FENCE.finditer(text):
        indent, lang, body = match.groups()
        before = [line for line in text[: match.start()].splitlines() if line.strip()]
        marker = MARKER.match(before[-1]) if before else None
        lines = [
            line[len(indent) :] if line.startswith(indent) else line for line in body.splitlines()
        ]
        found.append(
            Block(
                page,
                text[: match.start()].count("\n") + 1,
                lang,
                "\n".join(lines) + "\n",
                marker and marker.group(1),
            )
        )
    return found


ALL = [block for page in PAGES for block in blocks(page)]
CI_BLOCKS = [b.text for b in blocks(REPO / "README.md") if b.lang == "bash"][:2]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(REPO)))
def test_every_fence_and_marker_belongs_to_a_block(page):
    """The blocks found account for every fence line of the page (none missed: another
    indentation, a fence with attributes), and every marker stands before a block."""
    text = page.read_text(encoding="utf-8")
    fences = re.findall(r"(?m)^ *```", text)
    assert len(fences) == 2 * len(blocks(page)), page
    markers = re.findall(r"(?m)^ *<!-- docs-test:", text)
    assert len(markers) == sum(block.marker is not None for block in blocks(page)), page


def test_ci_runs_the_readmes_set_up_blocks():
    """The two blocks taken as run in CI are what .ci/run runs (its own extraction of
    the README's commands, run here)."""
    script = (REPO / ".ci" / "run").read_text(encoding="utf-8")
    extraction = re.search(r"<<'PY'\n(.*?)^PY$", script, re.S | re.M).group(1)
    done = subprocess.run(
        [sys.executable, "-c", extraction], cwd=REPO, capture_output=True, text=True, check=True
    )
    assert done.stdout.splitlines() == [" ".join(b.strip().splitlines()) for b in CI_BLOCKS]


def runs_in_ci(block: Block) -> bool:
    return block.lang in COMMANDS and block.text in CI_BLOCKS


def runs_here(block: Block) -> bool:
    """A command or Python block the slow suite runs: all but the set-up blocks CI runs
    and those marked as needing hardware."""
    runnable = block.lang in (*COMMANDS, "python")
    return runnable and not runs_in_ci(block) and block.marker != "needs hardware"


def shell_lines(block: Block) -> list[str]:
    """The block's commands, one per line (a trailing backslash continues a line)."""
    return [line.strip() for line in block.text.replace("\\\n", " ").splitlines() if line.strip()]


def holds_a_command(block: Block) -> bool:
    return any(re.match(r"(\$ |offline-prog |python3? )", line) for line in block.text.splitlines())


def shrink(marker: str | None) -> tuple[str, list[str], dict[str, str]] | None:
    """A shrink marker as (command, its added options, cell keys ``section.key`` ↦ value)."""
    if not (marker or "").startswith("shrink "):
        return None
    command, *words = marker.split()[1:]
    keys = dict(word.split("=", 1) for word in words if "=" in word)
    return command, [word for word in words if "=" not in word], keys


KNOWN_MARKERS = ("needs hardware", "needs ros-industrial-fanuc", "output", "synopsis")


@pytest.mark.parametrize("block", ALL, ids=str)
def test_every_block_is_run_checked_or_marked(block):
    """What each block is decides how it is checked: a block of another language, a text
    block holding an unmarked command, a marker no test reads, or an output block with no
    command above it fails here."""
    assert block.lang in LANGUAGES, f"{block}: say what the block is ({', '.join(LANGUAGES)})"
    assert block.marker is None or block.marker in KNOWN_MARKERS or shrink(block.marker), (
        f"{block}: unknown marker {block.marker!r}"
    )
    if block.lang == "text" and holds_a_command(block):
        assert block.marker in ("output", "synopsis"), (
            f"{block}: a command in a text block is never run: make it a bash block"
        )
    if block.marker == "output":
        above = [b for b in blocks(block.page) if b.line < block.line]
        assert block.lang == "text" and above and runs_here(above[-1]), block
    if shrinking := shrink(block.marker):
        command, options, keys = shrinking
        argvs = [a for line in shell_lines(block) for a in offline_prog_commands(line)]
        argvs = [argv for argv in argvs if argv[:1] == [command]]
        assert argvs, f"{block}: no offline-prog {command} to shrink"
        for argv in argvs:
            parser().parse_args(argv + options)  # exits 2 on an option it does not have
        assert set(keys) <= {row.key for row in cell_key_rows()}, keys
        assert all(re.fullmatch(r"\w+\.\w+", key) for key in keys), keys  # section.key
    if block.lang in COMMANDS and not runs_here(block):
        assert runs_in_ci(block) or block.marker == "needs hardware", block


def _key_paths(data, prefix: str = ""):
    if isinstance(data, dict):
        for key, value in data.items():
            path = f"{prefix}{key}"
            yield path
            yield from _key_paths(value, f"{path}.")
    elif isinstance(data, list):
        for item in data:
            yield from _key_paths(item, prefix[:-1] + "[].")


@pytest.mark.parametrize("block", [b for b in ALL if b.lang == "yaml"], ids=str)
def test_every_yaml_block_is_part_of_a_cell(block):
    """A YAML block (or the file it includes) parses as a cell file does, and each key
    in it is a key of the cell reference, or lies under one that takes any name (the
    calibration's part points, a grasp candidate's pose)."""
    text = block.text
    if include := re.fullmatch(r'--8<-- "(.+)"\n', text):
        text = (REPO / include.group(1)).read_text(encoding="utf-8")
    data = safe_yaml.load(block.page, text)
    assert isinstance(data, dict) and data, block
    keys = {row.key for row in cell_key_rows()}
    free = {key for key in keys if not any(k.startswith(f"{key}.") for k in keys)}
    for path in _key_paths(data):
        parents = [path[: m.start()].removesuffix("[]") for m in re.finditer(r"\.", path)]
        assert path in keys or any(p in free for p in parents), f"{block}: {path}"


def _options(command: list[str]) -> set[str]:
    action = parser()._subparsers._group_actions[0]
    for word in command:
        sub = action.choices[word]
        subs = sub._subparsers
        action = subs._group_actions[0] if subs else None
    return {flag for a in sub._actions for flag in a.option_strings}


@pytest.mark.parametrize("block", [b for b in ALL if b.marker == "synopsis"], ids=str)
def test_a_synopsis_names_the_parsers_commands_and_options(block):
    """Each ``offline-prog`` line (with its indented continuation lines) names a command
    of the parser and only options that command has."""
    entries = re.split(r"\n(?=offline-prog )", block.text.strip())
    for entry in entries:
        words = entry.split("#")[0].split()
        assert words[0] == "offline-prog", entry
        command = [words[1]] + ([words[2]] if words[1] == "robots" else [])
        flags = set(re.findall(r"--[a-z][a-z0-9-]*", " ".join(words)))
        assert flags <= _options(command), (entry, flags - _options(command))


# The slow runner: each page's blocks in order, in one folder.


def _with_keys(file: Path, keys: dict[str, str]) -> None:
    """Set ``section.key: value`` in a cell file's text (a top-level mapping's key)."""
    text = file.read_text(encoding="utf-8")
    for dotted, value in keys.items():
        section, key = dotted.split(".")
        body = re.search(rf"(?ms)^{section}:[^\n]*\n(.*?)(?=^\S|\Z)", text)
        assert body, (file, section)
        inner = re.sub(rf"(?m)^  {key}:.*\n", "", body.group(1))
        text = text[: body.start(1)] + f"  {key}: {value}\n" + inner + text[body.end(1) :]
    file.write_text(text, encoding="utf-8")


def _as_run(line: str, block: Block, folder: Path) -> str:
    """The line as the test runs it: shrunk as its marker says, ``offline-prog`` as this
    checkout's ``python -m offline_prog``."""
    if shrinking := shrink(block.marker):
        command, options, keys = shrinking
        argvs = [argv for argv in offline_prog_commands(line) if argv[:1] == [command]]
        for argv in argvs:
            written = shlex.join(["offline-prog", *argv])
            assert written in line, (line, written)
            line = line.replace(written, shlex.join(["offline-prog", *argv, *options]))
            cell = next(folder / word for word in argv[1:] if word.endswith((".yaml", ".yml")))
            _with_keys(cell, keys)
    python = shlex.quote(sys.executable)
    line = re.sub(r"^python3? ", f"{python} ", line)
    return re.sub(r"(?<![\w-])offline-prog ", f"{python} -m offline_prog ", line)


def _promised(line: str) -> list[str]:
    """The files a shell line says it writes: its ``--out`` and ``>`` targets, the
    folder of a ``python -m venv``."""
    words = shlex.split(line)
    return [
        after
        for word, after in zip(words, words[1:], strict=False)
        if word in ("--out", ">", "venv")
    ]


def _exists(folder: Path, name: str) -> bool:
    path = folder / name
    return path.is_dir() and any(path.iterdir()) or path.is_file() and path.stat().st_size > 0


def _run(argv: list[str], folder: Path, what: str) -> str:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    done = subprocess.run(argv, cwd=folder, capture_output=True, text=True, env=env, timeout=900)
    assert done.returncode == 0, (what, done.stdout[-1500:], done.stderr[-1500:])
    return done.stdout


def _assert_printed(block: Block, stdout: str) -> None:
    """Each line of an output block is, in order, a line of what the command printed."""
    printed = [line.strip() for line in stdout.splitlines()]
    position = 0
    for line in block.text.strip().splitlines():
        pattern = ".*".join(re.escape(part) for part in line.strip().split("..."))
        matching = [i for i in range(position, len(printed)) if re.fullmatch(pattern, printed[i])]
        assert matching, f"{block}: {line!r} is not printed:\n{stdout}"
        position = matching[0] + 1


def _quick_start(folder: Path) -> None:
    """Getting started's virtual environment has its Python, the tool pose edit moved the
    nozzle 20 mm, and export wrote KRL."""
    assert (folder / ".venv" / "bin" / "python").exists()
    moved = (folder / "out" / "my_seal.yaml").read_text(encoding="utf-8")
    assert "translation: [1.02, 0.0, 0.5]" in moved
    assert sorted((folder / "out" / "my_seal" / "krl").glob("*.src"))


AFTERWARDS = {"getting-started.md": _quick_start}
RUN_PAGES = [page for page in PAGES if any(runs_here(b) for b in blocks(page))]


@pytest.mark.slow  # plans the demos, places at a tiny size, imports a robot: minutes
@pytest.mark.parametrize("page", RUN_PAGES, ids=lambda p: str(p.relative_to(REPO)))
def test_the_pages_blocks_run_as_written(tmp_path, page):
    shutil.copytree(CELLS, tmp_path / "cells", symlinks=True)  # a shrink may edit a cell
    (tmp_path / "scripts").symlink_to(REPO / "scripts")
    stdout = ""
    for block in blocks(page):
        if block.marker == "output":
            _assert_printed(block, stdout)
        if not runs_here(block):
            continue
        if block.marker == "needs ros-industrial-fanuc":
            if FANUC is None or not FANUC.is_dir():
                pytest.skip(f"{FANUC} (ROS-I FANUC support packages) is absent")
            (tmp_path / "ros-industrial-fanuc").symlink_to(FANUC)
        if block.lang == "python":
            stdout = _run([sys.executable, "-c", block.text], tmp_path, str(block))
            promised = re.findall(r"[\"'](out/[^\"']+)[\"']", block.text)
            assert stdout.strip() or "print(" not in block.text, block
        else:
            stdout, promised = "", []
            for line in shell_lines(block):
                command = ["bash", "-e", "-o", "pipefail", "-c", _as_run(line, block, tmp_path)]
                printed = _run(command, tmp_path, line)
                assert printed.strip() or _promised(line), f"{block}: {line} promises nothing"
                stdout, promised = stdout + printed, promised + _promised(line)
        missing = [name for name in promised if not _exists(tmp_path, name)]
        assert not missing, f"{block}: wrote no {missing}"
    if check := AFTERWARDS.get(page.name):
        check(tmp_path)


def test_the_readmes_inline_commands_are_run_on_getting_started():
    """The README's quick start names its commands inline: each is a command of getting
    started's blocks (run above) but the session (interactive: tests/session start it),
    and its Python line is the one tests/test_api.py runs."""
    text = (REPO / "README.md").read_text(encoding="utf-8")
    inline = re.findall(r"`((?:offline-prog [^`\s]+|sed|python3 -m venv) [^`\n]+)`", text)
    page = REPO / "docs" / "getting-started.md"
    run = {line for block in blocks(page) if runs_here(block) for line in shell_lines(block)}
    assert len(inline) >= 5
    assert [line for line in inline if line not in run] == [
        "offline-prog session cells/seal_plate_kr16.yaml"
    ]
    python = re.search(r"`(import offline_prog as op;[^`]+)`", text).group(1)
    assert " ".join(python.split()).replace('"', "'") == ONE_LINER
