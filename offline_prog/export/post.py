"""The writer protocol: one post-processor per controller, one method vocabulary.

As RoboDK's post-processors do, each controller's writer (``export/<vendor>/``) is one
class with the same methods, and :func:`write_program` calls them in program order on
the job's program record (``export.record``), built once from the plan's events:

1. ``header(lines)``: the comment header (cell, robot, speeds, this controller's
   conventions from ``conventions()``);
2. ``frames()``: the tool, base and load the program runs with, and any output set up
   at the start;
3. per step, in run order: ``move_joint(move)`` for home and each link, and
   ``seam(run)`` for each seam. A :class:`CartesianPost` (KRL, RAPID) writes a seam as
   ``move_linear(approach)``, ``call_part(process)`` (the seam's points in a called
   routine) and ``move_linear(retract)``; a writer whose controller runs a seam
   otherwise (one called program per seam with its approach and retract, a streamed
   joint trajectory) writes ``seam`` in its own words;
4. ``footer(out_dir)``: the program's end; the files are written and returned.

The I/O events sit on the motions (``Switch``); a writer turns each into text with
``set_output`` (the process output) or ``follow_speed`` (the flow output, which
follows the TCP speed while it is live) and puts it where its language wants it
(``switch`` picks the one).

A writer declares its export options as the fields of an ``Options`` dataclass (a
format's options are exactly these: ``formats.export`` refuses others), the program
name's option and length, whether it needs an OPW arm, its ``PointRule`` (how its
controller interpolates, which decides the seams' points; None: it streams the plan)
and whether the record places the flow's events where the controller sets them.
"""

from __future__ import annotations

import abc
import dataclasses
from pathlib import Path
from typing import ClassVar

from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M
from offline_prog.export.header import header_lines
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.payload import payload
from offline_prog.export.points import PointRule
from offline_prog.export.record import (
    JointMove,
    LinearMove,
    Process,
    ProgramRecord,
    SeamRun,
    Switch,
    program_record,
)
from offline_prog.export.text import identifier
from offline_prog.io_events import Signal


@dataclasses.dataclass(frozen=True)
class PointOptions:
    """Export options of a writer with Cartesian points: the largest deviation of its
    controller's linear interpolation from the continuous plan [m, rad]."""

    chord_tol_m: float = DEFAULT_CHORD_TOL_M
    angle_tol_rad: float = DEFAULT_ANGLE_TOL_RAD


class ControllerPost(abc.ABC):
    """One controller's program writer (see the module docstring).

    Attributes (class):
        FORMAT: the export format's name (``--format``).
        Options: its export options (a frozen dataclass; every field has a default).
        NAME_OPTION, NAME_MAX: the option that names the program and its longest value.
        OPW_ONLY: the controller's conventions need an OPW arm (``robot.params``).
        FLOW_WHERE_SET: see ``record.program_record``.
    """

    FORMAT: ClassVar[str]
    Options: ClassVar[type]
    NAME_OPTION: ClassVar[str] = "name"
    NAME_MAX: ClassVar[int]
    OPW_ONLY: ClassVar[bool] = True
    FLOW_WHERE_SET: ClassVar[bool] = False

    def __init__(
        self, job: JobProgramData, options, *, forced: bool = False, no_payload: bool = False
    ):
        """``no_payload``: state no load (the controller's active load is used).

        Raises ValueError: a program name that is no identifier, a robot the
        controller's conventions do not cover."""
        self.job, self.options, self.forced = job, options, forced
        # The load the program states: the cell's (export.payload), or None.
        self.load = None if no_payload else payload(job.job.payload)
        identifier(
            getattr(options, self.NAME_OPTION), max_chars=self.NAME_MAX, what=self.NAME_OPTION
        )
        self.robot = job.load_robot()
        if self.OPW_ONLY and self.robot.family != "opw":
            raise ValueError(
                f"{self.FORMAT}: robot {job.robot} is not an OPW arm (family "
                f"{self.robot.family}); this controller's conventions need one"
            )

    def point_rule(self) -> PointRule | None:
        """How the controller interpolates between the seam's points (None: the writer
        streams every planned sample)."""
        return None

    @abc.abstractmethod
    def conventions(self, record: ProgramRecord) -> list[str]:
        """Header lines: units, frames and how the program runs the job."""

    @abc.abstractmethod
    def header(self, lines: list[str]) -> None:
        """The comment header, from plain text lines (the writer comments them)."""

    @abc.abstractmethod
    def frames(self) -> None:
        """Tool, base, load and outputs as the program starts."""

    @abc.abstractmethod
    def move_joint(self, move: JointMove) -> None:
        """Home (``move.number`` 0) or a link: joint moves through ``move.targets``."""

    @abc.abstractmethod
    def seam(self, run: SeamRun) -> None:
        """One seam as run: its approach, its points and its retract, with the switches
        on them."""

    @abc.abstractmethod
    def set_output(self, switch: Switch) -> str:
        """The process output's switch, as the text the writer places with its motion."""

    @abc.abstractmethod
    def follow_speed(self, switch: Switch) -> str:
        """The flow output going live (following the TCP speed) or back to idle."""

    @abc.abstractmethod
    def footer(self, out_dir: Path) -> list[Path]:
        """End the program and write its files into out_dir (main program first)."""

    def switch(self, switch: Switch) -> str:
        """The text of an I/O event: ``set_output`` or ``follow_speed``."""
        if switch.event.signal is Signal.DIGITAL:
            return self.set_output(switch)
        return self.follow_speed(switch)


class CartesianPost(ControllerPost):
    """A writer that runs a seam as linear moves: the approach and the retract in the
    main program, the seam's points in a called part."""

    @abc.abstractmethod
    def move_linear(self, move: LinearMove) -> None:
        """An approach or retract, with the switches on it."""

    @abc.abstractmethod
    def call_part(self, process: Process) -> None:
        """A seam's points with the switches on them, in a part the program calls."""

    def seam(self, run: SeamRun) -> None:
        if run.approach is not None:
            self.move_linear(run.approach)
        self.call_part(run.process)
        if run.retract is not None:
            self.move_linear(run.retract)


def write_program(post: ControllerPost, out_dir: Path) -> list[Path]:
    """Build the job's program record for ``post`` and have it translated, in program
    order (see the module docstring); returns the files written."""
    job = post.job
    record = program_record(job, post.point_rule(), flow_where_set=post.FLOW_WHERE_SET)
    lines = header_lines(
        job.job,
        conventions=post.conventions(record),
        forced=post.forced,
        load_written=post.load is not None or payload(job.job.payload) is None,
    )
    post.header(lines)
    post.frames()
    for step in record.steps:
        if isinstance(step, JointMove):
            post.move_joint(step)
        else:
            post.seam(step)
    return post.footer(Path(out_dir))
