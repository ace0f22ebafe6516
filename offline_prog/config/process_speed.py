"""The process speed of each seam, decided once from the cell.

A seam runs at its own ``seams[k].speed`` where it gives one, else at ``motion.speed``
(a ``path:`` cell's one seam: ``motion.speed``). :func:`process_speed` makes that
choice and nothing else does: the time law's cap and the process model's caps
(``stages.motion_setup``), the speed band check (``job.speed_band``), the labels of an
untimed option, the approach and retract, the report and the program writers read the
:class:`ProcessSpeed` a seam's ``Inputs`` and ``Plan`` carry, and the session's active
seam (``config.edits.CellValues.speed``) reads the same choice. The approach and
retract run at :func:`approach_speed` (``motion.approach_speed``, else the process
speed).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

from offline_prog.config.cell import Cell


@dataclasses.dataclass(frozen=True)
class ProcessSpeed:
    """The speed seam k's process runs at.

    Attributes:
        v_m_s: the speed of the tool along the part (or of the flange, per
            ``motion.speed_reference``) the time law holds and never exceeds [m/s].
        key: the cell key that sets it (``seams[k].speed`` or ``motion.speed``), for
            messages about it.
    """

    v_m_s: float
    key: str


def chosen_speed(motion_speed: float, seam_speeds: Sequence[float | None], k: int) -> ProcessSpeed:
    """Seam k's own speed (``seam_speeds[k]``, None: not given), else ``motion_speed``.

    Args:
        motion_speed: ``motion.speed`` [m/s].
        seam_speeds: each seam's ``speed`` [m/s] or None; a ``path:`` cell: (None,).
        k: the seam's index.
    """
    own = seam_speeds[k]
    if own is None:
        return ProcessSpeed(float(motion_speed), "motion.speed")
    return ProcessSpeed(float(own), f"seams[{k}].speed")


def process_speed(cell: Cell, k: int) -> ProcessSpeed:
    """Seam k's process speed in ``cell`` (a ``path:`` cell has the one seam 0)."""
    seam_speeds = [seam.speed for seam in cell.seams] if cell.seams else [None]
    return chosen_speed(cell.motion.speed, seam_speeds, k)


def approach_speed(cell: Cell, process: ProcessSpeed) -> ProcessSpeed:
    """The speed a seam's approach and retract run at: ``motion.approach_speed``, else
    the seam's process speed ``process`` (the default)."""
    if cell.motion.approach_speed is None:
        return process
    return ProcessSpeed(float(cell.motion.approach_speed), "motion.approach_speed")
