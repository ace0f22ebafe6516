"""The plan folder is replaced whole: no stale files, no mixtures, our files only."""

import errno
import os
import subprocess
import sys

import pytest

from offline_prog import atomic
from offline_prog.atomic import MANIFEST, read_manifest, remove_stale, write_atomic
from offline_prog.errors import InputError
from offline_prog.export.formats import export
from offline_prog.export.program import ProgramData
from offline_prog.results import plan_folder
from offline_prog.results.plan_folder import write_outputs

from conftest import REPO


def listing(folder):
    """{relative path: bytes} of every file under folder."""
    return {
        str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()
    }


@pytest.fixture(scope="module")
def kuka(planned_folder):
    return planned_folder("seal_plate_kr16")


@pytest.fixture(scope="module")
def abb(planned_folder):
    return planned_folder("weld_seam_irb2400")


@pytest.mark.slow
def test_replanning_another_cell_leaves_only_its_files(kuka, abb, tmp_path):
    out = tmp_path / "out"
    write_outputs(kuka[0], out)
    assert (out / "programs" / "offline_prog.src").is_file()
    files, _ = write_outputs(abb[0], out)
    names = set(listing(out))
    assert not any(name.endswith((".src", ".dat")) for name in names)
    assert {str(p.relative_to(out)) for p in files.values()} <= names
    assert set(read_manifest(out)["files"]["plan"]) == {n.split("/")[0] for n in names} - {MANIFEST}
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no temporary sibling left


@pytest.mark.slow
def test_a_crash_mid_write_leaves_the_previous_folder(kuka, abb, tmp_path, monkeypatch):
    out = tmp_path / "out"
    write_outputs(kuka[0], out)
    before = listing(out)

    def crash(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(plan_folder, "write_preview_html", crash)
    with pytest.raises(KeyboardInterrupt):
        write_outputs(abb[0], out)
    assert listing(out) == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_disk_full_leaves_the_previous_folder(kuka, tmp_path, monkeypatch):
    out = tmp_path / "out"
    write_outputs(kuka[0], out)
    before = listing(out)

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(out / "report.html"))

    monkeypatch.setattr(plan_folder, "write_report_html", full)
    with pytest.raises(OSError, match="No space"):
        write_outputs(kuka[0], out)
    assert listing(out) == before


def test_a_folder_with_foreign_files_is_not_replaced(kuka, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    with pytest.raises(InputError, match="did not write \\(notes.txt\\)"):
        write_outputs(kuka[0], out)
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="not a folder"):
        write_outputs(kuka[0], tmp_path / "file")
    assert (out / "notes.txt").read_text() == "mine"


def test_reexport_removes_its_own_stale_parts_only(kuka, tmp_path):
    data = ProgramData.load(kuka[1])
    out = tmp_path / "programs"
    out.mkdir()
    (out / "offline_prog_9.src").write_text("a user's file, not in the manifest")
    split = export(data, "krl", out, line_limit=60)
    assert len(split) > 4 and (out / "offline_prog_3.src").is_file()
    export(data, "csv", out)
    whole = export(data, "krl", out)
    assert [p.name for p in whole] == ["offline_prog.src", "offline_prog.dat"]
    assert sorted(p.name for p in out.iterdir()) == sorted(
        ["offline_prog.src", "offline_prog.dat", "joint_trajectory.csv", "offline_prog_9.src"]
        + [MANIFEST]
    )


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_files_follow_the_umask(tmp_path, umask):
    old = os.umask(umask)
    try:
        write_atomic(tmp_path / "f.txt", "x")
        with atomic.staged_folder(tmp_path / "d") as folder:
            write_atomic(folder / "g.txt", "y")
    finally:
        os.umask(old)
    assert (tmp_path / "f.txt").stat().st_mode & 0o777 == 0o666 & ~umask
    assert (tmp_path / "d" / "g.txt").stat().st_mode & 0o777 == 0o666 & ~umask
    assert (tmp_path / "d").stat().st_mode & 0o777 == 0o777 & ~umask


def test_temporary_files_of_a_killed_run_are_removed(tmp_path):
    script = (
        "import sys, time\n"
        "from pathlib import Path\n"
        "from offline_prog.atomic import atomic_stream, staged_folder\n"
        "with staged_folder(Path(sys.argv[1]) / 'out') as folder:\n"
        "    with atomic_stream(folder / 'big.csv') as stream:\n"
        "        stream.write(b'x' * 1000)\n"
        "        print('writing', flush=True)\n"
        "        time.sleep(60)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    child = subprocess.Popen(
        [sys.executable, "-c", script, str(tmp_path)], stdout=subprocess.PIPE, env=env
    )
    assert child.stdout.readline() == b"writing\n"
    child.kill()
    child.wait()
    left = [p.name for p in tmp_path.iterdir()]
    assert left and all(name.startswith(atomic.TEMP_PREFIX) for name in left)
    remove_stale(tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_remove_stale_keeps_live_processes_files(tmp_path):
    mine = tmp_path / f"{atomic.temp_prefix('x')}abc.tmp"
    mine.write_text("in use")
    remove_stale(tmp_path)
    assert mine.exists()


@pytest.mark.parametrize("exchange", [True, False])
def test_staged_folder_swaps_with_or_without_renameat2(tmp_path, monkeypatch, exchange):
    if not exchange:  # file systems without RENAME_EXCHANGE: two renames
        monkeypatch.setattr(atomic, "_exchange", lambda a, b: False)
    for content in ("old", "new"):
        with atomic.staged_folder(tmp_path / "d") as folder:
            write_atomic(folder / content, content)
    assert [p.name for p in tmp_path.iterdir()] == ["d"]
    assert [p.name for p in (tmp_path / "d").iterdir()] == ["new"]


@pytest.mark.parametrize("kind", ["seam", "job"])
def test_report_html_names_the_plan_folder_not_the_staged_one(planned_folder, planned_job, kind):
    """The page is rendered in the staged ``.offline_prog-<pid>-...`` sibling; it names
    the folder the user opens."""
    from offline_prog.atomic import TEMP_PREFIX

    if kind == "seam":
        _, folder = planned_folder("seal_plate_kr16")
    else:
        _, folder = planned_job("seal_job_kr16")
    page = (folder / "report.html").read_text()
    assert f"; plan folder {folder.name}</p>" in page
    assert TEMP_PREFIX not in page
