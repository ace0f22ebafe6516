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
from offline_prog.config.checks import seam_keys


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


def data_files(file: Path, cell: Cell) -> list[Path]:
    """The files a cell names (path points, DXF, meshes), resolved next to ``file``."""
    names = [cell.part.mesh]
    names += [getattr(path, k) for _, path in seam_keys(cell) for k in ("points", "dxf")]
    shapes = list(cell.obstacles) + list(cell.part.geometry) + list(cell.tool.geometry)
    names += [shape.mesh for shape in shapes if shape.shape == "mesh"]
    return sorted({(file.parent / name).resolve() for name in names if name})


def cell_payload(file: Path, cell: Cell) -> CellPayload:
    """Read the cell file and its data files into a payload."""
    paths = [Path(file).resolve(), *data_files(Path(file), cell)]
    root = Path(os.path.commonpath([p.parent for p in paths]))
    files = tuple((p.relative_to(root).as_posix(), p.read_bytes()) for p in paths)
    digest = hashlib.sha256()
    for name, content in files:
        digest.update(name.encode() + b"\0" + content + b"\0")
    return CellPayload(files[0][0], files, digest.hexdigest())


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
