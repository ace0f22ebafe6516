"""Lengths in the wrong unit: millimetres where a key takes metres (a slip of 1000×).

A work cell is at most MAX_CELL_EXTENT_M across. A pose farther than that from its
frame's origin, or a mesh larger than that, is refused with what the numbers are in
metres if they were meant as millimetres, as ``motion.speed: 100`` is (the unit is m/s:
100 mm/s is 0.1). The same rule serves ``plan`` (a cell's meshes, part model and poses)
and ``seams`` (a part model alone).
"""

from __future__ import annotations

import numpy as np

from offline_prog.constants import MAX_CELL_EXTENT_M

MM = 1e-3  # metres per millimetre


def _numbers(values) -> str:
    return "[" + ", ".join(f"{v:g}" for v in values) + "]"


def far_translation(p: np.ndarray) -> str | None:
    """Why a translation ``p`` (3,) [m] cannot be one of a cell's poses, or None.

    The reason names the distance and, when ``p`` read as mm is inside a cell, the
    values in metres."""
    p = np.asarray(p, dtype=float)
    distance = float(np.linalg.norm(p))
    if distance <= MAX_CELL_EXTENT_M:
        return None
    hint = ""
    if distance * MM <= MAX_CELL_EXTENT_M:
        hint = f" (the unit is m: {_numbers(p)} mm is {_numbers(p * MM)})"
    return (
        f"{_numbers(p)} is {distance:.4g} m from the origin, more than a cell's "
        f"{MAX_CELL_EXTENT_M:g} m{hint}"
    )


def large_mesh(extent_m: float, *, set_units: str) -> str | None:
    """Why a mesh ``extent_m`` [m] across (in the units it was read in) cannot be a part
    of a cell, or None.

    Args:
        set_units: how the user gives the file's unit, e.g. ``"mesh_units: mm"`` or
            ``"--mesh-units mm"`` (the hint when the file looks like mm).
    """
    if extent_m <= MAX_CELL_EXTENT_M:
        return None
    hint = f" (the file looks like mm: {set_units})" if extent_m * MM <= MAX_CELL_EXTENT_M else ""
    return f"{extent_m:.4g} m across, more than a cell's {MAX_CELL_EXTENT_M:g} m{hint}"
