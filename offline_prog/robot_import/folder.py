"""The folder ``robots import`` writes: one it owns, written whole or not at all.

- Every imported folder holds a manifest (:data:`offline_prog.atomic.MANIFEST`) whose
  ``robot_import`` group lists the files written; ``--force`` replaces only a folder
  with that manifest, never a folder inside the installed package (its bundled robots)
  and never through a symbolic link.
- The folder is staged beside the target and swapped in with one rename
  (:func:`offline_prog.atomic.staged_folder`) once URDF, robot.yaml, meshes,
  self-collision matrix and README are all written: Ctrl-C at any stage leaves the
  previous folder (or none) and no temporary one.
- :func:`remark` tells ``robots list`` which folders are broken or incomplete.
"""

from __future__ import annotations

from pathlib import Path

from offline_prog.atomic import read_manifest, write_manifest
from offline_prog.errors import InputError

IMPORT_GROUP = "robot_import"  # the manifest's group of an imported robot folder
PACKAGE_DIR = Path(__file__).resolve().parents[1]  # the installed offline_prog package


def check_target(target: Path, *, force: bool) -> None:
    """Refuse a target folder ``robots import`` may not write.

    Raises:
        InputError: a target inside the installed package, a symbolic link, an
            existing folder without ``--force``, or one this command did not write.
    """
    target = Path(target)
    if target.resolve().is_relative_to(PACKAGE_DIR) or target.absolute().is_relative_to(
        PACKAGE_DIR
    ):
        raise InputError(
            target,
            "--out",
            f"inside the installed package ({PACKAGE_DIR}): import into a folder of your "
            "own and name it in robot.robots_dir or OFFLINE_PROG_ROBOTS",
        )
    if target.is_symlink():
        raise InputError(
            target,
            "--name",
            f"is a symbolic link (to {target.readlink()}): remove it or choose another --name",
        )
    if not target.exists() and not target.is_symlink():
        return
    if not force:
        raise InputError(target, "--name", "folder exists (use --force to replace it)")
    if not target.is_dir() or not is_imported(target):
        raise InputError(
            target,
            "--force",
            "not a folder `robots import` wrote (no robot_import manifest): remove it "
            "yourself or choose another --name",
        )


def is_imported(folder: Path) -> bool:
    """True for a folder ``robots import`` wrote (its manifest names the group)."""
    manifest = read_manifest(folder)
    return manifest is not None and IMPORT_GROUP in manifest.get("files", {})


def mark(folder: Path) -> None:
    """Write the manifest listing every file in ``folder`` (relative, sorted)."""
    folder = Path(folder)
    files = sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())
    write_manifest(folder, {IMPORT_GROUP: files})


def remark(folder: Path) -> str:
    """What is wrong with a robot folder, for ``robots list`` ("" when nothing is):
    it does not load, an import's file is missing, or it has no self-collision matrix."""
    from offline_prog.robot.model import load_robot
    from offline_prog.scene.self_collision import MATRIX_FILE

    folder = Path(folder)
    try:
        load_robot(folder.name, folder.parent)
    except ValueError as error:
        return f"broken: {' '.join(str(error).split())}"
    manifest = read_manifest(folder)
    if manifest is not None and IMPORT_GROUP in manifest.get("files", {}):
        missing = [f for f in manifest["files"][IMPORT_GROUP] if not (folder / f).is_file()]
        if missing:
            return f"incomplete import: missing {', '.join(missing[:3])}"
    if not (folder / MATRIX_FILE).is_file():
        return f"incomplete: no {MATRIX_FILE} (robots self-collision {folder.name} writes it)"
    return ""
