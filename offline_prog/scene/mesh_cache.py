"""Meshes converted once and kept: OBJ copies in metres, CoACD convex pieces, and the
arrays a mesh file is drawn with (``drawn_arrays``: the preview need not import and run
trimesh's loaders again, ~0.2 s of every plan).

Drake uses a mesh's convex hull for collision, so a concave mesh is decomposed into convex
pieces with CoACD (Wei et al., "Approximate Convex Decomposition for 3D Meshes with
Collision-Aware Concavity and Tree Search", SIGGRAPH 2022). Both are cached on disk by
content hash (and scale and CoACD's settings) in ``$OFFLINE_PROG_CACHE`` or
``~/.cache/offline_prog``, written to a temporary name and renamed into place.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from offline_prog.disk_cache import cache_dir, keep

if TYPE_CHECKING:  # trimesh costs ~0.5 s to import; loaded where a mesh is used
    import trimesh


# CoACD's concavity threshold (its default): smaller gives more, tighter pieces.
COACD_THRESHOLD = 0.05
COACD_SEED = 0


def mesh_cache_dir() -> Path:
    """Where converted meshes live (``$OFFLINE_PROG_CACHE`` or ~/.cache/offline_prog)."""
    return cache_dir("meshes")


def as_obj(mesh_file: Path, scale: float) -> Path:
    """An OBJ copy of a mesh file (STL/OBJ/PLY/GLB) in metres, cached by content hash."""
    data = Path(mesh_file).read_bytes()
    key = hashlib.sha256(data + f"{scale!r}".encode()).hexdigest()[:20]
    target = mesh_cache_dir() / f"{key}.obj"
    if not target.exists():
        import trimesh

        mesh = trimesh.load(mesh_file, force="mesh")
        mesh.apply_scale(scale)
        target.parent.mkdir(parents=True, exist_ok=True)
        temp = target.with_suffix(f".{os.getpid()}.tmp")
        temp.write_text(trimesh.exchange.obj.export_obj(mesh), encoding="utf-8")
        os.replace(temp, target)
    return target


def convex_pieces(file: Path, scale: float, mesh: trimesh.Trimesh) -> tuple[Path, ...]:
    """CoACD convex pieces of a mesh as OBJ files [m], cached by content hash and scale.

    Args:
        file: the mesh file (its bytes are the cache key, with scale and CoACD's settings).
        scale: metres per file unit.
        mesh: the file's mesh already scaled to metres.
    """
    import coacd
    import trimesh

    settings = f"{scale!r} coacd {COACD_THRESHOLD!r} {COACD_SEED}".encode()
    key = hashlib.sha256(Path(file).read_bytes() + settings).hexdigest()[:20]
    target = mesh_cache_dir() / f"{key}.coacd"
    if not target.is_dir():
        coacd.set_log_level("error")
        parts = coacd.run_coacd(
            coacd.Mesh(mesh.vertices, mesh.faces), threshold=COACD_THRESHOLD, seed=COACD_SEED
        )
        target.parent.mkdir(parents=True, exist_ok=True)
        temp = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{key}."))
        for i, (vertices, faces) in enumerate(parts):
            piece = trimesh.Trimesh(vertices, faces, process=False)
            (temp / f"piece_{i:03d}.obj").write_text(
                trimesh.exchange.obj.export_obj(piece), encoding="utf-8"
            )
        try:
            os.rename(temp, target)
        except OSError:  # another process cached it first
            shutil.rmtree(temp, ignore_errors=True)
    return tuple(sorted(target.glob("piece_*.obj")))


# The OBJ statement naming a material library (its colours are part of the drawing).
MTLLIB = re.compile(rb"^[ \t]*mtllib[ \t]+(.+?)[ \t]*$", re.M)


def drawn_arrays(
    mesh_file: Path, how: str, convert: Callable[[], dict[str, np.ndarray]]
) -> dict[str, np.ndarray]:
    """``convert()``'s arrays for a mesh file, kept in the cache as an npz keyed by the
    file's bytes, the bytes of the material libraries an OBJ names, and ``how`` (what
    ``convert`` makes of them, with its version). Where the cache cannot be written,
    the arrays are returned all the same; a kept file that cannot be read is made
    again."""
    mesh_file = Path(mesh_file)
    data = mesh_file.read_bytes()
    if mesh_file.suffix.lower() == ".obj":
        for library in _material_libraries(mesh_file, data):
            data += library.read_bytes()
    key = hashlib.sha256(data + how.encode()).hexdigest()[:20]
    target = mesh_cache_dir() / f"{key}.drawn.npz"
    try:
        with np.load(target) as kept:
            return {name: kept[name] for name in kept.files}
    except Exception:  # not kept yet, or not readable (np.load's errors vary): made again
        pass
    arrays = convert()
    keep(target, lambda stream: np.savez(stream, **arrays))  # read-only cache: not kept
    return arrays


def _material_libraries(obj_file: Path, data: bytes) -> list[Path]:
    """The material library files an OBJ's ``mtllib`` statements name that exist (a
    statement may name several, separated by spaces, or one name with spaces)."""
    found: list[Path] = []
    for statement in MTLLIB.findall(data):
        text = statement.decode(errors="replace")
        for name in (text, *text.split()):
            library = obj_file.parent / name
            if library.is_file() and library not in found:
                found.append(library)
    return found
