"""Atomic writes of files and whole folders, and the files a folder's manifest owns.

- :func:`write_atomic`: a file goes to a temporary name beside it and is renamed into
  place, so a crash never leaves a half-written file that looks complete. Files get the
  user's umask (0644 by default), not mkstemp's 0600.
- :func:`staged_folder`: a folder is written as a temporary sibling and swapped in at
  the end (one ``renameat2(RENAME_EXCHANGE)`` on Linux, else two renames), so a crash or
  Ctrl-C leaves the previous complete folder and never a mixture of two runs.
- A manifest (``offline_prog.manifest.json``) lists what we wrote into a folder, so we
  remove our own stale files and nothing else.

Every temporary name is ``.offline_prog-<pid>-...``; :func:`remove_stale` deletes the
ones whose process is gone (after a kill, when no ``finally`` could run).
"""

from __future__ import annotations

import contextlib
import ctypes
import json
import os
import re
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

TEMP_PREFIX = ".offline_prog-"
MANIFEST = "offline_prog.manifest.json"
_TEMP_NAME = re.compile(re.escape(TEMP_PREFIX) + r"(\d+)-")
_RENAME_EXCHANGE = 2  # linux/fs.h
_AT_FDCWD = -100


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def file_mode() -> int:
    """The permission bits a new file gets under the current umask (0o644 for 022)."""
    return 0o666 & ~_umask()


def temp_prefix(purpose: str) -> str:
    """``.offline_prog-<pid>-<purpose>.``: a temporary name this process owns."""
    return f"{TEMP_PREFIX}{os.getpid()}-{purpose}."


def write_atomic(target: Path, content: str | bytes) -> None:
    """Write text or bytes to ``target`` via a temporary file and an atomic rename."""
    with atomic_stream(target) as stream:
        stream.write(content.encode() if isinstance(content, str) else content)


@contextlib.contextmanager
def atomic_stream(target: Path) -> Iterator:
    """A binary stream whose content replaces ``target`` when the block ends without
    an error (else the temporary file is removed and ``target`` is untouched)."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    handle, temp = tempfile.mkstemp(
        dir=target.parent, prefix=temp_prefix(target.name), suffix=".tmp"
    )
    try:
        os.fchmod(handle, file_mode())
        with os.fdopen(handle, "wb") as stream:
            yield stream
            stream.flush()
            os.fsync(stream.fileno())
        os.replace(temp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temp)
        raise


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale(folder: Path) -> None:
    """Delete our temporary files and folders in ``folder`` left by dead processes."""
    with contextlib.suppress(OSError):
        for entry in Path(folder).iterdir():
            match = _TEMP_NAME.match(entry.name)
            if match and not _alive(int(match.group(1))):
                _remove(entry)


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(OSError):
            path.unlink()


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths in one atomic step (Linux renameat2); False where unsupported."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    code = renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE)
    if code == 0:
        return True
    error = ctypes.get_errno()
    if error in (22, 38, 95):  # EINVAL, ENOSYS, EOPNOTSUPP: file system cannot
        return False
    raise OSError(error, os.strerror(error), str(b))


@contextlib.contextmanager
def staged_folder(target: Path) -> Iterator[Path]:
    """An empty temporary sibling of ``target`` to write into; when the block ends
    without an error it replaces ``target`` (whose old content is deleted), else it is
    removed and ``target`` stays as it was."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_stale(target.parent)
    staging = Path(tempfile.mkdtemp(dir=target.parent, prefix=temp_prefix(target.name)))
    try:
        os.chmod(staging, 0o777 & ~_umask())  # mkdtemp makes 0700
        yield staging
        if not target.exists():
            os.rename(staging, target)
        elif not _exchange(staging, target):  # two renames: the old folder kept aside
            old = Path(tempfile.mkdtemp(dir=target.parent, prefix=temp_prefix("old")))
            os.rename(target, old / target.name)
            os.rename(staging, target)
            staging = old
    finally:
        _remove(staging)  # after a swap: the old folder


def read_manifest(folder: Path) -> dict | None:
    """The manifest of a folder we wrote, or None (no manifest, or not ours)."""
    try:
        manifest = json.loads((Path(folder) / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return (
        manifest if isinstance(manifest, dict) and manifest.get("owner") == "offline_prog" else None
    )


def write_manifest(folder: Path, files: dict[str, list[str]]) -> Path:
    """Record the names we wrote into ``folder``, by group (a format, or "plan")."""
    target = Path(folder) / MANIFEST
    text = json.dumps({"owner": "offline_prog", "files": files}, indent=1, sort_keys=True)
    write_atomic(target, text + "\n")
    return target
