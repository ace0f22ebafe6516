"""ABB RAPID: the stationary tool and the robot-held work object a technician
calibrated on the controller, read from a module's text as data (a small parser for
RAPID aggregates; nothing is run).

The declarations (RAPID Technical Reference Manual 3HAC050917, ``tooldata``,
``wobjdata``, ``pose``, ``orient``)::

    PERS tooldata tool_nozzle := [FALSE,[[1000.1,-0.3,499.8],[0.7071,0.7071,0,0]],
                                  [5,[0,0,100],[1,0,0,0],0,0,0]];
    PERS wobjdata wobj_plate := [TRUE,TRUE,"",[[0,0,-100.2],[0,1,0,0]],
                                 [[0,0,0],[1,0,0,0]]];

``tooldata`` = [robhold, tframe, tload]: robhold FALSE is a stationary tool, whose
tframe is the tool in the world frame. ``wobjdata`` = [robhold, ufprog, ufmec, uframe,
oframe]: robhold TRUE is a work object the robot holds (used with a stationary tool),
uframe given in the wrist frame tool0, oframe in uframe (ROS-I ``abb_rapid_msgs``
WObjData; ABB MultiMove manual 3HAC021272 §6.3). A pose is [[x, y, z] mm, [q1, q2, q3,
q4]] with q1 the scalar part (rc_visard "ABB pose format": q = (Q2, Q3, Q4, Q1) in x, y,
z, w order).

The names are derived from the cell (issue 42): ``tool_<tool.name>`` and
``wobj_<part.name>``, as the RAPID writer declares them (``export.text.identifier_from``).
Comments (``!`` to the end of the line) are dropped; ``PERS``, ``TASK PERS`` and
``LOCAL PERS`` declarations are read (a technician's calibration lives in persistent
data). A malformed aggregate, a quaternion that is not a unit one, or the wrong
robhold is refused in one line.
"""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RotationMatrix

from offline_prog.errors import InputError
from offline_prog.export.abb.rapid import NAME_MAX
from offline_prog.export.text import identifier_from

_DECLARATION = re.compile(
    r"(?:\b(?:LOCAL|TASK)\s+)?\bPERS\s+(tooldata|wobjdata)\s+([A-Za-z]\w*)\s*:=\s*([^;]*);",
    re.IGNORECASE,
)
_TOKEN = re.compile(
    r'\s*(?:(\[)|(\])|(,)|("[^"]*")|(TRUE|FALSE)\b|([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?))',
    re.IGNORECASE,
)
QUATERNION_TOLERANCE = 1e-3  # |q| may differ from 1 by this (written to a few digits)


@dataclasses.dataclass(frozen=True)
class RapidData:
    """The tooldata and wobjdata of a module: {name: the parsed aggregate}."""

    tooldata: dict[str, list]
    wobjdata: dict[str, list]


def data_names(tool_name: str, part_name: str) -> tuple[str, str]:
    """(tooldata, wobjdata) names of a cell's tool and part, as the RAPID writer
    declares them."""
    return (
        identifier_from("tool", tool_name, max_chars=NAME_MAX),
        identifier_from("wobj", part_name, max_chars=NAME_MAX),
    )


def _without_comments(text: str) -> str:
    out = []
    for line in text.splitlines():
        quoted = False
        for k, char in enumerate(line):
            if char == '"':
                quoted = not quoted
            elif char == "!" and not quoted:
                line = line[:k]
                break
        out.append(line)
    return "\n".join(out)


def parse_aggregate(text: str):
    """A RAPID aggregate as nested lists of floats, booleans and strings.

    Raises:
        ValueError: anything else (an expression, a name, unbalanced brackets).
    """
    stack, position, value = [[]], 0, None
    while position < len(text.rstrip()):
        match = _TOKEN.match(text, position)
        if match is None:
            raise ValueError(f"unexpected {text[position : position + 20].strip()!r}")
        position = match.end()
        opening, closing, comma, string, boolean, number = match.groups()
        if opening:
            stack.append([])
        elif closing:
            if len(stack) < 2:
                raise ValueError("unbalanced ]")
            done = stack.pop()
            stack[-1].append(done)
        elif comma:
            continue
        elif string is not None:
            stack[-1].append(string[1:-1])
        elif boolean is not None:
            stack[-1].append(boolean.upper() == "TRUE")
        else:
            value = float(number)
            if not math.isfinite(value):
                raise ValueError(f"{number} is not finite")
            stack[-1].append(value)
    if len(stack) != 1 or len(stack[0]) != 1 or not isinstance(stack[0][0], list):
        raise ValueError("not one [...] aggregate")
    return stack[0][0]


