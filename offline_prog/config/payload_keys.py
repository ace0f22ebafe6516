"""Semantic checks of the payload keys (``gripper:`` and the part's mass properties)
that their types alone cannot express; every failure is an InputError naming the file
and key. The gripper's shapes are checked with the cell's others (``checks``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pydrake.multibody.tree import RotationalInertia

from offline_prog.config.cell import Cell
from offline_prog.constants import MAX_CENTER_OF_MASS_MM, MAX_PAYLOAD_KG, UNIT_SCALE
from offline_prog.errors import InputError

# A rotational inertia [kg m²] beyond this is a typo (g mm² for kg m²): a 1000 kg
# load spread over a 5 m sphere has about 1e4.
MAX_INERTIA_KGM2 = 1e4


def check_payload(file: Path, cell: Cell, check_data_file) -> None:
    """Masses within [0, MAX_PAYLOAD_KG], centres of mass 3 numbers within reach,
    inertias 6 numbers of a physically possible body (and only with a mass), the
    gripper's mesh a file in m or mm."""
    bodies = [("part", cell.part)]
    gripper = cell.gripper
    if gripper is not None:
        bodies.append(("gripper", gripper))
        if gripper.mesh_units not in UNIT_SCALE:
            raise InputError(
                file, "gripper.mesh_units", f"{gripper.mesh_units!r} is not a unit (use m or mm)"
            )
        if gripper.mesh is not None:
            check_data_file(file, "gripper.mesh", file.parent / gripper.mesh)
    for owner, body in bodies:
        mass, com = body.mass_kg, body.center_of_mass_mm
        if mass is not None and not 0.0 <= mass <= MAX_PAYLOAD_KG:
            raise InputError(file, f"{owner}.mass_kg", f"must be within [0, {MAX_PAYLOAD_KG:g}] kg")
        if com is not None and not (len(com) == 3 and np.linalg.norm(com) <= MAX_CENTER_OF_MASS_MM):
            raise InputError(
                file,
                f"{owner}.center_of_mass_mm",
                f"expected [x, y, z] within {MAX_CENTER_OF_MASS_MM:g} mm, got {com}",
            )
        if body.inertia_kgm2 is not None:
            _check_inertia(file, f"{owner}.inertia_kgm2", body.inertia_kgm2)
            if mass is None:
                raise InputError(file, f"{owner}.inertia_kgm2", f"needs {owner}.mass_kg")


def _check_inertia(file: Path, key: str, values: list[float]) -> None:
    """[Ixx, Iyy, Izz, Ixy, Ixz, Iyz] [kg m²]: finite, bounded, a possible body's."""
    if not (
        len(values) == 6
        and all(np.isfinite(v) and abs(v) <= MAX_INERTIA_KGM2 for v in values)
        and RotationalInertia(*map(float, values)).CouldBePhysicallyValid()
    ):
        raise InputError(
            file,
            key,
            f"expected [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] kg m² about the centre of mass "
            f"(moments ≥ 0, each at most the sum of the other two, within "
            f"{MAX_INERTIA_KGM2:g}), got {values}",
        )
