"""The documentation site (docs/, mkdocs.yml) and the README as its front page: the site
builds with warnings as errors and links checked, a broken link fails it, every command
in a code block parses with the command's own parser, the quick start runs as written,
the cell template plans, and no page cites an internal issue number."""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from offline_prog.cli_flags import parser

from conftest import REPO

DOCS = REPO / "docs"
PAGES = sorted(DOCS.rglob("*.md"))
README = REPO / "README.md"
# Fenced blocks of commands (not ```text synopses, ```yaml cells or program listings).
COMMAND_BLOCK = re.compile(r"^( *)```(bash|sh)\n(.*?)^\1```", re.S | re.M)
PYTHON_BLOCK = re.compile(r"^( *)```python\n(.*?)^\1```", re.S | re.M)


def _text(page: Path) -> str:
    return page.read_text(encoding="utf-8")


def command_lines(page: Path) -> list[str]:
    """Each command of the page's bash/sh blocks, one per line, indentation removed; in
    the README also its inline ``offline-prog ...`` spans (its quick start)."""
    lines = []
    for indent, _, block in COMMAND_BLOCK.findall(_text(page)):
        lines += [line[len(indent) :].strip() for line in block.splitlines() if line.strip()]
    if page == README:
        lines += re.findall(r"`(offline-prog [^`\s]+ [^`]+)`", _text(page))
    return lines


def offline_prog_commands(line: str) -> list[list[str]]:
    """The ``offline-prog`` invocations of a shell line (joined by && or ;), as argv."""
    found = []
    for part in re.split(r"&&|;|\|", line):
        words = shlex.split(part)
        if words[:1] == ["offline-prog"]:
            found.append(words[1:])
        elif words[:3] == ["python3", "-m", "offline_prog"] or words[:3] == [
            "python",
            "-m",
            "offline_prog",
        ]:
            found.append(words[3:])
    return found


def _run_mkdocs(config: Path, site: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(REPO), "NO_MKDOCS_2_WARNING": "1"}
    return subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config), "-d", str(site)],
        cwd=config.parent,
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )


def test_the_readme_is_a_front_page():
    """At most ~150 lines, starting with the two set-up commands CI runs (.ci/run), with
    a picture of the cell's frames and links into the documentation that exist."""
    text = _text(README)
    assert len(text.splitlines()) <= 160
    blocks = re.findall(r"```bash\n(.*?)```", text, flags=re.S)
    assert blocks[0].startswith("python3 -m pip install -c constraints.txt -e . && ")
    assert blocks[1].startswith('python3 -m pip install -c constraints.txt -e ".[test]"')
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", text)
    local = [link for link in links if not link.startswith("http")]
    assert any(link.endswith(".svg") for link in local)
    missing = [link for link in local if not (REPO / link).exists()]
    assert not missing and any(link.startswith("docs/") for link in local), missing


@pytest.mark.parametrize("page", [*PAGES, README], ids=lambda p: str(p.relative_to(REPO)))
def test_no_internal_issue_numbers(page):
    found = re.findall(r"\b[Ii]ssues? \d+|#\d{2,}\b", _text(page))
    assert not found, found


@pytest.mark.parametrize("page", [*PAGES, README], ids=lambda p: str(p.relative_to(REPO)))
def test_every_documented_command_parses(page):
    """Each ``offline-prog ...`` line of a bash/sh block is a command the parser takes
    (flags, choices, types: what ``--help`` documents), and each Python block compiles."""
    for line in command_lines(page):
        for argv in offline_prog_commands(line):
            try:
                parser().parse_args(argv)
            except SystemExit as exit:
                pytest.fail(f"{page.name}: `offline-prog {shlex.join(argv)}` exits {exit.code}")
    for _, block in PYTHON_BLOCK.findall(_text(page)):
        compile(block, str(page), "exec")


