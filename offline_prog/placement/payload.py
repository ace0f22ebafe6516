"""The cell as it travels to the workers: the cell file and every data file it names,
as bytes, sent once per run (``dask.distributed`` scatters it to every worker).

A worker on another machine has no access to the user's folders; it writes the files
into a private temporary folder, keeping their layout relative to each other, and
loads the cell from there. Robots come with the installed package.
"""

from __future__ import annotations

import atexit
import dataclasses
import hashlib
import os
import shutil
import tempfile
from pathlib import Path

from offline_prog.config.cell import Cell
from offline_prog.config.cell_text import with_values


@dataclasses.dataclass(frozen=True)
class CellPayload:
    """The cell file and its data files.

    Attributes:
        cell_file: the cell file's path relative to ``files``' common root (POSIX).
        files: {path relative to the common root (POSIX): content}.
        digest: sha256 of all of it (a worker keeps one loaded cell per digest).
    """

    cell_file: str
    files: tuple[tuple[str, bytes], ...]
    digest: str


def data_file_keys(cell: Cell) -> dict[str, str]:
    """{dotted key of the cell file: file name as written} of every data file the cell
    names (path points, DXF, meshes, CAD models)."""
    keys = {}
    if cell.part.mesh:
        keys["part.mesh"] = cell.part.mesh
    if cell.part.model:  # STEP or mesh: seams, collision and visual geometry
        keys["part.model"] = cell.part.model
    gripper = cell.gripper
    if gripper is not None and gripper.mesh:
        keys["gripper.mesh"] = gripper.mesh
    paths = [("path", cell.path)] if cell.path else list(enumerate(cell.seams))
    for key, path in paths:
        key = key if isinstance(key, str) else f"seams.{key}"
        for name in ("points", "dxf"):
            if getattr(path, name):
                keys[f"{key}.{name}"] = getattr(path, name)
        if path.cad is not None and path.cad.file:
            keys[f"{key}.cad.file"] = path.cad.file
    for owner, shapes in (
        ("obstacles", cell.obstacles),
        ("part.geometry", cell.part.geometry),
        ("tool.geometry", cell.tool.geometry),
        ("gripper.geometry", gripper.geometry if gripper is not None else []),
    ):
        for i, shape in enumerate(shapes):
            if shape.shape == "mesh" and shape.mesh:
                keys[f"{owner}.{i}.mesh"] = shape.mesh
    return keys


def cell_payload(file: Path, cell: Cell) -> CellPayload:
    """Read the cell file and its data files into a payload. Paths are taken as
    written (symlinks not followed, ``..`` folded); the payload's cell text names
    each data file relative to itself, so an absolute path is carried too."""
    cell_path = Path(os.path.abspath(file))
    keys = data_file_keys(cell)
    found = {key: Path(os.path.abspath(cell_path.parent / name)) for key, name in keys.items()}
    paths = [cell_path, *sorted(set(found.values()))]
    root = Path(os.path.commonpath([p.parent for p in paths]))
    text = with_values(
        cell_path.read_text(encoding="utf-8"),
        {},
        {key: os.path.relpath(path, cell_path.parent) for key, path in found.items()},
    )
    files = [(cell_path.relative_to(root).as_posix(), text.encode())]
    files += [(p.relative_to(root).as_posix(), p.read_bytes()) for p in paths[1:]]
    digest = hashlib.sha256()
    for name, content in files:
        digest.update(name.encode() + b"\0" + content + b"\0")
    return CellPayload(files[0][0], tuple(files), digest.hexdigest())


def unpack(payload: CellPayload) -> Path:
    """Write the payload into a new temporary folder (removed when this process
    exits); the cell file's path there."""
    root = Path(tempfile.mkdtemp(prefix="offline_prog_place_"))
    atexit.register(shutil.rmtree, root, ignore_errors=True)
    for name, content in payload.files:
        target = root / name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(content)
    return root / payload.cell_file
