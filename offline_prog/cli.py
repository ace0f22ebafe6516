"""Command line: ``offline-prog plan CELL.yaml --out DIR``.

Thin by design: parse flags, call the library, print a short summary. Bad input
ends with one line on stderr and exit code 2; a plan that fails a check (a collision)
writes its outputs, prints one line and exits with 1; an internal error with one line
and exit code 3 (``--debug`` shows the traceback).
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

import numpy as np
from rich.console import Console

EXIT_PLAN_FAILED = 1
EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 3
EXIT_INTERRUPTED = 130  # Ctrl-C, as shells report SIGINT


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="offline-prog",
        description="Plan robot motions that carry a part past a spatially fixed tool.",
    )
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    commands = parser.add_subparsers(dest="command", required=True)
    plan = commands.add_parser("plan", help="plan a cell and write the outputs")
    plan.add_argument("cell", type=Path, help="work-cell YAML file")
    plan.add_argument(
        "--out", type=Path, default=None, help="output folder (default: out/<cell name>)"
    )
    plan.add_argument(
        "--preview", action="store_true", help="also show the plan in MeshCat (see `preview`)"
    )
    plan.add_argument("--port", type=int, default=7000, help="MeshCat port for --preview")
    preview = commands.add_parser("preview", help="plan a cell and show it in MeshCat")
    preview.add_argument("cell", type=Path, help="work-cell YAML file")
    preview.add_argument("--port", type=int, default=7000, help="MeshCat port (default 7000)")
    preview.add_argument(
        "--seconds",
        type=float,
        default=None,
        help="keep the server this long (default: until Ctrl-C)",
    )
    robots = commands.add_parser("robots", help="robot descriptions: list, self-collision matrix")
    robot_commands = robots.add_subparsers(dest="robots_command", required=True)
    robot_commands.add_parser("list", help="the robots in offline_prog/robots")
    matrix = robot_commands.add_parser(
        "self-collision",
        help="sample configurations and write robots/<robot>/self_collision.yaml",
    )
    matrix.add_argument("robot", help="robot folder name, e.g. ur10e")
    matrix.add_argument("--samples", type=int, default=10_000, help="configurations (10000)")
    matrix.add_argument("--seed", type=int, default=0, help="random seed (0)")
    export = commands.add_parser("export", help="re-export programs from a finished plan")
    export.add_argument("plan_dir", type=Path, help="folder written by `offline-prog plan`")
    export.add_argument(
        "--format", required=True, choices=["krl", "rapid", "urscript", "csv", "ros-json"]
    )
    export.add_argument(
        "--out", type=Path, default=None, help="output folder (default: PLAN_DIR/programs)"
    )
    export.add_argument(
        "--force", action="store_true", help="export even if the plan failed (the header says so)"
    )
    export.add_argument(
        "--style",
        choices=["external_tcp", "flange"],
        default=None,
        help="KRL: external TCP ($IPO_MODE #TCP) or flange path",
    )
    export.add_argument(
        "--mode",
        choices=["servoj", "movel"],
        default=None,
        help="URScript: joint trajectory (servoj) or movel poses",
    )
    export.add_argument(
        "--chord-tol-mm",
        type=float,
        default=None,
        help="Cartesian point density: chordal tolerance [mm] (default 0.05)",
    )
    export.add_argument(
        "--angle-tol-deg",
        type=float,
        default=None,
        help="Cartesian point density: orientation tolerance [deg] (default 0.1)",
    )
    export.add_argument(
        "--line-limit",
        type=int,
        default=None,
        help="split programs longer than this (KRL 1400, RAPID 5000)",
    )
    return parser


def _export_options(args) -> dict:
    """Library keyword arguments from the export flags that apply to the format."""
    options = {}
    if args.chord_tol_mm is not None and args.format != "csv":
        options["chord_tol_m"] = args.chord_tol_mm * 1e-3
    if args.angle_tol_deg is not None and args.format != "csv":
        options["angle_tol_rad"] = float(np.deg2rad(args.angle_tol_deg))
    if args.style is not None and args.format == "krl":
        options["style"] = args.style
    if args.mode is not None and args.format == "urscript":
        options["mode"] = args.mode
    if args.line_limit is not None and args.format in ("krl", "rapid"):
        options["line_limit"] = args.line_limit
    return options


def _run_robots(args, console: Console) -> None:
    """``robots list`` and ``robots self-collision ROBOT``."""
    from offline_prog.errors import InputError
    from offline_prog.robot.model import ROBOTS_DIR, list_robots, load_robot

    if args.robots_command == "list":
        for name in list_robots():
            console.print(name)
        return
    from offline_prog.scene.self_collision import write_matrix

    if args.samples < 1:
        raise InputError("--samples", "", f"must be at least 1, got {args.samples}")
    try:
        robot = load_robot(args.robot)
    except ValueError as error:
        raise InputError(ROBOTS_DIR, "", str(error)) from None
    file, pairs = write_matrix(robot, samples=args.samples, seed=args.seed)
    for kind in ("adjacent", "always", "constant", "never", "check"):
        names = [f"{p.a}-{p.b}" for p in pairs if p.kind == kind]
        console.print(f"  {kind:<9} {len(names):3d}  {', '.join(names)}", highlight=False)
    console.print(f"wrote {file} ({args.samples} samples, seed {args.seed})")


def _run_export(args, console: Console) -> None:
    from offline_prog.export.formats import export
    from offline_prog.export.program import ProgramData

    data = ProgramData.load(args.plan_dir)
    out = args.out or args.plan_dir / "programs"
    files = export(data, args.format, out, force=args.force, **_export_options(args))
    for file in files:
        console.print(f"  {args.format:<9} {file}")
    console.print(f"exported {len(files)} file(s) from {args.plan_dir}")


def _serve_preview(plan, args, console: Console) -> None:
    """Show the plan in a MeshCat server on localhost until Ctrl-C (or --seconds)."""
    from pydrake.geometry import Meshcat, MeshcatParams

    from offline_prog.viz.preview import near_collision_mask, show_plan

    params = MeshcatParams()
    params.port = args.port
    meshcat = Meshcat(params)
    info = show_plan(plan, meshcat, near_collision=near_collision_mask(plan))
    console.print(
        f"MeshCat preview at [bold]{meshcat.web_url()}[/bold] "
        f"({info['frames']} animation frames; Ctrl-C to stop)"
    )
    seconds = getattr(args, "seconds", None)
    try:
        deadline = None if seconds is None else time.monotonic() + seconds
        while deadline is None or time.monotonic() < deadline:
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass


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
    return EXIT_INTERNAL, f"internal error: {type(error).__name__}: {error} (rerun with --debug)"


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    console, errors = Console(soft_wrap=True), Console(stderr=True, soft_wrap=True)
    started = time.perf_counter()

    def fail(message: str, code: int) -> int:
        """One plain line on stderr (no rich markup), and the exit code."""
        errors.print(message, markup=False, highlight=False)
        return code

    try:
        from offline_prog.plan import plan_cell
        from offline_prog.results.plan_folder import write_outputs
        from offline_prog.results.summary import print_summary

        # After pydrake's import (it sets the level): its INFO lines would break
        # "one line on stderr".
        logging.getLogger("drake").setLevel(logging.WARNING)

        if args.command == "export":
            _run_export(args, console)
            return 0
        if args.command == "robots":
            _run_robots(args, console)
            return 0
        if args.command == "preview":
            args.preview, args.out = True, None
        with errors.status("planning") as status:
            plan = plan_cell(args.cell, progress=lambda stage: status.update(stage))
            out = args.out or Path("out") / args.cell.stem
            status.update("writing outputs")
            if args.command == "plan":
                files, report = write_outputs(plan, out)
        if args.command == "plan":
            print_summary(console, report, files, time.perf_counter() - started)
        if args.preview:
            _serve_preview(plan, args, console)
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
    sys.exit(main())
