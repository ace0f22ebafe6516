"""The touches file: one row per touch, its target and the robot's joint angles.

Contract (issue 38)::

    target,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg
    tool_tip,12.5,-80.1,95.3,0.4,40.2,10.0
    corner_a,...

``target`` is ``tool_tip`` (the pointer's tip on the tool's tip), ``tool_axis`` (the
pointer's tip on the point ``calibration.tool_axis_point_mm`` along +z of T) or a name
of ``calibration.part_points`` (that point of the gripped part on the tool's tip). The
angles are degrees in the convention of trajectory.csv's ``q`` columns (the URDF's
joints); with ``controller_angles`` as the controller shows them, mapped through the
robot record's conventions (``RobotModel.urdf_joints``: the ABB/FANUC J2/J3 coupling).
Lines starting with ``#`` and blank lines are skipped. The file is parsed as data
(Python's csv module), never run.

Refused, each in one line naming the file and the row: a wrong header, a row without
its seven fields, a number that is not finite, an unknown target, angles that look
like radians, a touch beyond the robot's joint limits.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import math
from pathlib import Path

import numpy as np

from offline_prog.calibration.limits import (
    LIMIT_SLACK_RAD,
    MAX_TOUCHES,
    MAX_TOUCHES_BYTES,
    RADIANS_LIKE_DEG,
)
from offline_prog.config.calibration_keys import TOOL_AXIS, TOOL_TIP, CalibrationConfig
from offline_prog.config.safe_yaml import read_text
from offline_prog.errors import InputError
from offline_prog.robot.model import RobotModel

HEADER = ("target", "q1_deg", "q2_deg", "q3_deg", "q4_deg", "q5_deg", "q6_deg")


@dataclasses.dataclass(frozen=True)
class Touches:
    """The touches of one file.

    Attributes:
        file: where they came from (for messages).
        targets: (N,) each touch's target: tool_tip, tool_axis or a part point's name.
        lines: (N,) each touch's line in the file (1-based: the header is a line).
        q: (N, 6) URDF joint angles [rad] (trajectory.csv's convention).
    """

    file: str
    targets: tuple[str, ...]
    lines: tuple[int, ...]
    q: np.ndarray

    def __len__(self) -> int:
        return len(self.targets)

    def where(self, i: int) -> str:
        """``line 7 (corner_a)``: how messages name touch i."""
        return f"line {self.lines[i]} ({self.targets[i]})"

    def without(self, i: int) -> Touches:
        """These touches less touch i."""
        keep = [k for k in range(len(self)) if k != i]
        return Touches(
            self.file,
            tuple(self.targets[k] for k in keep),
            tuple(self.lines[k] for k in keep),
            self.q[keep],
        )


def read_touches(
    file: Path, robot: RobotModel, calibration: CalibrationConfig, *, controller_angles=False
) -> Touches:
    """Read and check a touches file (see the module docstring).

    Raises:
        InputError: one line naming the file, the line and what to fix.
    """
    text = read_text(Path(file), what="touches file", max_bytes=MAX_TOUCHES_BYTES)
    return parse_touches(str(file), text, robot, calibration, controller_angles=controller_angles)


def parse_touches(
    file: str,
    text: str,
    robot: RobotModel,
    calibration: CalibrationConfig,
    *,
    controller_angles: bool = False,
) -> Touches:
    """The touches in ``text`` (a file's content; ``file`` names it in messages).

    Raises:
        InputError: see :func:`read_touches`.
    """
    if len(text.encode("utf-8")) > MAX_TOUCHES_BYTES:
        raise InputError(file, "", f"a touches file has at most {MAX_TOUCHES_BYTES:,} bytes")
    rows = [
        (number, line)
        for number, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not rows:
        raise InputError(file, "", f"no header: the first line must be {','.join(HEADER)}")
    number, header = rows[0]
    fields = [f.strip() for f in next(csv.reader([header]))]
    if tuple(fields) != HEADER:
        raise InputError(
            file, f"line {number}", f"the header must be {','.join(HEADER)} (got {header[:80]!r})"
        )
    if len(rows) - 1 > MAX_TOUCHES:
        raise InputError(file, "", f"{len(rows) - 1} touches; at most {MAX_TOUCHES}")
    names = (TOOL_TIP, TOOL_AXIS, *calibration.part_points)
    targets, lines, q_deg = [], [], []
    for number, line in rows[1:]:
        values = [f.strip() for f in next(csv.reader(io.StringIO(line)))]
        if len(values) != len(HEADER):
            raise InputError(
                file, f"line {number}", f"expected {len(HEADER)} fields, got {len(values)}"
            )
        target = values[0]
        if target not in names:
            raise InputError(
                file,
                f"line {number}",
                f"target {target[:40]!r} is not {TOOL_TIP}, {TOOL_AXIS} or a name of "
                f"calibration.part_points (have: {', '.join(calibration.part_points) or 'none'})",
            )
        if target == TOOL_AXIS and calibration.tool_axis_point_mm is None:
            raise InputError(
                file,
                f"line {number}",
                "a tool_axis touch needs calibration.tool_axis_point_mm in the cell",
            )
        targets.append(target)
        lines.append(number)
        q_deg.append([_angle(file, number, text) for text in values[1:]])
    if not targets:
        raise InputError(file, "", "no touches below the header")
    q_deg = np.array(q_deg, dtype=float)
    if np.abs(q_deg).max() < RADIANS_LIKE_DEG:
        raise InputError(
            file,
            "",
            f"every angle is within ±{RADIANS_LIKE_DEG:.1f}: these look like radians; "
            "write degrees (q1_deg ... q6_deg)",
        )
    q_in = np.radians(q_deg)
    q_c = q_in if controller_angles else robot.controller_joints(q_in)
    _check_limits(file, robot, q_c, lines, targets, controller_angles)
    q = robot.urdf_joints(q_c) if controller_angles else q_in
    q.flags.writeable = False
    return Touches(file, tuple(targets), tuple(lines), q)


def _angle(file: str, number: int, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(file, f"line {number}", f"{text[:40]!r} is not a number") from None
    if not math.isfinite(value):
        raise InputError(file, f"line {number}", f"{text[:40]!r} is not a finite number")
    return value


def _check_limits(file, robot: RobotModel, q_c, lines, targets, controller_angles) -> None:
    """Every touch within the joint limits (the controller's axes, as robot.yaml)."""
    low, high = robot.q_lower - LIMIT_SLACK_RAD, robot.q_upper + LIMIT_SLACK_RAD
    outside = (q_c < low) | (q_c > high)
    if not outside.any():
        return
    i, j = np.argwhere(outside)[0]
    convention = (
        "the controller's axes (--controller-angles)"
        if controller_angles
        else "trajectory.csv's q convention; --controller-angles reads the controller's"
    )
    shown = "" if controller_angles or not robot.j23_coupled else " (controller axes)"
    raise InputError(
        file,
        f"line {lines[i]}",
        f"{targets[i]}: axis {j + 1} at {np.degrees(q_c[i, j]):.3f}°{shown} is beyond the "
        f"robot's joint limits [{np.degrees(robot.q_lower[j]):g}, "
        f"{np.degrees(robot.q_upper[j]):g}]° (angles in {convention})",
    )
