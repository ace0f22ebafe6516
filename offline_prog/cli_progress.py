"""The command's progress display while a plan runs (on stderr, as ``place``'s bar).

A spinner line with the stage running (the planners' plain messages), and one bar per
counted stage (:class:`~offline_prog.progress.Step`: the seams of a job, the seam-order
search's budget, the links) with its elapsed time, so a long job shows where it is.
Drawn only when stdout is a terminal: piped into a file or a log, the command prints
its summary and nothing else. ``place`` (minutes of work) says where it is in plain
lines when piped (:class:`PlaceProgress`).
"""

from __future__ import annotations

import time

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    SpinnerColumn,
    TextColumn,
    TimeElapsedColumn,
)

from offline_prog.progress import Step


class PlanProgress:
    """A context manager and the planners' ``progress`` callback (message: str)."""

    def __init__(self, console: Console, *, enabled: bool):
        columns = (SpinnerColumn(), TextColumn("{task.description}"), BarColumn())
        columns += (TimeElapsedColumn(),)
        self.bar = Progress(*columns, console=console, transient=True, disable=not enabled)
        self.status = None  # the spinner line's task
        self.counted: dict[str, int] = {}  # stage → its bar's task

    def __enter__(self) -> PlanProgress:
        self.bar.__enter__()
        self.status = self.bar.add_task("planning", total=None)
        return self

    def __exit__(self, *exc) -> None:
        self.bar.__exit__(*exc)

    def __call__(self, message: str) -> None:
        if not isinstance(message, Step):
            self.bar.update(self.status, description=str(message))
            return
        task = self.counted.get(message.stage)
        if task is None:
            task = self.counted[message.stage] = self.bar.add_task(message, total=message.total)
        self.bar.update(task, description=str(message), completed=message.done, total=message.total)


PLACE_LABELS = {
    "screen": "screening (path IK of every tool turn and branch)",
    "rank": "ranking (the cheaper law, a coarse collision look)",
    "plan": "planning candidates in full",
    "outputs": "writing outputs",
}
LINE_INTERVAL_S = 10.0  # a piped progress line at most this often per stage [s]


class PlaceProgress:
    """``place``'s progress: a bar per stage on ``bar_console`` (stderr) when it is a
    terminal; else plain lines on ``line_console`` (stdout, with the summary: stderr
    keeps its one line for an error): one per stage when it starts, every
    LINE_INTERVAL_S while it runs and when it ends, so a log shows it is alive."""

    def __init__(self, bar_console: Console, line_console: Console, *, clock=time.monotonic):
        self.console, self.clock = line_console, clock
        self.live = bar_console.is_terminal
        columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn())
        self.bar = Progress(*columns, console=bar_console, transient=True, disable=not self.live)
        self.tasks: dict[str, int] = {}
        self.said: dict[str, float] = {}
        self.started = clock()

    def __enter__(self) -> PlaceProgress:
        self.bar.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        self.bar.__exit__(*exc)

    def __call__(self, stage: str, done: int, total: int) -> None:
        if stage not in self.tasks:
            self.tasks[stage] = self.bar.add_task(PLACE_LABELS[stage], total=total)
        self.bar.update(self.tasks[stage], completed=done, total=total)
        if self.live:
            return
        now = self.clock()
        first = stage not in self.said
        if first or done >= total or now - self.said[stage] >= LINE_INTERVAL_S:
            self.said[stage] = now
            self.console.print(
                f"place: {PLACE_LABELS[stage]} {done}/{total} ({now - self.started:.0f} s)",
                markup=False,
                highlight=False,
            )
