"""Command line: ``offline-prog plan CELL.yaml --out DIR``.

Thin by design: parse flags, call the library, print a short summary. Bad input
ends with one line on stderr and exit code 2; a plan that fails a check (a collision)
writes its outputs, prints one line and exits with 1; an internal error with one line
and exit code 3 (``--debug`` shows the traceback).
"""

from __future__ import annotations

import errno
import gc
import logging
import sys
import time
from pathlib import Path

import numpy as np
from rich.console import Console

from offline_prog.cli_flags import EXIT_BAD_INPUT, one_line, parser
from offline_prog.cli_progress import PlanProgress

EXIT_PLAN_FAILED = 1
EXIT_INTERNAL = 3
EXIT_INTERRUPTED = 130  # Ctrl-C, as shells report SIGINT
# OSErrors the user's machine causes, not our code: exit 2 naming the path.
USER_ERRNOS = {
    errno.EACCES,
    errno.EPERM,
    errno.ENOSPC,
    errno.EDQUOT,
    errno.EROFS,
    errno.ENOTDIR,
    errno.EISDIR,
    errno.EEXIST,
    errno.ENOENT,
    errno.ENAMETOOLONG,
    errno.EMFILE,
    errno.EXDEV,
    errno.ELOOP,
    errno.EIO,
}


# The export flags, as library options.
EXPORT_FLAGS = {
    "chord_tol_m": "--chord-tol-mm",
    "angle_tol_rad": "--angle-tol-deg",
    "tcp_pose_convention": "--tcp-pose-convention",
    "line_limit": "--line-limit",
    "mode": "--mode",
}


def _export_options(args) -> dict:
    """Library keyword arguments from the export flags given.

    Raises:
        ValueError: a flag the format does not take (one line naming the ones it does).
    """
    from offline_prog.export.formats import format_options

    given = {
        "chord_tol_m": None if args.chord_tol_mm is None else args.chord_tol_mm * 1e-3,
        "angle_tol_rad": None
        if args.angle_tol_deg is None
        else float(np.deg2rad(args.angle_tol_deg)),
        "tcp_pose_convention": args.tcp_pose_convention,
        "line_limit": args.line_limit,
        "mode": args.mode,
    }
    options = {key: value for key, value in given.items() if value is not None}
    takes = format_options(args.format)
    refused = [EXPORT_FLAGS[key] for key in options if key not in takes]
    if refused:
        flags = ", ".join(EXPORT_FLAGS[key] for key in takes if key in EXPORT_FLAGS) or "none"
        raise ValueError(
            f"{', '.join(refused)}: not an option of --format {args.format} (its flags: {flags})"
        )
    return options


def _run_robots(args, console: Console) -> None:
    """``robots list | self-collision | import`` (offline_prog.cli_robots)."""
    from offline_prog.cli_robots import run_robots

    run_robots(args, console)


def _run_calibrate(args, console: Console) -> None:
    """``calibrate``: the calibrated cell and calibration.json, one line per frame."""
    from offline_prog.api import calibrate

    calibrated = calibrate(
        args.cell,
        args.out,
        touches=args.touches,
        from_controller=args.from_controller,
        controller_angles=args.controller_angles,
    )
    for line in calibrated.summary:
        console.print(line, highlight=False, markup=False)


def _run_export(args, console: Console) -> None:
    from offline_prog.api import export_programs

    files = export_programs(
        args.plan_dir,
        args.format,
        args.out,
        force=args.force,
        no_payload=args.no_payload,
        **_export_options(args),
    )
    for file in files:
        console.print(f"  {args.format:<9} {file}")
    console.print(f"exported {len(files)} file(s) from {args.plan_dir}")


