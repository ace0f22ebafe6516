"""The controller's calibrated frames mapped onto the cell's X_IT and X_PE.

The controller is the robot's (``robot.yaml`` ``controller.language``):

- KUKA KRL, ``$config.dat``: the fixed tool is ``BASE_DATA[tool.controller_frame]``
  (external TCP mode: a base in ``$WORLD``), the part ``TOOL_DATA[part.controller_frame]``
  (a tool in ``$FLANGE``). ``$WORLD`` is the robot's ``$ROBROOT`` = B (KSS's default,
  the KRL writer's assumption) and ``$FLANGE`` is E (``export.kuka.kuka.X_KE``), so
  ``X_IT = X_IB · BASE_DATA`` and ``X_PE = (X_KE⁻¹ · TOOL_DATA)⁻¹``.
- ABB RAPID, a module: the stationary ``tooldata tool_<tool.name>`` (tframe in the world
  frame W = B) and the robot-held ``wobjdata wobj_<part.name>`` (uframe · oframe in
  tool0 = E): ``X_IT = X_IB · tframe``, ``X_PE = (uframe · oframe)⁻¹``.

A frame the cell does not number (KUKA) keeps the cell's value; the result says which
were read. Anything else is refused in one line.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from offline_prog.calibration.controller_abb import (
    data_names,
    held_work_object,
    read_rapid,
    stationary_tool,
)
from offline_prog.calibration.controller_kuka import read_config_dat
from offline_prog.calibration.limits import MAX_CONTROLLER_FILE_BYTES
from offline_prog.config.safe_yaml import read_text
from offline_prog.errors import InputError
from offline_prog.export.kuka.kuka import X_KE

READERS = ("krl", "rapid")


@dataclasses.dataclass(frozen=True)
class FromController:
    """The frames read: X_IT, X_PE (4, 4) [m] (the cell's where not read), which
    controller data each came from (None: kept), and notes for the engineer."""

    X_IT: np.ndarray
    X_PE: np.ndarray
    tool_source: str | None
    part_source: str | None
    notes: tuple[str, ...] = ()


def from_controller(file: Path, inputs) -> FromController:
    """Read the controller's frames for the cell of ``inputs`` (stages.Inputs).

    Raises:
        InputError: the robot's controller has no reader, the cell names no frame, the
            file lacks a frame it names, or the file is malformed.
    """
    robot, cell = inputs.robot, inputs.cell
    if robot.language not in READERS:
        raise InputError(
            file,
            "",
            f"the robot's controller ({robot.language or 'none'}) has no frame file this "
            "command reads (KUKA $config.dat, ABB RAPID)",
        )
    text = read_text(Path(file), what="controller file", max_bytes=MAX_CONTROLLER_FILE_BYTES)
    X_IB = inputs.X_IB.GetAsMatrix4()
    X_IT, X_PE = inputs.X_IT.GetAsMatrix4(), inputs.X_PE.GetAsMatrix4()
    if robot.language == "krl":
        return _kuka(str(file), text, cell, X_IB, X_IT, X_PE)
    return _abb(str(file), text, cell, X_IB)


def _kuka(file, text, cell, X_IB, X_IT, X_PE) -> FromController:
    numbers = {"BASE": cell.tool.controller_frame, "TOOL": cell.part.controller_frame}
    if all(n is None for n in numbers.values()):
        raise InputError(
            file,
            "",
            "the cell numbers no controller frame: set tool.controller_frame (its BASE_DATA) "
            "and/or part.controller_frame (its TOOL_DATA)",
        )
    frames, notes, sources = read_config_dat(file, text), [], {}
    expected = {"BASE": "#TCP", "TOOL": "#BASE"}  # external TCP mode
    measured = {"BASE": "the fixed tool as a base", "TOOL": "the part as a tool"}
    for kind, number in numbers.items():
        if number is None:
            continue
        key = (kind, number)
        if key not in frames.frames:
            have = sorted(n for k, n in frames.frames if k == kind)
            raise InputError(
                file,
                "",
                f"no {kind}_DATA[{number}] (the cell's "
                f"{'tool' if kind == 'BASE' else 'part'}.controller_frame); the file has "
                f"{kind}_DATA {have or 'none'}",
            )
        name = frames.names.get(key)
        sources[kind] = f"{kind}_DATA[{number}]" + (f' "{name}"' if name else "")
        kind_type = frames.types.get(key)
        if kind_type is not None and kind_type != expected[kind]:
            notes.append(
                f"{kind}_TYPE[{number}] is {kind_type}, not {expected[kind]} (external TCP "
                f"mode measures {measured[kind]}): check the number"
            )
    if "BASE" in sources:
        X_IT = X_IB @ frames.frames[("BASE", numbers["BASE"])]
    if "TOOL" in sources:
        X_PE = np.linalg.inv(np.linalg.inv(X_KE) @ frames.frames[("TOOL", numbers["TOOL"])])
    return FromController(X_IT, X_PE, sources.get("BASE"), sources.get("TOOL"), tuple(notes))


def _abb(file, text, cell, X_IB) -> FromController:
    tool, wobj = data_names(cell.tool.name, cell.part.name)
    data = read_rapid(file, text)
    for kind, name, table in (("tooldata", tool, data.tooldata), ("wobjdata", wobj, data.wobjdata)):
        if name not in table:
            raise InputError(
                file,
                "",
                f"no PERS {kind} {name} (named after the cell's "
                f"{'tool' if kind == 'tooldata' else 'part'}.name); the file has "
                f"{', '.join(sorted(table)) or 'none'}",
            )
    X_IT = X_IB @ stationary_tool(file, tool, data.tooldata[tool])
    X_PE = np.linalg.inv(held_work_object(file, wobj, data.wobjdata[wobj]))
    return FromController(X_IT, X_PE, f"tooldata {tool}", f"wobjdata {wobj}")
