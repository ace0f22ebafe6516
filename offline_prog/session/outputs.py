"""Save and Export of a session: the changed cell file, and the plan folder of it.

Save writes ``<stem>-<n>.yaml`` next to the original (the first free n; a file is never
replaced), the original's text with the changed values written in (``cell_text``),
and checks that it loads to the session's cell. Export saves the cell first (the plan
folder names it) and writes the folder exactly as ``offline-prog plan`` does, with the
same writer: the whole job (a ``path:`` cell is a one-seam job: home, approach, seam,
retract, home), planned from the saved file.
"""

from __future__ import annotations

import os
from pathlib import Path

from pydrake.common.yaml import yaml_dump_typed

from offline_prog.config.cell import Cell, load_cell
from offline_prog.config.safe_yaml import read_text
from offline_prog.plan import plan_job
from offline_prog.results.job_folder import write_job_outputs
from offline_prog.session.cell_text import edited_text
from offline_prog.session.state import SessionState

MAX_SAVES = 10_000


def free_name(file: Path) -> Path:
    """``<stem>-<n>.yaml`` next to ``file``, the first n ≥ 1 not taken."""
    for n in range(1, MAX_SAVES):
        candidate = file.with_name(f"{file.stem}-{n}{file.suffix}")
        if not candidate.exists():
            return candidate
    raise FileExistsError(f"{file.parent}: {MAX_SAVES} saved copies of {file.name}")


def save_cell(original: Path, initial: SessionState, state: SessionState, cell: Cell) -> Path:
    """Write ``cell`` (``state``'s, edited from ``initial``) next to ``original``; returns
    the new file.

    Raises:
        OSError: the folder is not writable.
        RuntimeError: the written file does not load to ``cell`` (it is removed).
    """
    text = edited_text(read_text(original), initial, state)
    while True:
        target = free_name(original)
        try:
            with open(target, "x", encoding="utf-8") as stream:  # never replaces a file
                stream.write(text)
            break
        except FileExistsError:  # taken since free_name looked: the next one
            continue
    try:
        same = yaml_dump_typed(load_cell(target)) == yaml_dump_typed(cell)
    except Exception:
        same = False
    if not same:
        os.unlink(target)
        raise RuntimeError(f"{target}: the edited file did not load to the session's cell")
    return target


def export(cell_file: Path, out: Path, progress) -> tuple[Path, str]:
    """Write the plan folder of ``cell_file`` (the saved state) to ``out``.

    Returns:
        (the folder, one line for the status).

    Raises:
        InputError: ``out`` holds files offline_prog did not write, or the job fails
            its input checks; PlanFailedError: no plan to export.
    """
    progress("planning the whole job")
    plan = plan_job(cell_file, progress=progress)
    progress("writing the plan folder")
    files, _ = write_job_outputs(plan, out)
    programs = sum(1 for key in files if ":" in key)
    what = f"{programs} program file(s)" if programs else "no programs (the plan fails)"
    return out, f"exported {cell_file.name} to {out}/ ({len(files)} files, {what})"
