"""The tool's stand: an obstacle that stands with the tool (``place.moves_with_tool``)
keeps its foot on the floor wherever the placement puts the tool.

A stand is a box or a cylinder whose own z axis is vertical in I (checked by
:func:`check_stands`). The cell gives it standing: its foot (lower face) at some
height z_f in I, its top under the tool. A candidate moves the tool by
X_TT' = X_IT' · X_IT⁻¹; the stand's top point moves with it, p_top' = X_TT' · p_top,
and its turn about the vertical follows the tool's (the yaw of R_TT'), so it stays
upright; the foot stays at z_f and the stand is lengthened (or cut) to reach the top:
length' = p_top'.z − z_f. A length outside (0, ``place.stand_max_length_mm``] makes the
candidate infeasible (kind "stand").
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix

from offline_prog.config.cell import Cell, ShapeConfig, transform
from offline_prog.errors import InputError

MIN_STAND_M = 0.01  # a stand cut shorter than this is no stand [m]
VERTICAL_TOL = 1e-6  # |1 − |z_O · z_I|| of an upright stand


@dataclasses.dataclass(frozen=True)
class Stand:
    """A stand as the cell gives it.

    Attributes:
        index: its place in ``obstacles``; name: its name; kind: "box" | "cylinder".
        length_m: its height along the vertical [m] (box: size_mm[2]; cylinder:
            length_mm); p_top: (3,) the centre of its top face in I [m];
            foot_z: the height of its foot in I [m]; R_IO: its rotation in I.
    """

    index: int
    name: str
    kind: str
    length_m: float
    p_top: np.ndarray
    foot_z: float
    R_IO: RotationMatrix


@dataclasses.dataclass(frozen=True)
class PlacedStand:
    """A stand at a candidate's placement.

    Attributes:
        stand: the stand as given; X_IO: its new pose in I; length_m: its new length
            [m]; reason: why the length cannot be ("" when it can).
    """

    stand: Stand
    X_IO: RigidTransform
    length_m: float
    reason: str

    def shape(self, shape: ShapeConfig, pose) -> ShapeConfig:
        """The obstacle's ShapeConfig with this pose (a schema Transform) and length."""
        mm = 1e3 * self.length_m
        if self.stand.kind == "box":
            size = [*shape.size_mm[:2], mm]
            return dataclasses.replace(shape, pose=pose, size_mm=size)
        return dataclasses.replace(shape, pose=pose, length_mm=mm)

    def length_key(self) -> str:
        """The cell file's key of the length (``obstacles.<i>.size_mm.2`` or
        ``obstacles.<i>.length_mm``)."""
        box = self.stand.kind == "box"
        return f"obstacles.{self.stand.index}." + ("size_mm.2" if box else "length_mm")


def _length(shape: ShapeConfig) -> float:
    return 1e-3 * (shape.size_mm[2] if shape.shape == "box" else shape.length_mm)


def check_stands(file: Path, cell: Cell, names: list[str], max_length_m: float) -> None:
    """Each obstacle that stands with the tool is a box or cylinder, upright, and not
    longer than the limit as given.

    Raises:
        InputError: naming ``place.moves_with_tool[i]`` or ``place.stand_max_length_mm``.
    """
    by_name = {shape.name: shape for shape in cell.obstacles}
    for i, name in enumerate(names):
        key = f"place.moves_with_tool[{i}]"
        shape = by_name[name]
        if shape.shape not in ("box", "cylinder"):
            raise InputError(
                file,
                key,
                f"{name!r} is a {shape.shape}: a stand keeps its foot on the floor by "
                "its length, so it is a box or a cylinder",
            )
        R = transform(shape.pose).rotation().matrix()
        if abs(1.0 - abs(R[2, 2])) > VERTICAL_TOL:
            raise InputError(
                file, key, f"{name!r} is not upright: its own z axis must be vertical in I"
            )
        if _length(shape) > max_length_m + 1e-12:
            raise InputError(
                file,
                "place.stand_max_length_mm",
                f"{1e3 * max_length_m:g} mm is shorter than {name!r} as given "
                f"({1e3 * _length(shape):g} mm)",
            )


def stands(cell: Cell) -> list[Stand]:
    """The cell's stands (``place.moves_with_tool``) as given."""
    names = set(cell.place.moves_with_tool) if cell.place else set()
    found = []
    for i, shape in enumerate(cell.obstacles):
        if shape.name not in names:
            continue
        X_IO = transform(shape.pose)
        length = _length(shape)
        p = X_IO.translation()
        half = np.array([0.0, 0.0, 0.5 * length])
        foot = float(p[2] - half[2])
        found.append(Stand(i, shape.name, shape.shape, length, p + half, foot, X_IO.rotation()))
    return found


def yaw_of(R: np.ndarray) -> float:
    """The turn about the vertical of I of a rotation (3, 3) [rad]: that of its x axis
    seen from above (its y axis' where x is vertical)."""
    if math.hypot(R[0, 0], R[1, 0]) > 1e-9:
        return math.atan2(R[1, 0], R[0, 0])
    return math.atan2(-R[0, 1], R[1, 1])


def place_stands(
    given: list[Stand], X_IT: RigidTransform, X_IT_new: RigidTransform, max_length_m: float
) -> list[PlacedStand]:
    """The stands at a new tool pose (see the module)."""
    X_TT = X_IT_new @ X_IT.inverse()  # old tool pose → new, in I
    turn = RotationMatrix(RollPitchYaw(0.0, 0.0, yaw_of(X_TT.rotation().matrix())))
    placed = []
    for stand in given:
        top = X_TT.multiply(stand.p_top)
        length = float(top[2] - stand.foot_z)
        centre = np.array([top[0], top[1], stand.foot_z + 0.5 * length])
        reason = ""
        if length < MIN_STAND_M:
            reason = (
                f"{stand.name} would be {1e3 * length:.0f} mm long: the tool stands too low "
                f"above its foot (at least {1e3 * MIN_STAND_M:g} mm)"
            )
        elif length > max_length_m + 1e-12:
            reason = (
                f"{stand.name} would be {1e3 * length:.0f} mm long, beyond "
                f"place.stand_max_length_mm ({1e3 * max_length_m:g} mm)"
            )
        X_IO = RigidTransform(turn @ stand.R_IO, centre)
        placed.append(PlacedStand(stand, X_IO, length, reason))
    return placed