def _serve_preview(plan, args, console: Console) -> None:
    """Show the plan in a MeshCat server on --host (localhost) until Ctrl-C (or --seconds;
    Ctrl-C ends the command with 130, as it does every other command)."""
    from offline_prog.job.records import JobPlan
    from offline_prog.viz.job_preview import show_job
    from offline_prog.viz.local_server import open_meshcat, url
    from offline_prog.viz.preview import near_collision_mask, show_plan

    meshcat = open_meshcat(args.host, args.port)
    if isinstance(plan, JobPlan):
        info = show_job(plan, meshcat)
    else:
        info = show_plan(plan, meshcat, near_collision=near_collision_mask(plan))
    console.print(
        f"MeshCat preview at [bold]{url(args.host, args.port, '')}[/bold] "
        f"({info['frames']} animation frames; Ctrl-C to stop)"
    )
    seconds = getattr(args, "seconds", None)
    deadline = None if seconds is None else time.monotonic() + seconds
    while deadline is None or time.monotonic() < deadline:  # Ctrl-C: exit 130, as elsewhere
        time.sleep(0.2)


OUT = ("reach", "joint_limit", "stand", "collision")  # placement's screened-out fates


def _run_place(args, console: Console, errors: Console) -> str:
    """``place``: the search with a progress bar on stderr, then a short summary.
    Returns "" or, when no candidate was feasible, the one line saying so."""
    from offline_prog import api
    from offline_prog.cli_progress import PlaceProgress

    out = args.out or Path("out") / f"{args.cell.stem}_place"
    with PlaceProgress(errors, console) as progress:
        data = api.place(
            args.cell,
            out,
            budget=args.budget,
            seed=args.seed,
            workers=args.workers,
            scheduler=args.scheduler,
            progress=progress,
        )
    from offline_prog.atomic import read_manifest

    best, cut, engine = data["best"], data["cycle_time_cut"], data["engine"]
    wrote = ", ".join(sorted((read_manifest(out) or {}).get("files", {}).get("plan", [])))
    verdict = "feasible" if best["feasible"] else f"infeasible ({best['reason']})"
    console.print(f"best placement: {verdict}", highlight=False, markup=False)
    if best["feasible"]:
        p, rpy = best["X_IT"]["translation"], best["X_IT"]["rpy_deg"]
        console.print(
            f"  X_IT translation [mm] {', '.join(f'{1e3 * v:.1f}' for v in p)}, rpy [deg] "
            f"{', '.join(f'{v:.2f}' for v in rpy)}; cycle {best['cycle_time_s']:.2f} s",
            highlight=False,
            markup=False,
        )
    if cut["percent"] is not None:
        console.print(
            f"  {cut['percent']:.1f} % faster than the cell as given", highlight=False, markup=False
        )
    if cut.get("why_not_more"):
        console.print(f"  why not more: {cut['why_not_more']}", highlight=False, markup=False)
    console.print(
        f"{engine['candidates_evaluated']} candidates planned in full of {engine['screened']} "
        "screened, "
        f"{engine['wall_time_s']:.1f} s on {engine['workers']} worker(s) "
        f"({engine['scheduler']}); wrote into {out}: {wrote}",
        highlight=False,
        markup=False,
    )
    if best["feasible"]:
        return ""
    fates, planned = data["screening"]["fates"], engine["candidates_evaluated"]
    out_by = ", ".join(f"{n} by {k.replace('_', ' ')}" for k, n in fates.items() if n and k in OUT)
    return (
        f"error: {args.cell}: no feasible placement in {planned} candidate"
        f"{'' if planned == 1 else 's'} planned"
        + (f" ({out_by} screened out)" if out_by else "")
        + f"; the closest: {best['reason']} (see {out}/placement.html)"
    )


def exit_code(error: BaseException, args) -> tuple[int, str]:
    """The exit code and the one stderr line for an error: the one place that maps
    errors to exit codes (README: "exit code")."""
    from offline_prog.errors import InputError, PlanFailedError
    from offline_prog.export.formats import ExportRefusedError

    if isinstance(error, KeyboardInterrupt):
        return EXIT_INTERRUPTED, "interrupted"
    if isinstance(error, PlanFailedError):  # valid cell, but the robot cannot do it
        return EXIT_PLAN_FAILED, f"error: {args.cell}: {error}"
    if isinstance(error, ExportRefusedError):
        return EXIT_BAD_INPUT, f"error: {args.plan_dir}: {error}"
    if isinstance(error, InputError) or (
        args.command == "export" and isinstance(error, ValueError)
    ):
        return EXIT_BAD_INPUT, f"error: {error}"
    if isinstance(error, OSError) and error.errno in USER_ERRNOS:  # disk full, permissions
        where = error.filename or getattr(args, "out", None) or ""
        return EXIT_BAD_INPUT, f"error: {where}: {error.strerror}"
    return EXIT_INTERNAL, f"internal error: {type(error).__name__}: {error} (rerun with --debug)"


