"""Names that reach controller programs and CSV headers: one rule for all of them.

A seam's name labels a controller program's routine; a robot's name and its joint
names head ``joint_trajectory.csv``'s columns and a program's header. A comma, a space,
a newline or a quote in one would break the CSV or the program, so every such name is
letters, digits and ``_``, starting with a letter, and short.
"""

from __future__ import annotations

import re

NAME_RULE = "letters, digits and _, starting with a letter"
MAX_ROBOT_NAME_CHARS = 40  # a robot folder's and a joint's name


def name_pattern(max_chars: int) -> re.Pattern:
    """The rule for names of at most ``max_chars`` characters (use ``fullmatch``)."""
    return re.compile(rf"[A-Za-z][A-Za-z0-9_]{{0,{max_chars - 1}}}")


def name_problem(name: object, *, max_chars: int) -> str | None:
    """Why ``name`` breaks the rule (one phrase), or None when it follows it."""
    if isinstance(name, str) and name_pattern(max_chars).fullmatch(name):
        return None
    return f"{name!r} is not a name ({NAME_RULE}, at most {max_chars} characters)"
