"""Cell editing: the values a session or a placement changes in a cell, and the Cell
they make.

:class:`CellValues` holds SI values (and degrees where the cell file keeps degrees, so a
saved file carries the typed numbers unchanged). :func:`apply` replaces only the
changed fields of the original Cell, so an unchanged transform keeps its own schema
value (an AngleAxis stays one). ``config.cell_text`` writes them into the cell file's
text (session Save, placement's ``placed.yaml``).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from pydrake.common.schema import Rotation, Transform
from pydrake.math import RollPitchYaw

from offline_prog.config.cell import Cell, transform
from offline_prog.config.process_speed import chosen_speed

ROUND_DEG = 9  # decimals kept of angles read from a rotation that is not an Rpy


@dataclasses.dataclass(frozen=True)
class CellValues:
    """The editable values of a cell (one seam of it active).

    Attributes:
        p_IT: tool T's origin in I [m]; rpy_IT_deg: its roll, pitch, yaw [deg].
        p_PE: flange E's origin in the part P [m]; rpy_PE_deg: its roll, pitch, yaw [deg].
        motion_speed: motion.speed [m/s].
        seam_speeds: each seam's own speed [m/s] (None: it runs at motion.speed).
        free_rotation_deg: tool.free_rotation_deg [deg].
        turn_smoothing_mm: tool.turn_smoothing_mm [mm].
        clearance: motion.clearance [m].
        seam: the active seam's index.
    """

    p_IT: tuple[float, float, float]
    rpy_IT_deg: tuple[float, float, float]
    p_PE: tuple[float, float, float]
    rpy_PE_deg: tuple[float, float, float]
    motion_speed: float
    seam_speeds: tuple[float | None, ...]
    free_rotation_deg: float
    turn_smoothing_mm: float
    clearance: float
    seam: int = 0

    @property
    def speed(self) -> float:
        """The active seam's process speed [m/s] (config.process_speed's choice)."""
        return chosen_speed(self.motion_speed, self.seam_speeds, self.seam).v_m_s


def rpy_deg_of(value: Transform) -> tuple[float, float, float]:
    """Roll, pitch, yaw [deg] of a schema transform: an Rpy's own numbers."""
    rotation = value.rotation.value
    if isinstance(rotation, Rotation.Rpy):
        return tuple(float(d) for d in rotation.deg)
    rpy = RollPitchYaw(transform(value).rotation()).vector()
    return tuple(round(float(np.rad2deg(a)), ROUND_DEG) + 0.0 for a in rpy)


def initial_values(cell: Cell) -> CellValues:
    """The state of a cell as loaded (seam 0 active)."""
    seams = cell.seams or [None]
    return CellValues(
        tuple(float(v) for v in cell.tool.X_IT.translation),
        rpy_deg_of(cell.tool.X_IT),
        tuple(float(v) for v in cell.part.X_PE.translation),
        rpy_deg_of(cell.part.X_PE),
        float(cell.motion.speed),
        tuple(None if s is None or s.speed is None else float(s.speed) for s in seams),
        float(cell.tool.free_rotation_deg),
        float(cell.tool.turn_smoothing_mm),
        float(cell.motion.clearance),
    )


def schema_transform(p: tuple, rpy_deg: tuple) -> Transform:
    """The cell file's ``{translation: p, rotation: !Rpy {deg: rpy_deg}}``."""
    rpy = Rotation.Rpy()
    rpy.deg = list(rpy_deg)
    value = Transform()
    value.translation = list(p)
    value.rotation = Rotation()
    value.rotation.value = rpy
    return value


def apply(cell: Cell, initial: CellValues, state: CellValues) -> Cell:
    """The cell with the state's values where they differ from ``initial``."""
    tool, part, motion, seams = cell.tool, cell.part, cell.motion, cell.seams
    if (state.p_IT, state.rpy_IT_deg) != (initial.p_IT, initial.rpy_IT_deg):
        tool = dataclasses.replace(tool, X_IT=schema_transform(state.p_IT, state.rpy_IT_deg))
    if state.free_rotation_deg != initial.free_rotation_deg:
        tool = dataclasses.replace(tool, free_rotation_deg=state.free_rotation_deg)
    if state.turn_smoothing_mm != initial.turn_smoothing_mm:
        tool = dataclasses.replace(tool, turn_smoothing_mm=state.turn_smoothing_mm)
    if (state.p_PE, state.rpy_PE_deg) != (initial.p_PE, initial.rpy_PE_deg):
        part = dataclasses.replace(part, X_PE=schema_transform(state.p_PE, state.rpy_PE_deg))
    if state.motion_speed != initial.motion_speed:
        motion = dataclasses.replace(motion, speed=state.motion_speed)
    if state.clearance != initial.clearance:
        motion = dataclasses.replace(motion, clearance=state.clearance)
    if state.seam_speeds != initial.seam_speeds:
        seams = [
            dataclasses.replace(seam, speed=speed) if speed != old else seam
            for seam, speed, old in zip(seams, state.seam_speeds, initial.seam_speeds, strict=True)
        ]
    return dataclasses.replace(cell, tool=tool, part=part, motion=motion, seams=seams)
