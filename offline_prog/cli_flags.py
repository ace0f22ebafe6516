"""The command line's flags: argparse with checked numbers and one-line errors.

Every numeric flag has a type function that refuses NaN, infinity and values out of
range; any parse error is one line, ``error: <message> (see offline-prog <cmd> --help)``,
and exit code 2 (not argparse's usage block).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from offline_prog import __version__
from offline_prog.constants import MAX_PLACE_BUDGET, MAX_PLACE_SEED
from offline_prog.export.split import MIN_LINE_LIMIT
from offline_prog.viz.local_server import MAX_PORT, MIN_PORT

EXIT_BAD_INPUT = 2
MAX_MESSAGE_CHARS = 500  # one stderr line, however long the cause's text


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``error: <message> (see offline-prog <cmd> --help)``
    and exit code 2, instead of the usage block; ``--debug`` is taken before or after
    any (sub)command (every internal error says "rerun with --debug")."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # SUPPRESS: a subcommand without the flag leaves the value parsed before it.
        self.add_argument(
            "--debug", action="store_true", default=argparse.SUPPRESS, help="show tracebacks"
        )

    def error(self, message: str):
        self.exit(EXIT_BAD_INPUT, f"error: {one_line(message)} (see {self.prog} --help)\n")


def one_line(message: str) -> str:
    """Whitespace (newlines too) collapsed, cut to MAX_MESSAGE_CHARS."""
    text = " ".join(str(message).split())
    return text if len(text) <= MAX_MESSAGE_CHARS else text[: MAX_MESSAGE_CHARS - 3] + "..."


def _number(kind, *, low: float, inclusive: bool, high: float = math.inf):
    """An argparse type: a finite ``kind`` (float or int) above ``low`` (or equal to it
    when inclusive), at most ``high``; ArgumentTypeError otherwise."""
    noun = "an integer" if kind is int else "a number"
    show = (lambda v: f"{int(v)}") if kind is int else (lambda v: f"{v:g}")

    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not {noun}") from None
        if not (math.isfinite(value) and low <= value <= high) or (value == low and not inclusive):
            bound = (f">= {show(low)}" if inclusive else f"> {show(low)}") + (
                f" and <= {show(high)}" if high < math.inf else ""
            )
            finite = noun if kind is int else "a finite number"
            raise argparse.ArgumentTypeError(f"{text!r}: need {finite} {bound}")
        return value

    parse.__name__ = kind.__name__  # argparse names the type in its messages
    return parse


POSITIVE = _number(float, low=0.0, inclusive=False)
PORT = _number(int, low=MIN_PORT, inclusive=True, high=MAX_PORT)  # MeshCat aborts below 1024
HOST_HELP = "listen on this host (default localhost; 0.0.0.0: every interface; ::1: IPv6)"
MAX_MATRIX_SAMPLES = 10_000_000  # self-collision samples (10⁴ take ~3 s)


def parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="offline-prog",
        description="Plan robot motions that carry a part past a spatially fixed tool.",
    )
    parser.set_defaults(debug=False)
    parser.add_argument("--version", action="version", version=f"offline-prog {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    plan = commands.add_parser("plan", help="plan a cell and write the outputs")
    plan.add_argument("cell", type=Path, help="work-cell YAML file")
    plan.add_argument(
        "--out",
        type=Path,
        default=None,
        help="output folder (default: out/<file stem>, e.g. out/seal_plate_kr16 for "
        "cells/seal_plate_kr16.yaml)",
    )
    plan.add_argument(
        "--preview", action="store_true", help="also show the plan in MeshCat (see `preview`)"
    )
    plan.add_argument("--port", type=PORT, default=7000, help="MeshCat port for --preview")
    plan.add_argument("--host", default="localhost", help=f"--preview: {HOST_HELP}")
    preview = commands.add_parser("preview", help="plan a cell and show it in MeshCat")
    preview.add_argument("cell", type=Path, help="work-cell YAML file")
    preview.add_argument("--port", type=PORT, default=7000, help="MeshCat port (default 7000)")
    preview.add_argument("--host", default="localhost", help=HOST_HELP)
    preview.add_argument(
        "--seconds",
        type=_number(float, low=0.0, inclusive=True),
        default=None,
        help="keep the server this long (default: until Ctrl-C)",
    )
    _session_flags(commands)
    _place_flags(commands)
    _calibrate_flags(commands)
    _seams_flags(commands)
    robots = commands.add_parser(
        "robots", help="robot descriptions: list, import (URDF or xacro), self-collision matrix"
    )
    robot_commands = robots.add_subparsers(
        dest="robots_command", required=True, parser_class=_Parser
    )
    robot_commands.add_parser("list", help="the robots found, and where each comes from")
    _import_flags(robot_commands)
    matrix = robot_commands.add_parser(
        "self-collision",
        help="sample configurations and write the robot's self-collision matrix",
    )
    matrix.add_argument("robot", help="robot folder name, e.g. ur10e")
    matrix.add_argument(
        "--samples",
        type=_number(int, low=1, inclusive=True, high=MAX_MATRIX_SAMPLES),
        default=10_000,
        help="configurations (10000)",
    )
    matrix.add_argument("--seed", type=int, default=0, help="random seed (0)")
    matrix.add_argument(
        "--out",
        type=Path,
        default=Path("."),
        help="file, or folder for self_collision.yaml (default: the current folder); "
        "the planner reads the one in the robot's folder",
    )
    export = commands.add_parser("export", help="re-export programs from a finished plan")
    export.add_argument("plan_dir", type=Path, help="folder written by `offline-prog plan`")
    export.add_argument(
        "--format", required=True, choices=["krl", "rapid", "urscript", "fanuc", "csv", "ros-json"]
    )
    export.add_argument(
        "--out", type=Path, default=None, help="output folder (default: PLAN_DIR/programs)"
    )
    export.add_argument(
        "--force", action="store_true", help="export even if the plan failed (the header says so)"
    )
    export.add_argument(
        "--no-payload",
        action="store_true",
        help="controller programs state no load: the controller's active load is used (the "
        "header says so); without it a cell that gives no gripper.mass_kg / part.mass_kg is "
        "refused",
    )
    export.add_argument(
        "--tcp-pose-convention",
        choices=["X_TP", "X_PF"],
        default=None,
        help="KRL: points are the part P in the tool T (X_TP, default) or T in P (X_PF)",
    )
    export.add_argument(
        "--chord-tol-mm",
        type=POSITIVE,
        default=None,
        help="KRL, RAPID, FANUC, URScript movel/movep point density: chordal tolerance "
        "[mm] (default 0.05)",
    )
    export.add_argument(
        "--angle-tol-deg",
        type=POSITIVE,
        default=None,
        help="KRL, RAPID, FANUC, URScript movel/movep point density: orientation "
        "tolerance [deg] (default 0.1)",
    )
    export.add_argument(
        "--mode",
        choices=["servoj", "movel", "movep"],
        default=None,
        help="URScript: servoj streams the planned joints (default); movel / movep: linear "
        "moves with blend radii within the path tolerance, the flow set per point, in the "
        "tool's feature (editable on the pendant)",
    )
    export.add_argument(
        "--line-limit",
        type=_number(int, low=MIN_LINE_LIMIT, inclusive=True),
        default=None,
        help="KRL, RAPID, FANUC: most lines of one program part; a seam's longer program "
        "is split into parts called in turn (default: no split; set your controller's limit)",
    )
    return parser


def _session_flags(commands) -> None:
    """``session CELL.yaml [--port 7000] [--host localhost] [--no-browser]``."""
    session = commands.add_parser(
        "session", help="adjust the cell in the browser (MeshCat), re-plan live, export"
    )
    session.add_argument("cell", type=Path, help="work-cell YAML file")
    session.add_argument(
        "--port",
        type=_number(int, low=MIN_PORT, inclusive=True, high=MAX_PORT - 1),
        default=7000,
        help="panel port (default 7000); MeshCat uses the next one",
    )
    session.add_argument("--host", default="localhost", help=HOST_HELP)
    session.add_argument("--no-browser", action="store_true", help="do not open a browser")
    session.add_argument(
        "--seconds",
        type=_number(float, low=0.0, inclusive=True),
        default=None,
        help="stop after this long (default: until Ctrl-C)",
    )


def _place_flags(commands) -> None:
    """``place CELL.yaml --out DIR [--budget N] [--seed S] [--workers N | --scheduler ADDR]``."""
    place = commands.add_parser(
        "place", help="search where the tool stands and how the part is held (place: block)"
    )
    place.add_argument("cell", type=Path, help="work-cell YAML file with a place: block")
    place.add_argument(
        "--out",
        type=Path,
        default=None,
        help="output folder (default: out/<file stem>_place)",
    )
    place.add_argument(
        "--budget",
        type=_number(int, low=1, inclusive=True, high=MAX_PLACE_BUDGET),
        default=None,
        help="candidates through the planning pipeline (default: place.budget)",
    )
    place.add_argument(
        "--seed",
        type=_number(int, low=0, inclusive=True, high=MAX_PLACE_SEED),
        default=None,
        help="search seed (default: place.seed)",
    )
    where = place.add_mutually_exclusive_group()
    where.add_argument(
        "--workers",
        type=_number(int, low=0, inclusive=True, high=1024),
        default=None,
        help="Dask LocalCluster workers (default: one per core; 0: this process, no Dask)",
    )
    where.add_argument(
        "--scheduler",
        default=None,
        help="an existing Dask cluster's scheduler, e.g. tcp://host:8786",
    )


def _calibrate_flags(commands) -> None:
    """``calibrate CELL (--touches FILE [--controller-angles] | --from-controller FILE)
    --out calibrated.yaml``."""
    calibrate = commands.add_parser(
        "calibrate",
        help="the fixed tool's TCP and the grasp from touches, or from the controller's frames",
    )
    calibrate.add_argument("cell", type=Path, help="work-cell YAML file")
    source = calibrate.add_mutually_exclusive_group(required=True)
    source.add_argument(
        "--touches",
        type=Path,
        help="CSV target,q1_deg..q6_deg: touches of the tool's tip, its axis, part points",
    )
    source.add_argument(
        "--from-controller",
        type=Path,
        help="the controller's calibrated frames: KUKA $config.dat or an ABB RAPID module",
    )
    calibrate.add_argument(
        "--controller-angles",
        action="store_true",
        help="the touches' angles as the controller shows them (e.g. ABB/FANUC axis 3)",
    )
    calibrate.add_argument(
        "--out",
        type=Path,
        required=True,
        help="the calibrated cell file (calibration.json is written beside it)",
    )


def _import_flags(robot_commands) -> None:
    """``robots import DESCRIPTION --name NAME ...``."""
    imp = robot_commands.add_parser(
        "import", help="a robot folder from a URDF or xacro (six revolute joints)"
    )
    imp.add_argument("description", type=Path, help="the robot's .urdf or .xacro file")
    imp.add_argument("--name", required=True, help="the robot folder's name, e.g. fanuc_m20ia")
    imp.add_argument(
        "--package-path",
        type=Path,
        action="append",
        help="a folder holding ROS packages (package.xml), for package:// and $(find); "
        "repeatable (default: the folder above the description's package)",
    )
    imp.add_argument(
        "--vendor",
        default="other",
        choices=("fanuc", "kuka", "abb", "universal_robots", "other"),
        help="the maker: chooses the controller language (default other: none)",
    )
    imp.add_argument("--out", type=Path, default=None, help="ROBOTS_DIR to write into (./robots)")
    imp.add_argument("--base", default="base_link", help="the chain's base link (base_link)")
    imp.add_argument("--tip", default="tool0", help="the chain's flange link (tool0)")
    imp.add_argument(
        "--samples",
        type=_number(int, low=1, inclusive=True, high=MAX_MATRIX_SAMPLES),
        default=10_000,
        help="self-collision configurations (10000)",
    )
    imp.add_argument(
        "--force",
        action="store_true",
        help="replace a robot folder an earlier `robots import` wrote (no other folder)",
    )
    imp.add_argument(
        "--allow-file-meshes",
        action="store_true",
        help="read file:// mesh names (anywhere on disk); default: only package:// and "
        "relative names inside the --package-path folders",
    )
    imp.add_argument(
        "--j23-coupled",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="the controller counts axis 3 from the horizontal (ABB: required, model-"
        "dependent, e.g. true for the IRB 2400; FANUC: always)",
    )


def _seams_flags(commands) -> None:
    """``seams PART.step|PART.stl [--out PAGE.html] [--mesh-units m|mm]``."""
    seams = commands.add_parser(
        "seams", help="list a part model's faces, loops and edge chains; write a 3D page"
    )
    seams.add_argument("part", type=Path, help="STEP (.step, .stp) or mesh (.stl, .obj, .ply)")
    seams.add_argument(
        "--out",
        type=Path,
        default=None,
        help="the page, a .html file (default: out/<part stem>_seams.html); a file this "
        "command did not write is not replaced",
    )
    seams.add_argument(
        "--mesh-units", choices=("m", "mm"), default="m", help="a mesh file's unit (default m)"
    )
