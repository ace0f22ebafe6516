"""Where a cell's robot is looked for: the folders holding robot folders, in order.

1. the cell's ``robot: {robots_dir: DIR}`` (relative to the cell file), if given: it
   must exist and hold the robot (``config.checks`` refuses it otherwise, so a mistyped
   folder never falls back to a robot of the same name further down);
2. each folder of the ``OFFLINE_PROG_ROBOTS`` environment variable (``os.pathsep``
   separated, like ``PATH``), e.g. where ``offline-prog robots import`` wrote robots;
3. the bundled robots (``offline_prog/robots``).

The first folder holding ``<model>/robot.yaml`` wins; ``offline-prog robots list``
shows each robot with the folder it comes from.
"""

from __future__ import annotations

import os
from pathlib import Path

ENV_VAR = "OFFLINE_PROG_ROBOTS"
RECORD_FILE = "robot.yaml"


def search_path(
    default: Path, *, cell_file: Path | None = None, robots_dir: str | None = None
) -> list[Path]:
    """The folders to look in, in order (see the module docstring).

    Args:
        default: the bundled robots' folder (or a caller's own, e.g. a test's).
        cell_file: the cell file, which a relative ``robots_dir`` is read against.
        robots_dir: the cell's ``robot.robots_dir``, or None.
    """
    folders = []
    if robots_dir is not None:
        base = Path(cell_file).parent if cell_file is not None else Path.cwd()
        folders.append(base / Path(robots_dir).expanduser())
    folders += [Path(p).expanduser() for p in os.environ.get(ENV_VAR, "").split(os.pathsep) if p]
    folders.append(Path(default))
    return folders


def find_robot(name: str, folders: list[Path]) -> Path | None:
    """The first ``folder/name`` holding a robot.yaml, or None."""
    if not name or Path(name).name != name or name in (".", ".."):
        return None
    for folder in folders:
        if (folder / name / RECORD_FILE).is_file():
            return folder / name
    return None


def robots_in(folders: list[Path]) -> list[tuple[str, Path, bool]]:
    """(name, folder, used) for every robot folder found, in search order; ``used`` is
    False for one hidden by a robot of the same name found earlier."""
    seen, out = set(), []
    for folder in folders:
        for record in sorted(Path(folder).glob(f"*/{RECORD_FILE}")):
            name = record.parent.name
            out.append((name, folder, name not in seen))
            seen.add(name)
    return out
