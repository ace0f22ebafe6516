"""One entry point for every export format, and which ones a robot gets by default.

The registry: each controller format is one writer class (``export.post``), imported when
it is used; the joint-trajectory files are one function each. A format's export options
are its writer's ``Options`` fields: any other is refused in one line naming the ones it
takes.

A format's files are written into a temporary folder inside ``out_dir`` and moved into
place; the folder's manifest (``atomic.MANIFEST``) lists them by format, so a re-export
removes the files its previous run wrote and this one did not (``name_S1_3.ls`` after a
split into fewer parts), and never a file we did not write.
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib
import os
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

from offline_prog.atomic import read_manifest, remove_stale, temp_prefix, write_manifest
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.payload import refusal
from offline_prog.export.post import ControllerPost, write_program

# A controller's own language (only for a plan of that controller's robot): its writer,
# as module and class.
CONTROLLER_FORMATS = {
    "krl": ("offline_prog.export.kuka.krl", "KrlPost"),
    "rapid": ("offline_prog.export.abb.rapid", "RapidPost"),
    "urscript": ("offline_prog.export.ur.urscript", "UrScriptPost"),
    "fanuc": ("offline_prog.export.fanuc.fanuc_ls", "FanucPost"),
}
# The joint trajectory, for every robot: its writer function, which takes no options.
JOINT_FORMATS = {
    "csv": ("offline_prog.export.joint_files", "write_joint_csv"),
    "ros-json": ("offline_prog.export.joint_files", "write_ros_json"),
}
FORMATS = (*CONTROLLER_FORMATS, *JOINT_FORMATS)
PROGRAMS_DIR = "programs"


class ExportRefusedError(ValueError):
    """The plan failed; exporting it needs ``force``."""


def default_formats(language: str | None) -> list[str]:
    """The robot's controller language (robot.yaml) plus the joint-trajectory files."""
    return ([language] if language in CONTROLLER_FORMATS else []) + list(JOINT_FORMATS)


def format_options(fmt: str) -> tuple[str, ...]:
    """The export options a format takes (its writer's ``Options`` fields)."""
    if fmt not in CONTROLLER_FORMATS:
        return ()
    return tuple(f.name for f in dataclasses.fields(_writer(CONTROLLER_FORMATS[fmt]).Options))


def check_export(data: JobProgramData, fmt: str, *, force: bool = False) -> None:
    """Whether ``fmt`` may be written for the plan (before any option is looked at).

    Raises:
        ExportRefusedError: the plan failed and force is False.
        ValueError: unknown format, or another robot's controller language.
    """
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r} (use {', '.join(FORMATS)})")
    if not data.feasible and not force:
        raise ExportRefusedError(
            f"the plan failed ({data.failure}); refusing to export a "
            "program from it (use --force to export anyway)"
        )
    if fmt in CONTROLLER_FORMATS and fmt != data.language:
        raise ValueError(
            f"{fmt} is not the controller language of the plan's robot "
            f"{data.robot} (use {', '.join(default_formats(data.language))})"
        )


def export(
    data: JobProgramData,
    fmt: str,
    out_dir: Path,
    *,
    force: bool = False,
    no_payload: bool = False,
    **options,
) -> list[Path]:
    """Write ``fmt`` for the plan into ``out_dir``; returns the files written.

    Args:
        no_payload: a controller program states no load (the controller's active load
            is used, as its header says); without it a plan whose cell gives no masses
            is refused.

    Raises:
        ExportRefusedError: the plan failed and force is False.
        ValueError: unknown format or option, an option value the writer refuses, a
            controller program of a plan without masses and no_payload False.
    """
    check_export(data, fmt, force=force)
    _check_options(fmt, options)
    if fmt in JOINT_FORMATS:
        write = _writer(JOINT_FORMATS[fmt])
        return replace_owned(Path(out_dir), fmt, lambda folder: write(data, folder))
    if not no_payload and (why := refusal(data.job.payload)):
        raise ValueError(f"{fmt}: {why}")
    # its options checked before any file
    post = controller_post(data, fmt, no_payload=no_payload, **options)
    return replace_owned(Path(out_dir), fmt, lambda folder: write_program(post, folder))


def controller_post(
    data: JobProgramData, fmt: str, *, no_payload: bool = False, **options
) -> ControllerPost:
    """The writer of controller format ``fmt`` for the plan, with its options (a failed
    plan's header says so; ``no_payload``: it states no load); ``write_program(post,
    folder)`` writes its files.

    Raises:
        ValueError: an option value the writer refuses, a robot it cannot write for.
    """
    _check_options(fmt, options)
    post_class = _writer(CONTROLLER_FORMATS[fmt])
    options = post_class.Options(**options)
    return post_class(data, options, forced=not data.feasible, no_payload=no_payload)


def _check_options(fmt: str, options: dict) -> None:
    unknown = sorted(set(options) - set(format_options(fmt)))
    if unknown:
        takes = ", ".join(format_options(fmt)) or "none"
        raise ValueError(f"{fmt}: no option {', '.join(unknown)} (its options: {takes})")


def _writer(where: tuple[str, str]):
    """The writer (class or function) a registry entry names."""
    module, name = where
    return getattr(importlib.import_module(module), name)


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
