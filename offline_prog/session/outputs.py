"""Export of a session: the plan folder of the saved cell file.

Save (``config.cell_text.save_cell``) writes ``<stem>-<n>.yaml`` next to the original
(where its data files' relative paths hold). Export of the values as loaded plans the
cell file itself into ``out/<stem>``, writing nothing beside it; of edited values it
saves the cell first (the plan folder names it) into ``out/<stem>-<n>``. Either way the
folder is written exactly as ``offline-prog plan`` writes it, with the same writer: the
whole job (a ``path:`` cell is a one-seam job: home, approach, seam, retract, home).
"""

from __future__ import annotations

from pathlib import Path

from offline_prog.plan import plan_job
from offline_prog.results.job_folder import write_job_outputs


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