def command() -> int:
    """The ``offline-prog`` command in its own process (``python -m offline_prog``)."""
    gc.disable()  # while the command imports: main freezes their objects, then enables it
    return main(own_process=True)


def main(argv: list[str] | None = None, *, own_process: bool = False) -> int:
    """Run the command ``argv`` (default: the command line); the exit code.

    Args:
        own_process: the process is this command's (not a test's that runs many):
            what the imports made is frozen out of the garbage collector's walks, and
            the collector (disabled by :func:`command` while it imports) is enabled.
    """
    args = parser().parse_args(argv)
    console, errors = Console(soft_wrap=True), Console(stderr=True, soft_wrap=True)
    started = time.perf_counter()

    def fail(message: str, code: int) -> int:
        """One plain line on stderr (no rich markup), and the exit code."""
        errors.print(one_line(message), markup=False, highlight=False)
        return code

    try:
        from offline_prog import api
        from offline_prog.results.plan_folder import check_out_dir
        from offline_prog.results.summary import print_job_summary

        if own_process:
            # The imports' objects (a million: pydrake, scipy) live as long as the
            # process; the cyclic collector need not walk them again in every full
            # collection and at exit (0.2-0.35 s of the seal demo's 2.1-2.4 s); nor,
            # disabled until here, in the imports (40-60 ms).
            gc.freeze()
            gc.enable()
        # After pydrake's import (it sets the level): its INFO lines would break
        # "one line on stderr".
        logging.getLogger("drake").setLevel(logging.WARNING)

        if args.command == "export":
            _run_export(args, console)
            return 0
        if args.command == "robots":
            _run_robots(args, console)
            return 0
        if args.command == "calibrate":
            _run_calibrate(args, console)
            return 0
        if args.command == "seams":
            from offline_prog.viz.seams_page import run_seams

            run_seams(args.part, args.out, args.mesh_units, say=console.print)
            return 0
        if args.command == "session":
            from offline_prog.session.launch import run_session

            run_session(
                args.cell,
                host=args.host,
                port=args.port,
                seconds=args.seconds,
                open_browser=not args.no_browser,
                say=console.print,
            )
            return 0
        if args.command == "place":  # no feasible placement: outputs written, exit 1
            failed = _run_place(args, console, errors)
            return fail(failed, EXIT_PLAN_FAILED) if failed else 0
        if args.command == "preview":
            args.preview, args.out = True, None
        if args.preview:  # a taken port is known before planning
            from offline_prog.viz.local_server import check_free

            check_free(args.host, args.port)
        out = args.out or Path("out") / args.cell.stem
        if args.command == "plan":
            check_out_dir(out)  # before planning: a bad --out is known now
        # Every cell is a job (path: one seam). Progress on stderr only while stdout is
        # a terminal: logs and pipes stay clean.
        with PlanProgress(errors, enabled=console.is_terminal) as progress:
            plan = api.plan(args.cell, progress=progress)
            progress("writing outputs")
            if args.command == "plan":
                files = plan.write(out)
        if args.command == "plan":
            print_job_summary(console, plan.report, files, time.perf_counter() - started)
        if args.preview:
            _serve_preview(plan.job, args, console)
        if not plan.feasible:  # outputs written so the user can see why; no programs
            where = f" (see {files['collisions']})" if args.command == "plan" else ""
            return fail(f"error: {args.cell}: {plan.failure}{where}", EXIT_PLAN_FAILED)
        return 0
    except (Exception, KeyboardInterrupt) as error:  # one line, never a traceback unless asked
        code, message = exit_code(error, args)
        if code == EXIT_INTERNAL and args.debug:
            raise
        return fail(message, code)


if __name__ == "__main__":
    sys.exit(command())