@pytest.mark.slow
def test_the_quick_start_runs_as_written(tmp_path):
    """Getting started's five steps in a folder holding the repository's cells/: plan,
    change the tool pose, plan again (the nozzle moved 20 mm), export; and its Python
    snippet. ``offline-prog`` runs as ``python -m offline_prog`` (this checkout's code)."""
    (tmp_path / "cells").symlink_to(REPO / "cells")
    page = DOCS / "getting-started.md"
    steps = [
        line
        for line in command_lines(page)
        if not line.startswith(("python3 -m pip", "python3 -m venv"))
    ]
    assert len(steps) == 4, steps
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    for line in steps:
        line = line.replace("offline-prog ", f"{shlex.quote(sys.executable)} -m offline_prog ")
        done = subprocess.run(
            line, shell=True, cwd=tmp_path, capture_output=True, text=True, env=env, timeout=600
        )
        assert done.returncode == 0, (line, done.stdout[-1000:], done.stderr[-1000:])
    moved = (tmp_path / "out" / "my_seal.yaml").read_text(encoding="utf-8")
    assert "translation: [1.02, 0.0, 0.5]" in moved
    assert sorted(p.name for p in (tmp_path / "out" / "my_seal" / "krl").glob("*.src"))
    (snippet,) = [b for _, b in PYTHON_BLOCK.findall(_text(page))]
    done = subprocess.run(
        [sys.executable, "-c", snippet], cwd=tmp_path, capture_output=True, text=True, env=env
    )
    assert done.returncode == 0, done.stderr[-2000:]


@pytest.mark.slow
def test_the_cell_template_plans(tmp_path):
    """cells/examples/reference.yaml, the example the cell file page shows, plans
    feasibly as a one-seam job."""
    import offline_prog as op

    plan = op.plan(REPO / "cells" / "examples" / "reference.yaml")
    assert plan.feasible, plan.failure
    assert len(plan.seams) == 1 and plan.cycle_time_s > 0


@pytest.mark.slow
def test_the_site_builds_strict_and_a_broken_link_fails_it(tmp_path):
    """``mkdocs build --strict`` of the site (the cell key table generated by its hook);
    the same site with one link to a missing page does not build."""
    done = _run_mkdocs(REPO / "mkdocs.yml", tmp_path / "site")
    assert done.returncode == 0, done.stderr[-3000:]
    built = (tmp_path / "site" / "cell-file" / "index.html").read_text(encoding="utf-8")
    assert "tool.geometry[].radius_mm" in built and "reference_plate" in built
    copy = tmp_path / "copy"
    shutil.copytree(REPO / "docs", copy / "docs")
    shutil.copy(REPO / "mkdocs.yml", copy / "mkdocs.yml")
    (copy / "cells" / "examples").mkdir(parents=True)
    shutil.copy(REPO / "cells" / "examples" / "reference.yaml", copy / "cells" / "examples")
    page = copy / "docs" / "api.md"
    page.write_text(_text(page) + "\nSee [nowhere](no-such-page.md).\n", encoding="utf-8")
    broken = _run_mkdocs(copy / "mkdocs.yml", tmp_path / "broken")
    assert broken.returncode != 0
    assert "no-such-page.md" in broken.stderr


# Pages whose command blocks the slow suite runs as written (getting-started's in the
# quick start test above). Placement's block is a search of minutes; the same command
# runs in tests/placement/test_place_cli.py.
RUN_AS_WRITTEN = ["calibration.md", "process-models.md"]


@pytest.mark.slow
@pytest.mark.parametrize("name", RUN_AS_WRITTEN)
def test_the_pages_commands_run_as_written(tmp_path, name):
    (tmp_path / "cells").symlink_to(REPO / "cells")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    lines = command_lines(DOCS / name)
    assert lines
    for line in lines:
        line = line.replace("offline-prog ", f"{shlex.quote(sys.executable)} -m offline_prog ")
        done = subprocess.run(
            ["bash", "-o", "pipefail", "-c", line],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            env=env,
            timeout=900,
        )
        assert done.returncode == 0, (line, done.stdout[-1000:], done.stderr[-1000:])
        assert done.stdout.strip(), line
