"""The command line: bad flags and user-caused errors are one line and exit 2."""

import argparse
import errno
import os
import re
import shutil
import time

import pytest

from offline_prog.cli import exit_code, main

from conftest import CELLS


def run(capsys, *argv) -> tuple[int, list[str]]:
    """Exit code and stderr lines of ``offline-prog argv``."""
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exit:
        code = exit.code
    return code, capsys.readouterr().err.splitlines()


BAD_FLAGS = [
    ["--chord-tol-mm", "nan"],
    ["--chord-tol-mm", "-1"],
    ["--chord-tol-mm", "inf"],
    ["--chord-tol-mm", "0"],
    ["--angle-tol-deg", "1e400"],
    ["--angle-tol-deg", "x"],
    ["--line-limit", "0"],
    ["--line-limit", "-5"],
    ["--line-limit", "2.5"],
    ["--format", "gcode"],
    ["--bogus"],
]


@pytest.mark.parametrize("flags", BAD_FLAGS)
def test_bad_export_flags_are_one_line_exit_2(capsys, tmp_path, flags):
    argv = ["export", tmp_path, *(["--format", "krl"] if "--format" not in flags else []), *flags]
    code, err = run(capsys, *argv)
    assert code == 2 and len(err) == 1, err
    assert re.fullmatch(r"error: .+ \(see offline-prog( export)? --help\)", err[0]), err


@pytest.mark.parametrize(
    "argv",
    [[], ["plan"], ["plan", "a.yaml", "--port", "0"], ["plan", "a.yaml", "--port", "99999"]],
)
def test_bad_commands_are_one_line_exit_2(capsys, argv):
    code, err = run(capsys, *argv)
    assert code == 2 and len(err) == 1 and err[0].startswith("error: "), err


def test_out_is_an_existing_file(capsys, tmp_path):
    (tmp_path / "out").write_text("x")
    code, err = run(capsys, "plan", CELLS / "seal_plate_kr16.yaml", "--out", tmp_path / "out")
    assert code == 2 and err == [f"error: {tmp_path / 'out'}: --out: exists and is not a folder"]


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes anywhere")
def test_out_in_a_folder_without_write_permission(capsys, tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    code, err = run(capsys, "plan", CELLS / "seal_plate_kr16.yaml", "--out", locked / "out")
    assert code == 2 and len(err) == 1 and "permission denied" in err[0]


def test_disk_full_names_the_path():
    args = argparse.Namespace(command="plan", out=None, cell="c.yaml")
    error = OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), "/data/out/trajectory.csv")
    assert exit_code(error, args) == (2, "error: /data/out/trajectory.csv: No space left on device")
    assert exit_code(RuntimeError("bug"), args)[0] == 3


@pytest.mark.parametrize("damage", ["truncate", "garbage", "empty", "missing"])
def test_damaged_plan_npz_is_exit_2(capsys, planned_folder, tmp_path, damage):
    folder = tmp_path / "plan"
    shutil.copytree(planned_folder("seal_plate_kr16")[1], folder)
    npz = folder / "plan.npz"
    content = npz.read_bytes()
    if damage == "missing":
        npz.unlink()
    else:
        npz.write_bytes(
            {"truncate": content[: len(content) // 2], "garbage": b"PK\x03\x04" + b"\x00" * 99}.get(
                damage, b""
            )
        )
    code, err = run(capsys, "export", folder, "--format", "csv")
    assert code == 2 and len(err) == 1 and str(npz) in err[0], err


def test_export_out_is_an_existing_file(capsys, planned_folder, tmp_path):
    (tmp_path / "file").write_text("x")
    plan_dir = planned_folder("seal_plate_kr16")[1]
    code, err = run(capsys, "export", plan_dir, "--format", "csv", "--out", tmp_path / "file")
    assert code == 2 and len(err) == 1 and str(tmp_path / "file") in err[0], err


@pytest.mark.parametrize("suffix", [".stl", ".ply", ".obj"])
def test_corrupt_part_mesh_is_one_line_exit_2(capsys, tmp_path, suffix):
    from config.test_cell_errors import BASE, write_cell  # tests/config

    cell = write_cell(tmp_path, BASE.replace("part:\n", f"part:\n  mesh: part{suffix}\n", 1))
    (tmp_path / f"part{suffix}").write_bytes(b"solid x\n\x00\xff\xfe garbage" * 50)
    code, err = run(capsys, "plan", cell, "--out", tmp_path / "out")
    assert code == 2 and len(err) == 1 and "part.mesh" in err[0], err
    assert not (tmp_path / "out").exists()


def test_ctrl_c_while_writing_is_exit_130_one_line_and_no_half_folder(
    capsys, tmp_path, monkeypatch
):
    """Ctrl-C during the writes: one line, exit 130, no traceback, and the folder
    holds the previous complete plan (nothing of the interrupted one)."""
    import offline_prog.results.job_folder as job_folder

    out = tmp_path / "out"
    assert run(capsys, "plan", CELLS / "seal_plate_kr16.yaml", "--out", out)[0] == 0
    before = sorted(p.relative_to(out) for p in out.rglob("*"))

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    def slow_preview(*args, **kwargs):  # still drawing, in its child, at the Ctrl-C
        time.sleep(0.5)
        draw_preview(*args, **kwargs)

    draw_preview = job_folder.write_job_preview_html
    monkeypatch.setattr(job_folder, "write_job_preview_html", slow_preview)
    monkeypatch.setattr(job_folder, "write_job_report_html", interrupted)
    code, err = run(capsys, "plan", CELLS / "tape_cylinder_ur10e.yaml", "--out", out)
    assert code == 130 and err == ["interrupted"]
    time.sleep(1.0)  # a preview child left running would have written by now
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no staged sibling left


def test_out_under_proc_is_one_line_exit_2(capsys):
    code, err = run(capsys, "plan", CELLS / "seal_plate_kr16.yaml", "--out", "/proc/offline_prog")
    assert code == 2 and len(err) == 1 and err[0].startswith("error: /proc")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["plan", "a.yaml", "--port", "7000.5"], "argument --port: '7000.5' is not an integer"),
        (["session", "a.yaml", "--port", "x"], "argument --port: 'x' is not an integer"),
        (["robots", "self-collision", "ur10e", "--samples", "1e3"], "'1e3' is not an integer"),
        (["export", "d", "--format", "krl", "--chord-tol-mm", "x"], "'x' is not a number"),
    ],
)
def test_a_flag_that_is_not_a_number_says_so(capsys, argv, message):
    code, err = run(capsys, *argv)
    assert code == 2 and len(err) == 1 and message in err[0], err


