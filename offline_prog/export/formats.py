"""One entry point for every export format, and which ones a robot gets by default.

A format's files are written into a temporary folder inside ``out_dir`` and moved into
place; the folder's manifest (``atomic.MANIFEST``) lists them by format, so a re-export
removes the files its previous run wrote and this one did not (``name_3.src`` after a
split into fewer parts), and never a file we did not write.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

from offline_prog.atomic import read_manifest, remove_stale, temp_prefix, write_manifest
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.program import ProgramData

FORMATS = ("krl", "rapid", "urscript", "fanuc", "csv", "ros-json")
# A controller's own language: only for a plan of that controller's robot (the joint
# CSV and ROS JSON are for every robot).
CONTROLLER_FORMATS = ("krl", "rapid", "urscript", "fanuc")
PROGRAMS_DIR = "programs"


class ExportRefusedError(ValueError):
    """The plan failed; exporting it needs ``force``."""


def default_formats(language: str | None) -> list[str]:
    """The robot's controller language (robot.yaml) plus the joint-trajectory files."""
    return ([language] if language else []) + ["csv", "ros-json"]


# Controller languages with a whole-job writer.
JOB_LANGUAGES = ("krl", "rapid", "urscript", "fanuc")


def job_formats(language: str | None) -> list[str]:
    """The formats a whole job is exported in: as for one seam (default_formats), for
    the languages that have a job writer."""
    return default_formats(language if language in JOB_LANGUAGES else None)


def export(
    data: ProgramData | JobProgramData,
    fmt: str,
    out_dir: Path,
    *,
    force: bool = False,
    **options,
) -> list[Path]:
    """Write ``fmt`` for the plan into ``out_dir``; returns the files written.

    Raises:
        ExportRefusedError: the plan failed and force is False.
        ValueError: unknown format or option.
    """
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r} (use {', '.join(FORMATS)})")
    if not data.feasible and not force:
        raise ExportRefusedError(
            f"the plan failed ({data.failure}); refusing to export a "
            "program from it (use --force to export anyway)"
        )
    if fmt in CONTROLLER_FORMATS and fmt != data.language:  # (a job's is its robot's)
        raise ValueError(
            f"{fmt} is not the controller language of the plan's robot "
            f"{data.robot} (use {', '.join(default_formats(data.language))})"
        )
    if isinstance(data, JobProgramData):
        return replace_owned(
            Path(out_dir), fmt, lambda folder: _write_job(data, fmt, folder, **options)
        )
    return replace_owned(Path(out_dir), fmt, lambda folder: _write(data, fmt, folder, **options))


def replace_owned(out_dir: Path, group: str, write: Callable[[Path], list[Path]]) -> list[Path]:
    """Run ``write(folder)`` on an empty temporary folder, move the files it wrote into
    out_dir, and remove the files the manifest listed under ``group`` that it did not
    write again. Returns the files in out_dir.

    Order: the manifest first lists old and new names (a crash then leaves no file we
    do not know of), the files move, then the manifest lists the new names only and the
    stale ones go.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    remove_stale(out_dir)
    staging = Path(tempfile.mkdtemp(dir=out_dir, prefix=temp_prefix("export")))
    try:
        names = [file.name for file in write(staging)]
        owned = (read_manifest(out_dir) or {}).get("files", {})
        old = owned.get(group, [])
        write_manifest(out_dir, {**owned, group: sorted(set(old) | set(names))})
        for name in names:
            os.replace(staging / name, out_dir / name)
        write_manifest(out_dir, {**owned, group: names})
        others = {n for g, listed in owned.items() if g != group for n in listed}
        for name in set(old) - set(names) - others:
            with contextlib.suppress(FileNotFoundError):
                (out_dir / name).unlink()
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return [out_dir / name for name in names]


def _write(data: ProgramData, fmt: str, out_dir: Path, **options) -> list[Path]:
    """Write one format's files into out_dir (a fresh folder)."""
    forced = not data.feasible
    if fmt == "csv":
        from offline_prog.export.joint_files import write_joint_csv

        return [write_joint_csv(data, out_dir)]
    if fmt == "ros-json":
        from offline_prog.export.joint_files import write_ros_json

        return [write_ros_json(data, out_dir)]
    if fmt == "urscript":
        from offline_prog.export.ur.urscript import write_urscript

        return [write_urscript(data, out_dir, forced=forced, **options).file]
    if fmt == "fanuc":
        from offline_prog.export.fanuc.fanuc_ls import write_fanuc

        return list(write_fanuc(data, out_dir, forced=forced, **options).files)
    if fmt == "krl":
        from offline_prog.export.kuka.krl import write_krl

        return list(write_krl(data, out_dir, forced=forced, **options).files)
    from offline_prog.export.abb.rapid import write_rapid

    return list(write_rapid(data, out_dir, forced=forced, **options).files)


# The options each job writer takes (the rest are one-seam options: refused by name).
_JOB_OPTIONS = {
    "krl": {"chord_tol_m", "angle_tol_rad", "name", "blend_m", "tcp_pose_convention"},
    "rapid": {"chord_tol_m", "angle_tol_rad", "module", "zone_mm"},
    "urscript": {"name", "period_s"},
    "fanuc": {"chord_tol_m", "angle_tol_rad", "name", "line_limit"},
}


def _write_job(data: JobProgramData, fmt: str, out_dir: Path, **options) -> list[Path]:
    """Write one format's files of a whole job into out_dir (a fresh folder).

    Raises:
        ValueError: an option of one-seam programs only (style, mode, line_limit).
    """
    if fmt == "urscript":  # servoj streams the plan: point tolerances do not apply
        options = {k: v for k, v in options.items() if k not in ("chord_tol_m", "angle_tol_rad")}
    unknown = sorted(set(options) - _JOB_OPTIONS.get(fmt, set()))
    if unknown:
        raise ValueError(
            f"{fmt}: {', '.join(unknown)} is for one-seam plans; a whole job's {fmt} "
            "program has its own form (see the README, Whole jobs)"
        )
    if fmt == "csv":
        from offline_prog.export.joint_files import write_job_joint_csv

        return [write_job_joint_csv(data, out_dir)]
    if fmt == "ros-json":
        from offline_prog.export.joint_files import write_job_ros_json

        return [write_job_ros_json(data, out_dir)]
    if fmt == "krl":
        from offline_prog.export.kuka.krl_job import write_krl_job

        return write_krl_job(data, out_dir, forced=not data.feasible, **options)
    if fmt == "fanuc":
        from offline_prog.export.fanuc.fanuc_job import write_fanuc_job

        return write_fanuc_job(data, out_dir, forced=not data.feasible, **options)
    if fmt == "rapid":
        from offline_prog.export.abb.rapid_job import write_rapid_job

        return write_rapid_job(data, out_dir, forced=not data.feasible, **options)
    from offline_prog.export.ur.urscript_job import write_urscript_job

    return [write_urscript_job(data, out_dir, forced=not data.feasible, **options)]
