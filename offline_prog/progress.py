"""Progress messages of the planners.

A planner's ``progress`` callback takes a str: the description of the stage starting
(what ``StageTimer`` passes). A :class:`Step` is such a str that also says how far a
counted stage has come (``done`` of ``total``: seams planned, links found, the order
search's budget spent), so that a display can draw a bar; a callback that only shows
or records the text needs no change.
"""

from __future__ import annotations


class Step(str):
    """A progress message (the str) of stage ``stage``, ``done`` of ``total`` done."""

    stage: str
    done: int
    total: int

    def __new__(cls, text: str, *, stage: str, done: int, total: int) -> Step:
        step = super().__new__(cls, text)
        step.stage, step.done, step.total = stage, int(done), int(total)
        return step
