"""The robot folder `robots import` writes (issue 36): replaced with --force only when
an import wrote it, never inside the installed package or through a symbolic link;
written whole or not at all (Ctrl-C while the self-collision matrix is computed
leaves the previous folder); readable by others; naming none of the user's folders;
and `robots list` remarks on broken and incomplete robot folders."""

import os
import shutil
from pathlib import Path

import pytest

from offline_prog.cli import main
from offline_prog.config.robot_search import ENV_VAR
from offline_prog.robot.model import ROBOTS_DIR, load_robot
from offline_prog.robot.record import folder_sha256
from offline_prog.robot_import import run as import_run

KUKA = ROBOTS_DIR / "kuka_kr16_2" / "kuka_kr16_2.urdf"
# The same robot drawn with boxes and cylinders: no meshes to convert (a faster import).
PRIMITIVES = ROBOTS_DIR / "kuka_kr16_2" / "kuka_kr16_2_primitives.urdf"


def _argv(out: Path, name: str, description: Path = PRIMITIVES) -> list[str]:
    return ["robots", "import", str(description), "--name", name, "--out", str(out)] + [
        "--samples",
        "10",
    ]


def _run(capsys, argv: list[str]) -> tuple[int, list[str]]:
    code = main([*argv])
    return code, capsys.readouterr().err.strip().splitlines()


def _tree(folder: Path) -> dict[str, bytes]:
    return {
        p.relative_to(folder).as_posix(): p.read_bytes() for p in folder.rglob("*") if p.is_file()
    }


@pytest.fixture(scope="module")
def imported(tmp_path_factory) -> Path:
    """The bundled KR 16-2's URDF imported once: ``<tmp>/robots/kr16``."""
    out = tmp_path_factory.mktemp("imported") / "robots"
    assert main(_argv(out, "kr16", KUKA)) == 0
    return out / "kr16"


def test_folder_is_readable_and_names_none_of_the_users_folders(imported):
    """Modes as any file the user writes (not mkdtemp's 0700); README, robot.yaml and
    SOURCES.md name the description by package, not by the user's absolute paths."""
    umask = os.umask(0)
    os.umask(umask)
    for path in [imported, *imported.rglob("*")]:
        mode = path.stat().st_mode & 0o777
        assert mode == (0o777 if path.is_dir() else 0o666) & ~umask, (path, oct(mode))
    for path in imported.rglob("*"):
        if path.suffix in (".md", ".yaml", ".urdf", ".json"):
            text = path.read_text()
            for folder in (ROBOTS_DIR.parent, imported.parent, Path.home()):
                assert str(folder) not in text, (path, folder)
    readme = (imported / "README.md").read_text()
    assert "from `package://offline_prog_robots/kuka_kr16_2/kuka_kr16_2.urdf`" in readme


def test_force_replaces_only_what_an_import_wrote(imported, tmp_path, capsys):
    """A folder of the user's (`--out home --name projects --force` removed a .git and a
    thesis), the bundled robots and a symbolic link are refused, one line, untouched;
    an earlier import is replaced."""
    projects = tmp_path / "projects"
    (projects / ".git").mkdir(parents=True)
    (projects / "thesis.tex").write_text("years of work")
    before = _tree(projects)
    code, err = _run(capsys, [*_argv(tmp_path, "projects"), "--force"])
    assert code == 2 and len(err) == 1 and "not a folder `robots import` wrote" in err[0], err
    assert _tree(projects) == before

    bundled = folder_sha256(ROBOTS_DIR / "kuka_kr16_2")
    for name in ("kuka_kr16_2", "new_robot"):
        code, err = _run(capsys, [*_argv(ROBOTS_DIR, name), "--force"])
        assert code == 2 and len(err) == 1 and "inside the installed package" in err[0], err
    assert folder_sha256(ROBOTS_DIR / "kuka_kr16_2") == bundled
    assert not (ROBOTS_DIR / "new_robot").exists()

    elsewhere = tmp_path / "elsewhere" / "kr16"
    shutil.copytree(imported, elsewhere)
    (tmp_path / "linked").symlink_to(elsewhere, target_is_directory=True)
    code, err = _run(capsys, [*_argv(tmp_path, "linked"), "--force"])
    assert code == 2 and len(err) == 1 and "is a symbolic link" in err[0], err
    assert _tree(elsewhere) == _tree(imported)

    again = tmp_path / "robots" / "kr16"
    shutil.copytree(imported, again)
    (again / "robot.yaml").write_text("stale: true\n")
    code, err = _run(capsys, _argv(tmp_path / "robots", "kr16"))
    assert code == 2 and "folder exists (use --force" in err[0], err
    code, err = _run(capsys, [*_argv(tmp_path / "robots", "kr16"), "--force"])
    assert code == 0, err
    assert load_robot("kr16", tmp_path / "robots").family == "opw"
    assert sorted(p.name for p in again.parent.iterdir()) == ["kr16"]


def test_ctrl_c_while_the_matrix_is_computed_leaves_the_previous_folder(
    imported, tmp_path, capsys, monkeypatch
):
    """Everything is staged beside the target and swapped in with one rename: an
    interrupt in the last stage leaves the earlier import (or nothing) and no
    temporary folder; exit 130."""

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(import_run, "write_matrix", interrupted)
    out = tmp_path / "robots"
    shutil.copytree(imported, out / "kr16")
    before = _tree(out / "kr16")
    assert _run(capsys, [*_argv(out, "kr16"), "--force"]) == (130, ["interrupted"])
    assert _run(capsys, _argv(out, "fresh")) == (130, ["interrupted"])
    assert [p.name for p in out.iterdir()] == ["kr16"]
    assert _tree(out / "kr16") == before


def test_robots_list_remarks_on_broken_and_incomplete_folders(
    imported, tmp_path, capsys, monkeypatch
):
    robots = tmp_path / "robots"
    for name in ("good", "broken", "half", "no_matrix", "bad-name"):
        shutil.copytree(imported, robots / name)  # robot.yaml names kr16.urdf
    (robots / "broken" / "robot.yaml").write_text("family: opw\n")
    (robots / "half" / "README.md").unlink()
    (robots / "no_matrix" / "self_collision.yaml").unlink()
    os.remove(robots / "no_matrix" / "offline_prog.manifest.json")
    monkeypatch.setenv(ENV_VAR, str(robots))
    assert main(["robots", "list"]) == 0
    rows = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()}
    assert rows["good"].endswith(f"{ENV_VAR}: {robots}")
    assert "(broken: " in rows["broken"] and "key 'joint_names': missing" in rows["broken"]
    assert "(incomplete import: missing README.md)" in rows["half"]
    assert "(incomplete: no self_collision.yaml" in rows["no_matrix"]
    assert "(broken: " in rows["bad-name"] and "is not a name" in rows["bad-name"]
    assert rows["kuka_kr16_2"].endswith("bundled")
