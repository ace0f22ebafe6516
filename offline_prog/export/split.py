"""Splitting a seam's statements into called parts at a controller's line limit.

A writer hands over the seam's motions as blocks: each a motion statement with what
must stay with it (KRL's ``TRIGGER`` before its ``LIN``, RAPID's ``TriggIO`` before its
``TriggL``), and what a block needs when it opens a part (the speed the part starts
at: a part carries the state it runs with). :func:`split_blocks` groups consecutive
blocks into parts of at most ``line_limit`` lines, each part counted with its own
opening and closing lines, and the main program calls the parts in turn.

No controller documentation we could find states a line limit for a KRL ``.src``, a
RAPID routine or a FANUC TP program, so no writer splits unless it is given one
(``--line-limit``): the user sets it to the controller's limit.
"""

from __future__ import annotations

from collections.abc import Sequence

MIN_LINE_LIMIT = 20  # the smallest part a writer splits into (the CLI's floor too)


def check_line_limit(line_limit: int | None) -> None:
    """None, or a whole number ≥ MIN_LINE_LIMIT.

    Raises:
        ValueError: naming line_limit.
    """
    if line_limit is not None and not (
        isinstance(line_limit, int) and line_limit >= MIN_LINE_LIMIT
    ):
        raise ValueError(
            f"line_limit={line_limit!r}: need a whole number of at least {MIN_LINE_LIMIT} lines"
        )


def split_blocks(
    sizes: Sequence[int],
    line_limit: int | None,
    *,
    frame: int,
    opening: Sequence[int] | None = None,
) -> list[range]:
    """Consecutive blocks grouped into parts of at most ``line_limit`` lines.

    Args:
        sizes: (n,) lines of each block where it follows another in its part.
        line_limit: most lines of a part; None: one part.
        frame: lines every part has besides its blocks (its opening and closing).
        opening: (n,) lines block k adds when it opens a part (the state the part
            starts with), beyond sizes[k]; default none.

    Returns:
        The parts as ranges of block indices, in order, covering every block.

    Raises:
        ValueError: a block does not fit into a part of line_limit lines.
    """
    n = len(sizes)
    if line_limit is None or n == 0:
        return [range(n)]
    opening = [0] * n if opening is None else opening
    parts, start, used = [], 0, frame + opening[0] + sizes[0]
    for k in range(1, n):
        if used + sizes[k] > line_limit:
            parts.append(range(start, k))
            start, used = k, frame + opening[k] + sizes[k]
        else:
            used += sizes[k]
        if used > line_limit:
            raise ValueError(
                f"line_limit={line_limit}: a motion with its I/O needs {used} lines in a part"
            )
    if frame + opening[0] + sizes[0] > line_limit:
        raise ValueError(f"line_limit={line_limit}: a part needs more lines than that")
    parts.append(range(start, n))
    return parts
