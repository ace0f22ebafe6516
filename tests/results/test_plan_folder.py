"""The plan folder is replaced whole: no stale files, no mixtures, our files only; its
files are written from the finished plan, without computing its poses again."""

import errno
import os
import subprocess
import sys

import pytest

from offline_prog import atomic
from offline_prog.atomic import MANIFEST, read_manifest, remove_stale, write_atomic
from offline_prog.errors import InputError
from offline_prog.export.formats import export
from offline_prog.export.job_program import JobProgramData
from offline_prog.results import job_folder
from offline_prog.results.job_folder import write_job_outputs

from conftest import REPO


def listing(folder):
    """{relative path: bytes} of every file under folder."""
    return {
        str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()
    }


@pytest.fixture(scope="module")
def kuka(planned_job):
    return planned_job("seal_plate_kr16")


@pytest.fixture(scope="module")
def abb(planned_job):
    return planned_job("weld_seam_irb2400")


@pytest.mark.slow
def test_replanning_another_cell_leaves_only_its_files(kuka, abb, tmp_path):
    out = tmp_path / "out"
    write_job_outputs(kuka[0], out)
    assert (out / "programs" / "offline_prog.src").is_file()
    files, _ = write_job_outputs(abb[0], out)
    names = set(listing(out))
    assert not any(name.endswith((".src", ".dat")) for name in names)
    assert {str(p.relative_to(out)) for p in files.values()} <= names
    assert set(read_manifest(out)["files"]["plan"]) == {n.split("/")[0] for n in names} - {MANIFEST}
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no temporary sibling left


@pytest.mark.slow
def test_a_crash_mid_write_leaves_the_previous_folder(kuka, abb, tmp_path, monkeypatch):
    out = tmp_path / "out"
    write_job_outputs(kuka[0], out)
    before = listing(out)

    def crash(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(job_folder, "write_job_preview_html", crash)
    with pytest.raises(KeyboardInterrupt):
        write_job_outputs(abb[0], out)
    assert listing(out) == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_disk_full_leaves_the_previous_folder(kuka, tmp_path, monkeypatch):
    out = tmp_path / "out"
    write_job_outputs(kuka[0], out)
    before = listing(out)

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(out / "report.html"))

    monkeypatch.setattr(job_folder, "write_job_report_html", full)
    with pytest.raises(OSError, match="No space"):
        write_job_outputs(kuka[0], out)
    assert listing(out) == before


def test_a_folder_with_foreign_files_is_not_replaced(kuka, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    with pytest.raises(InputError, match="did not write \\(notes.txt\\)"):
        write_job_outputs(kuka[0], out)
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="not a folder"):
        write_job_outputs(kuka[0], tmp_path / "file")
    assert (out / "notes.txt").read_text() == "mine"


def test_reexport_removes_its_own_stale_parts_only(kuka, planned_job, tmp_path):
    """A job of four seams, then one of one seam into the same folder: the modules of
    seams 2 to 4 go, the user's file stays."""
    out = tmp_path / "programs"
    out.mkdir()
    (out / "offline_prog_9.src").write_text("a user's file, not in the manifest")
    four = export(JobProgramData.load(planned_job("seal_job_kr16")[1]), "krl", out)
    assert len(four) == 12 and (out / "offline_prog_4.src").is_file()  # + the nominal frames
    data = JobProgramData.load(kuka[1])
    export(data, "csv", out)
    one = export(data, "krl", out)
    names = ["offline_prog.src", "offline_prog.dat", "offline_prog_1.src", "offline_prog_1.dat"]
    names += ["offline_prog_frm.src", "offline_prog_frm.dat"]
    assert [p.name for p in one] == names
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [*names, "joint_trajectory.csv", "offline_prog_9.src", MANIFEST]
    )


def test_the_folders_writers_compute_no_flange_pose_again(kuka, tmp_path, monkeypatch):
    """trajectory.csv, plan.npz and the programs read the flange poses the plan
    computed (``JobPlan.X_BE``): with the robot's forward kinematics raising, the
    folder's files are those of the planned folder."""
    from offline_prog.robot.model import RobotModel

    job, folder = kuka

    def no_forward(*_):
        raise AssertionError("a writer computed forward kinematics again")

    monkeypatch.setattr(RobotModel, "forward", no_forward)
    monkeypatch.setattr(job_folder, "BESIDE", (job_folder.trajectory_file,))  # no preview
    monkeypatch.setattr(job_folder, "LAST", ())
    files, _ = write_job_outputs(job, tmp_path / "out")
    assert (tmp_path / "out" / "trajectory.csv").read_text() == (
        folder / "trajectory.csv"
    ).read_text()
    assert {"trajectory", "report", "collisions", "job", "plan"} <= set(files)
    assert any(key.startswith("krl:") for key in files)


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


@pytest.mark.parametrize("name", ["seal_plate_kr16", "seal_job_kr16"])
def test_report_html_names_the_plan_folder_not_the_staged_one(planned_job, name):
    """The page is rendered in the staged ``.offline_prog-<pid>-...`` sibling; it names
    the folder the user opens."""
    from offline_prog.atomic import TEMP_PREFIX

    _, folder = planned_job(name)
    page = (folder / "report.html").read_text()
    assert f"; plan folder {folder.name}</p>" in page
    assert TEMP_PREFIX not in page
