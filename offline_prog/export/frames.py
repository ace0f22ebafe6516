"""The controller's calibrated frames, by number: which of the controller's frames a
program runs with (issue 42's contract keys ``tool.controller_frame`` and
``part.controller_frame``), and the nominal values of those frames from the cell.

A program names the frames and writes its positions relative to them, so that a
calibration on the controller moves the whole program with it; the nominal values
(the cell's X_BT and X_EP) go into one separate file per export that the technician may
load once (``<name>_frm`` on KUKA, ``<module>_frames.mod`` on ABB, ``<NAME>_FRAMES.ls``
on FANUC), never into a motion program. A number the cell does not give is
``DEFAULT_FRAME``, and the header says so.
"""

from __future__ import annotations

import dataclasses

from offline_prog.export.program import ProgramData

DEFAULT_FRAME = 1  # the frame number a program uses when the cell gives none


@dataclasses.dataclass(frozen=True)
class ControllerFrames:
    """The numbers of the fixed tool T (KUKA ``BASE_DATA``, FANUC ``UFRAME``) and of the
    part P on the flange (KUKA ``TOOL_DATA``, FANUC ``UTOOL``); ``defaulted``: the cell
    keys that were not given (their frame is DEFAULT_FRAME)."""

    tool: int
    part: int
    defaulted: tuple[str, ...] = ()

    def note(self, tool_name: str, part_name: str) -> str:
        """One header line: how the cell's numbers map onto the controller's frames,
        ``tool_name`` / ``part_name`` being the controller's names of the two."""
        line = (
            f"Frames: tool.controller_frame {self.tool} = {tool_name}, "
            f"part.controller_frame {self.part} = {part_name}"
        )
        if self.defaulted:
            line += (
                f" ({' and '.join(self.defaulted)} not given in the cell: frame "
                f"{DEFAULT_FRAME} by default)"
            )
        return line + "."


def controller_frames(data: ProgramData) -> ControllerFrames:
    """The frame numbers of a plan (``ProgramData.controller_frames``, from the cell)."""
    given = data.controller_frames or {}
    numbers, defaulted = {}, []
    for owner in ("tool", "part"):
        number = given.get(owner)
        if number is None:
            defaulted.append(f"{owner}.controller_frame")
            number = DEFAULT_FRAME
        numbers[owner] = int(number)
    return ControllerFrames(numbers["tool"], numbers["part"], tuple(defaulted))
