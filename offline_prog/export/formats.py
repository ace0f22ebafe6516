"""One entry point for every export format, and which ones a robot gets by default."""

from __future__ import annotations

from pathlib import Path

from offline_prog.export.program import ProgramData

FORMATS = ("krl", "rapid", "urscript", "csv", "ros-json")
PROGRAMS_DIR = "programs"


class ExportRefusedError(ValueError):
    """The plan failed; exporting it needs ``force``."""


def default_formats(language: str | None) -> list[str]:
    """The robot's controller language (robot.yaml) plus the joint-trajectory files."""
    return ([language] if language else []) + ["csv", "ros-json"]


def export(
    data: ProgramData, fmt: str, out_dir: Path, *, force: bool = False, **options
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
    if fmt in ("krl", "rapid") and fmt != data.language:
        raise ValueError(
            f"{fmt} is not the controller language of the plan's robot "
            f"{data.robot} (use {', '.join(default_formats(data.language))})"
        )
    forced = not data.feasible
    out_dir = Path(out_dir)
    if fmt == "csv":
        from offline_prog.export.joint_files import write_joint_csv

        return [write_joint_csv(data, out_dir)]
    if fmt == "ros-json":
        from offline_prog.export.joint_files import write_ros_json

        return [write_ros_json(data, out_dir)]
    if fmt == "urscript":
        from offline_prog.export.urscript import write_urscript

        return [write_urscript(data, out_dir, forced=forced, **options).file]
    if fmt == "krl":
        from offline_prog.export.krl import write_krl

        return list(write_krl(data, out_dir, forced=forced, **options).files)
    from offline_prog.export.rapid import write_rapid

    return list(write_rapid(data, out_dir, forced=forced, **options).files)
