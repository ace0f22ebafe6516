"""KUKA ``$config.dat``: the frames a technician calibrated on the controller, read as
data (regular expressions over the text; nothing is run).

The file holds the calibrated frames as KRL aggregates (KSS 8), one per line::

    BASE_DATA[3]={X 1000.12,Y -0.35,Z 499.8,A 0.1,B -0.02,C 90.05}
    BASE_NAME[3,]="NOZZLE"
    BASE_TYPE[3]=#TCP
    TOOL_DATA[1]={X 0.0,Y 0.0,Z -100.2,A 0.0,B 0.0,C 180.0}

``BASE_DATA[n]`` (n = 1..32) is a frame in ``$WORLD``, ``TOOL_DATA[m]`` (m = 1..16) a
frame in ``$FLANGE`` (KUKA's mxAutomation blocks KRC_ReadBaseData / KRC_ReadToolData,
Beckhoff TF5120). X, Y, Z in mm; A, B, C in degrees with R = Rz(A)·Ry(B)·Rx(C), KUKA's
Z-Y′-X″ Euler angles (Basler rc_cube, "KUKA XYZ-ABC format"). In external-TCP mode the
fixed tool is measured as a base (``BASE_TYPE[n]=#TCP``) and the robot-held workpiece
as a tool (``TOOL_TYPE[m]=#BASE``); a type that says otherwise is reported as a note.

Comments (``;`` to the end of the line) are dropped first; names, types and frames are
matched case-insensitively (KRL is). A frame given twice, an aggregate without exactly
X, Y, Z, A, B, C, or a number that is not finite is refused in one line naming the
file's line.
"""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.errors import InputError

_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
_FRAME = re.compile(
    r"^\s*(?:DECL\s+(?:GLOBAL\s+)?FRAME\s+)?\$?(BASE|TOOL)_DATA\s*\[\s*(\d+)\s*\]\s*=\s*(.*?)\s*$",
    re.IGNORECASE,
)
_AGGREGATE = re.compile(r"^\{(.*)\}$")
_COMPONENT = re.compile(rf"^\s*([A-Za-z])\s+({_NUMBER})\s*$")
_NAME = re.compile(r'^\s*\$?(BASE|TOOL)_NAME\s*\[\s*(\d+)\s*,\s*\]\s*=\s*"([^"]*)"', re.IGNORECASE)
_TYPE = re.compile(r"^\s*\$?(BASE|TOOL)_TYPE\s*\[\s*(\d+)\s*\]\s*=\s*#(\w+)", re.IGNORECASE)
AXES = "XYZABC"


@dataclasses.dataclass(frozen=True)
class KukaFrames:
    """The frames of a ``$config.dat``: {(kind "BASE" | "TOOL", number): X (4, 4) [m]},
    and the names and types the file gives them."""

    frames: dict[tuple[str, int], np.ndarray]
    names: dict[tuple[str, int], str]
    types: dict[tuple[str, int], str]
    lines: dict[tuple[str, int], int]


def frame_matrix(values_mm_deg) -> np.ndarray:
    """X (4, 4) [m] of KUKA's X, Y, Z [mm], A, B, C [deg] (R = Rz(A)·Ry(B)·Rx(C))."""
    x, y, z, a, b, c = values_mm_deg
    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler("ZYX", [a, b, c], degrees=True).as_matrix()
    X[:3, 3] = np.array([x, y, z]) * 1e-3
    return X


def _without_comment(line: str) -> str:
    """The line up to a ``;`` outside a string."""
    quoted = False
    for k, char in enumerate(line):
        if char == '"':
            quoted = not quoted
        elif char == ";" and not quoted:
            return line[:k]
    return line


def _aggregate(file: str, number: int, kind: str, index: int, text: str) -> list[float]:
    """X, Y, Z, A, B, C of ``{X ..,Y ..,Z ..,A ..,B ..,C ..}`` (any order)."""
    what = f"{kind}_DATA[{index}]"
    shape = _AGGREGATE.match(text)
    values = {}
    for part in shape.group(1).split(",") if shape else [None]:
        match = _COMPONENT.match(part) if part is not None else None
        if match is None:
            raise InputError(
                file,
                f"line {number}",
                f"{what} is not {{X ..,Y ..,Z ..,A ..,B ..,C ..}} (got {text[:60]!r})",
            )
        letter = match.group(1).upper()
        if letter not in AXES or letter in values:
            raise InputError(file, f"line {number}", f"{what}: component {letter} unexpected")
        value = float(match.group(2))
        if not math.isfinite(value):
            raise InputError(file, f"line {number}", f"{what}: {letter} is not finite")
        values[letter] = value
    missing = [letter for letter in AXES if letter not in values]
    if missing:
        raise InputError(file, f"line {number}", f"{what} lacks {', '.join(missing)}")
    return [values[letter] for letter in AXES]


def read_config_dat(file: str, text: str) -> KukaFrames:
    """Every ``BASE_DATA``/``TOOL_DATA`` frame of a ``$config.dat`` text, with names
    and types.

    Raises:
        InputError: a malformed or repeated frame (one line naming the file's line).
    """
    frames, names, types, lines = {}, {}, {}, {}
    for number, raw in enumerate(text.splitlines(), start=1):
        line = _without_comment(raw)
        if match := _FRAME.match(line):
            key = (match.group(1).upper(), int(match.group(2)))
            if key in frames:
                raise InputError(
                    file,
                    f"line {number}",
                    f"{key[0]}_DATA[{key[1]}] is given twice (also line {lines[key]})",
                )
            frames[key] = frame_matrix(_aggregate(file, number, *key, match.group(3)))
            lines[key] = number
        elif match := _NAME.match(line):
            names[(match.group(1).upper(), int(match.group(2)))] = match.group(3)
        elif match := _TYPE.match(line):
            types[(match.group(1).upper(), int(match.group(2)))] = "#" + match.group(3).upper()
    return KukaFrames(frames, names, types, lines)
