"""The command's progress display while a plan runs (on stderr, as ``place``'s bar).

A spinner line with the stage running (the planners' plain messages), and one bar per
counted stage (:class:`~offline_prog.progress.Step`: the seams of a job, the seam-order
search's budget, the links) with its elapsed time, so a long job shows where it is.
Drawn only when stdout is a terminal: piped into a file or a log, the command prints
its summary and nothing else.
"""

from __future__ import annotations

from rich.console import Console
from rich.progress import BarColumn, Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

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