@pytest.mark.parametrize("where", ["before", "after"])
def test_debug_before_or_after_the_subcommand_shows_the_traceback(capsys, monkeypatch, where):
    """Every internal error says "rerun with --debug": either place works."""
    import offline_prog.cli as cli

    def bug(*args, **kwargs):
        raise RuntimeError("a bug of ours")

    monkeypatch.setattr(cli, "_run_robots", bug)
    code, err = run(capsys, "robots", "list")
    assert code == 3 and err == ["internal error: RuntimeError: a bug of ours (rerun with --debug)"]
    argv = ["--debug", "robots", "list"] if where == "before" else ["robots", "list", "--debug"]
    with pytest.raises(RuntimeError, match="a bug of ours"):
        main(argv)


def test_self_collision_writes_where_the_user_says_not_into_the_package(
    capsys, tmp_path, monkeypatch
):
    """The robot file shipped in the package stays as it is; the matrix goes to the
    current folder (or --out), and the command says how to plan with it."""
    from offline_prog.robot.model import ROBOTS_DIR
    from offline_prog.scene.self_collision import MATRIX_FILE, read_matrix

    shipped = ROBOTS_DIR / "ur10e" / MATRIX_FILE
    before = shipped.read_bytes(), shipped.stat().st_mtime_ns
    monkeypatch.chdir(tmp_path)
    assert main(["robots", "self-collision", "ur10e", "--samples", "20"]) == 0
    said = capsys.readouterr().out.splitlines()[-1]
    assert said.startswith("wrote self_collision.yaml (20 samples, seed 0)")
    assert said.endswith(f"copy it there: cp self_collision.yaml {shipped}")
    assert len(read_matrix(tmp_path)) == len(read_matrix(shipped.parent))
    assert main(["robots", "self-collision", "ur10e", "--samples", "20", "--out", "m.yaml"]) == 0
    assert (tmp_path / "m.yaml").read_text() == (tmp_path / MATRIX_FILE).read_text()
    assert (shipped.read_bytes(), shipped.stat().st_mtime_ns) == before


def test_the_command_collects_garbage_after_its_imports():
    """``command()`` imports with the collector off, freezes what the imports made and
    turns the collector on again: a long session or placement run collects its cycles."""
    import subprocess
    import sys

    probe = (
        "import gc, sys\n"
        "from offline_prog import cli\n"
        "sys.argv = ['offline-prog', 'robots', 'list']\n"
        "code = cli.command()\n"
        "print(code, gc.isenabled(), gc.get_freeze_count())\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True)
    code, enabled, frozen = done.stdout.split()[-3:]
    assert (code, enabled) == ("0", "True") and int(frozen) > 100_000, done.stdout


def test_version_is_the_packages_one(capsys):
    import tomllib

    import offline_prog

    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    assert capsys.readouterr().out.strip() == f"offline-prog {offline_prog.__version__}"
    project = tomllib.loads((CELLS.parent / "pyproject.toml").read_text(encoding="utf-8"))
    assert project["project"]["dynamic"] == ["version"]  # one source: offline_prog.__version__
    dynamic = project["tool"]["setuptools"]["dynamic"]["version"]
    assert dynamic == {"attr": "offline_prog.__version__"}


def test_the_help_names_every_command_and_robots_subcommand(capsys):
    """``offline-prog --help`` lists each command with what it does; ``robots``' line
    names each of its subcommands (import was missing)."""
    with pytest.raises(SystemExit):
        main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    for command in ("plan", "preview", "session", "place", "seams", "robots", "export"):
        assert f" {command} " in text
    robots_line = text[text.index(" robots robot descriptions") :]
    robots_line = robots_line[: robots_line.index(" export ")]
    for subcommand in ("list", "import", "self-collision"):
        assert subcommand in robots_line, robots_line
