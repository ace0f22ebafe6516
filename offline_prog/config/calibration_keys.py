"""The cell-file keys of calibration (issue 38's contract) and of the controller's frame
numbers (issue 42's contract)::

    tool:
      controller_frame: 3            # KUKA BASE_DATA[3] (external TCP), FANUC UFRAME 3
    part:
      controller_frame: 1            # KUKA TOOL_DATA[1] (the part on the flange), FANUC UTOOL 1
    calibration:
      pointer_mm: [0, 0, 250]        # nominal tip of a pointer on the flange, in E
      tool_axis_point_mm: 50         # optional: a point 50 mm from the tool's tip along +z of T
      part_points:                   # points of the part, in P (mm), the tool tip can touch
        corner_a: [-200, -150, 0]
        corner_b: [200, -150, 0]
        hole_c: [0, 100, 0]

``offline-prog calibrate`` reads ``calibration:``; ``plan`` ignores it. ABB RAPID names
its frames instead of numbering them: the PERS data are named after ``tool.name`` and
``part.name`` (``offline_prog.calibration.controller_abb``). Every failure is one line
naming the file and key.
"""

import dataclasses
import math
import re
from pathlib import Path

from offline_prog.errors import InputError

# Targets a touch names besides the part points (the touches file's ``target``).
TOOL_TIP, TOOL_AXIS = "tool_tip", "tool_axis"
# A part point's name: it is a CSV field and a JSON key, never program text.
POINT_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_.-]{0,63}")
MAX_POINT_MM = 5000.0  # a pointer or a part point farther than this from its frame's origin
MAX_AXIS_POINT_MM = 1000.0
# Frame numbers per controller language: KUKA BASE_DATA[1..32] (the fixed tool, external
# TCP) and TOOL_DATA[1..16] (the part on the flange), as KUKA's mxAutomation blocks
# number them (Beckhoff TF5120 KRC_ReadBaseData / KRC_ReadToolData). Languages not
# listed take any number from 1.
CONTROLLER_FRAME_RANGES = {"krl": {"tool": (1, 32), "part": (1, 16)}}
CONTROLLER_FRAME_NAMES = {"krl": {"tool": "BASE_DATA", "part": "TOOL_DATA"}}


@dataclasses.dataclass
class CalibrationConfig:
    """``calibration:``: what the touches of ``offline-prog calibrate`` refer to."""

    pointer_mm: list[float] | None = None  # nominal pointer tip on the flange, in E [mm]
    tool_axis_point_mm: float | None = None  # a point this far along +z of T [mm]
    part_points: dict[str, list[float]] = dataclasses.field(default_factory=dict)  # in P [mm]


def _error(file, key, reason) -> InputError:
    return InputError(file, key, reason)


def _point(file: Path, key: str, value: list[float]) -> None:
    if len(value) != 3:
        raise _error(file, key, f"expected [x, y, z] in mm, got {len(value)} numbers")
    if math.hypot(*value) > MAX_POINT_MM:
        raise _error(file, key, f"more than {MAX_POINT_MM:g} mm from the origin (a unit slip?)")


def check_calibration(file: Path, calibration: CalibrationConfig | None) -> None:
    """The ``calibration:`` block's values (the types are checked before)."""
    if calibration is None:
        return
    if calibration.pointer_mm is not None:
        _point(file, "calibration.pointer_mm", calibration.pointer_mm)
    d = calibration.tool_axis_point_mm
    if d is not None and not 0.0 < d <= MAX_AXIS_POINT_MM:
        raise _error(
            file,
            "calibration.tool_axis_point_mm",
            f"must be > 0 and ≤ {MAX_AXIS_POINT_MM:g} mm, got {d:g}",
        )
    for name, value in calibration.part_points.items():
        key = f"calibration.part_points.{name}"
        if name in (TOOL_TIP, TOOL_AXIS) or not POINT_NAME.fullmatch(str(name)):
            raise _error(
                file,
                key,
                f"{str(name)[:40]!r} is not a point name (a letter, then letters, digits, "
                f"_ . -; not {TOOL_TIP} or {TOOL_AXIS})",
            )
        _point(file, key, value)


def check_controller_frames(file: Path, cell, language: str | None) -> None:
    """``tool.controller_frame`` and ``part.controller_frame``: numbers from 1, within
    the robot's controller's range (``CONTROLLER_FRAME_RANGES``)."""
    for owner in ("tool", "part"):
        number = getattr(cell, owner).controller_frame
        if number is None:
            continue
        low, high = CONTROLLER_FRAME_RANGES.get(language, {}).get(owner, (1, 10_000))
        if not low <= number <= high:
            data = CONTROLLER_FRAME_NAMES.get(language, {}).get(owner, "frame")
            whose = f" of the robot's {language} controller" if language else ""
            raise _error(
                file,
                f"{owner}.controller_frame",
                f"{number} is not a {data} number{whose} (use {low}..{high})",
            )
