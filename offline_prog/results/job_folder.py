"""The plan folder of a job, as a list of writers: each takes the finished plan and
writes one file (or one program set) of the folder.

- on the second core, needing nothing else written here: ``trajectory.csv``
  (``job_table``) and ``preview.html`` (``viz.job_preview``);
- here: ``report.json`` (``job_report``), ``collisions.json``, ``clearance.csv``,
  ``plan.npz`` + ``job.npz`` (``program_data``), and ``programs/``: every default format
  (``export.formats``) of a feasible plan;
- last: ``report.html``, which reads the programs and trajectory.csv.

What several of them read is made once (:class:`FinishedJob`). The folder is staged and
swapped in whole, and a folder holding files we did not write is refused
(``plan_folder``).
"""

from __future__ import annotations

import functools
import json
from collections.abc import Callable
from pathlib import Path

from offline_prog.atomic import staged_folder, write_atomic, write_manifest
from offline_prog.collision.check import write_collisions_json
from offline_prog.export.formats import PROGRAMS_DIR, default_formats, export
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.payload import payload
from offline_prog.export.program import PLAN_FILE
from offline_prog.job.records import JobPlan
from offline_prog.results.job_report import job_report
from offline_prog.results.job_table import trajectory_csv
from offline_prog.results.plan_folder import InParallel, check_out_dir, clearance_csv
from offline_prog.results.program_data import job_program_data
from offline_prog.viz.job_preview import write_job_preview_html
from offline_prog.viz.job_report_html import write_job_report_html


class FinishedJob:
    """A finished job and what several files are made of, each made once when first
    read: ``report`` (report.json) and ``programs`` (plan.npz, job.npz, the programs)."""

    def __init__(self, job: JobPlan, folder_name: str):
        self.job, self.folder_name = job, folder_name

    @functools.cached_property
    def report(self) -> dict:
        return job_report(self.job)

    @functools.cached_property
    def programs(self) -> JobProgramData:
        return job_program_data(self.job, self.report)


Writer = Callable[[FinishedJob, Path], dict[str, Path]]


def preview_html(done: FinishedJob, folder: Path) -> dict[str, Path]:
    file = folder / "preview.html"
    write_job_preview_html(done.job, file)
    return {"preview": file}


def trajectory_file(done: FinishedJob, folder: Path) -> dict[str, Path]:
    file = folder / "trajectory.csv"
    write_atomic(file, trajectory_csv(done.job))
    return {"trajectory": file}


def report_json(done: FinishedJob, folder: Path) -> dict[str, Path]:
    file = folder / "report.json"
    write_atomic(file, json.dumps(done.report, indent=2) + "\n")
    return {"report": file}


def collisions_json(done: FinishedJob, folder: Path) -> dict[str, Path]:
    file = folder / "collisions.json"
    write_collisions_json(done.job.collisions, file)
    return {"collisions": file}


def clearance_file(done: FinishedJob, folder: Path) -> dict[str, Path]:
    if done.job.clearance_profile is None:
        return {}
    file = folder / "clearance.csv"
    write_atomic(file, clearance_csv(*done.job.clearance_profile))
    return {"clearance": file}


def plan_files(done: FinishedJob, folder: Path) -> dict[str, Path]:
    """job.npz and plan.npz: the plan for ``offline-prog export``."""
    return {"job": done.programs.save(folder), "plan": folder / PLAN_FILE}


def program_files(done: FinishedJob, folder: Path) -> dict[str, Path]:
    """Every default format; none of a failed plan (``offline-prog export --force`` can).
    A cell without masses: programs without a load statement, which their headers say
    (the controller's active load is used; report.json and the summary warn)."""
    data, files = done.programs, {}
    unset = payload(data.job.payload) is None
    if data.feasible:
        for fmt in default_formats(data.language):
            for file in export(data, fmt, folder / PROGRAMS_DIR, no_payload=unset):
                files[f"{fmt}:{file.name}"] = file
    return files


def report_html(done: FinishedJob, folder: Path) -> dict[str, Path]:
    """report.html, naming the folder the user gets (not the staged one)."""
    return {"report_html": write_job_report_html(folder, folder_name=done.folder_name)}


# The second core's writers, the writers here, and the last (reads the others' files).
BESIDE: tuple[Writer, ...] = (preview_html, trajectory_file)
HERE: tuple[Writer, ...] = (report_json, collisions_json, clearance_file, plan_files, program_files)
LAST: tuple[Writer, ...] = (report_html,)


def _run(writers: tuple[Writer, ...], done: FinishedJob, folder: Path) -> dict[str, Path]:
    files = {}
    for write in writers:
        files |= write(done, folder)
    return files


def write_job_outputs(
    job: JobPlan, out_dir: Path, *, finished: FinishedJob | None = None
) -> tuple[dict[str, Path], dict]:
    """Write the job's plan folder; returns the files by name and the report.

    Args:
        finished: the job's report and program data made already (the API's plan).

    Raises:
        InputError: out_dir is a file, or a folder with files we did not write.
    """
    out_dir = Path(out_dir)
    check_out_dir(out_dir)
    done = finished or FinishedJob(job, out_dir.name)
    done.folder_name = out_dir.name
    with staged_folder(out_dir) as folder:
        # An error or Ctrl-C in the block stops the second core before the staged
        # folder goes.
        with InParallel(lambda: _run(BESIDE, done, folder)) as child:
            here = _run(HERE, done, folder)
            files = child.wait() | here
        files |= _run(LAST, done, folder)
        names = sorted({path.relative_to(folder).parts[0] for path in files.values()})
        write_manifest(folder, {"plan": names})
    return {key: out_dir / path.relative_to(folder) for key, path in files.items()}, done.report
