"""Where what is computed once and kept between runs lives: ``$OFFLINE_PROG_CACHE`` or
``~/.cache/offline_prog``, one folder per kind (``meshes``: converted meshes and their
convex pieces, ``scene.mesh_cache``; ``fits``: the control-point counts of path fits,
``path.fit_hint``). Every entry is keyed by a hash of what it was computed from, so an
entry is never stale: changed input is another key.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO


def cache_dir(kind: str) -> Path:
    """The folder of one kind of kept result (it may not exist yet)."""
    root = os.environ.get("OFFLINE_PROG_CACHE") or Path.home() / ".cache" / "offline_prog"
    return Path(root) / kind


def keep(target: Path, write: Callable[[BinaryIO], None]) -> None:
    """Write ``target`` in the cache through ``write(stream)``: whole (a temporary file
    renamed into place) or not at all. Where the cache cannot be written (read-only, a
    full disk) nothing is kept and no temporary file is left: it only costs time."""
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        handle, temp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    except OSError:
        return
    try:
        with os.fdopen(handle, "wb") as stream:
            write(stream)
        os.replace(temp, target)
    except OSError:
        with contextlib.suppress(OSError):
            os.unlink(temp)
