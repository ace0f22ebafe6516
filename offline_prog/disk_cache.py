"""Where what is computed once and kept between runs lives: ``$OFFLINE_PROG_CACHE`` or
``~/.cache/offline_prog``, one folder per kind (``meshes``: converted meshes and their
convex pieces, ``scene.mesh_cache``; ``fits``: the control-point counts of path fits,
``path.fit_hint``). Every entry is keyed by a hash of what it was computed from, so an
entry is never stale: changed input is another key.
"""

from __future__ import annotations

import os
from pathlib import Path


def cache_dir(kind: str) -> Path:
    """The folder of one kind of kept result (it may not exist yet)."""
    root = os.environ.get("OFFLINE_PROG_CACHE") or Path.home() / ".cache" / "offline_prog"
    return Path(root) / kind