def read_rapid(file: str, text: str) -> RapidData:
    """Every PERS tooldata and wobjdata of a module's text.

    Raises:
        InputError: a declaration whose value is not an aggregate, or a name given twice.
    """
    tooldata, wobjdata = {}, {}
    code = _without_comments(text)
    # Declarations are found in the code with its strings blanked (a string may hold
    # anything, "PERS tooldata ..." too); each value is then read from the code itself.
    blanked = re.sub(r'"[^"\n]*"', lambda m: '"' + " " * (len(m.group()) - 2) + '"', code)
    for match in _DECLARATION.finditer(blanked):
        kind, name = match.group(1).lower(), match.group(2)
        value = code[match.start(3) : match.end(3)]
        table = tooldata if kind == "tooldata" else wobjdata
        if name in table:
            raise InputError(file, name, f"PERS {kind} {name} is declared twice")
        try:
            table[name] = parse_aggregate(value)
        except ValueError as error:
            raise InputError(file, name, f"PERS {kind} {name}: {error}") from None
    return RapidData(tooldata, wobjdata)


def pose_matrix(file: str, what: str, pose) -> np.ndarray:
    """X (4, 4) [m] of a RAPID pose [[x, y, z] mm, [q1, q2, q3, q4]].

    Raises:
        InputError: not a pose, or a quaternion farther than QUATERNION_TOLERANCE from unit.
    """
    if not (
        isinstance(pose, list)
        and len(pose) == 2
        and all(isinstance(v, list) for v in pose)
        and len(pose[0]) == 3
        and len(pose[1]) == 4
        and all(isinstance(v, float) for v in pose[0] + pose[1])
    ):
        raise InputError(file, what, "expected a pose [[x, y, z], [q1, q2, q3, q4]]")
    q = np.array(pose[1])
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise InputError(file, what, f"the quaternion's norm is {norm:.4f}, not 1")
    X = np.eye(4)
    X[:3, :3] = RotationMatrix(Quaternion(q / norm)).matrix()  # [w, x, y, z]
    X[:3, 3] = np.array(pose[0]) * 1e-3
    return X


def stationary_tool(file: str, name: str, value) -> np.ndarray:
    """tframe (4, 4) [m] of a stationary tooldata (robhold FALSE), in the world frame.

    Raises:
        InputError: not a tooldata, or robhold TRUE (a tool the robot holds).
    """
    if not (isinstance(value, list) and len(value) == 3 and isinstance(value[0], bool)):
        raise InputError(file, name, "expected tooldata [robhold, tframe, tload]")
    if value[0]:
        raise InputError(
            file,
            name,
            "robhold is TRUE: a tool the robot holds; the cell's fixed tool is a stationary "
            "tool (robhold FALSE)",
        )
    return pose_matrix(file, f"{name}.tframe", value[1])


def held_work_object(file: str, name: str, value) -> np.ndarray:
    """uframe · oframe (4, 4) [m] of a robot-held wobjdata (robhold TRUE): the object
    frame in the wrist frame tool0.

    Raises:
        InputError: not a wobjdata, or robhold FALSE (a work object fixed in the cell).
    """
    if not (isinstance(value, list) and len(value) == 5 and isinstance(value[0], bool)):
        raise InputError(file, name, "expected wobjdata [robhold, ufprog, ufmec, uframe, oframe]")
    if not value[0]:
        raise InputError(
            file,
            name,
            "robhold is FALSE: a work object fixed in the cell; the part the robot carries "
            "past a stationary tool is held (robhold TRUE)",
        )
    return pose_matrix(file, f"{name}.uframe", value[3]) @ pose_matrix(
        file, f"{name}.oframe", value[4]
    )
