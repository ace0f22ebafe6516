"""Calibration in the session: a touches file loaded from the panel, the calibrated
frames beside the session's own, and the switch to them.

The panel reads the file in the browser and sends its text (``POST /touches``): the
session opens no path a page names. The touches are checked at once (a bad file is a
400 with ``offline-prog calibrate``'s one line, nothing changed) and solved on the
planner thread against the cell as the controls set it (``calibration.run``). The
answer is drawn beside the plan shown: the nominal and the calibrated flange paths
(``calibration.path_shift.moved_flange``) and both tool tips; the status lists
``calibrate``'s summary lines. **Use calibrated values** sets the controls to the
calibrated X_IT and X_PE, which re-plans as any control does (Save writes them).
"""

from __future__ import annotations

import dataclasses

from offline_prog.calibration.run import Calibration, solve_touches
from offline_prog.calibration.touches import Touches, parse_touches
from offline_prog.config.cell import transform
from offline_prog.config.edits import CellValues
from offline_prog.errors import InputError
from offline_prog.session import request
from offline_prog.stages import Inputs

MAX_NAME_CHARS = 200
MAX_TEXT_CHARS = request.MAX_TOUCHES_BODY_BYTES


@dataclasses.dataclass(frozen=True)
class SessionCalibration:
    """A solved touches file: its name, the calibration and its summary lines."""

    file: str
    calibration: Calibration
    lines: list[str]


def state_inputs(replanner, state: CellValues) -> Inputs:
    """The whole cell (every seam) as the controls set it."""
    cell = replanner.cell(state)
    return dataclasses.replace(
        replanner.base,
        cell=cell,
        X_IT=transform(cell.tool.X_IT),
        X_PE=transform(cell.part.X_PE),
    )


def read(replanner, state: CellValues, file, text, controller_angles) -> tuple[Inputs, Touches]:
    """The touches the panel sent, checked against the cell of ``state``.

    Raises:
        RequestError: a value of the wrong kind; InputError: the cell has no
            ``calibration:`` block, or the touches are refused (one line).
    """
    name = request.text(file, "file", max_chars=MAX_NAME_CHARS)
    content = request.text(text, "text", max_chars=MAX_TEXT_CHARS)
    angles = request.boolean(controller_angles, "controller_angles")
    inputs = state_inputs(replanner, state)
    if inputs.cell.calibration is None:
        raise InputError(replanner.file, "calibration", "missing: the cell has no calibration:")
    touches = parse_touches(
        name, content, inputs.robot, inputs.cell.calibration, controller_angles=angles
    )
    return inputs, touches


def solve(inputs: Inputs, touches: Touches) -> SessionCalibration:
    """The calibration (planner thread)."""
    from offline_prog.calibration.outputs import summary

    calibration = solve_touches(inputs, touches)
    return SessionCalibration(touches.file, calibration, summary(inputs, calibration))


def calibrated(state: CellValues, found: SessionCalibration) -> CellValues:
    """The controls with the calibrated X_IT and X_PE."""
    c = found.calibration
    return dataclasses.replace(
        state,
        p_IT=c.pose_IT[0],
        rpy_IT_deg=c.pose_IT[1],
        p_PE=c.pose_PE[0],
        rpy_PE_deg=c.pose_PE[1],
    )
