"""``offline-prog robots list | self-collision ROBOT | import DESCRIPTION``."""

from __future__ import annotations

from pathlib import Path

from rich.console import Console


def run_robots(args, console: Console) -> None:
    """The ``robots`` subcommands (bad input raises InputError: one line, exit 2)."""
    from offline_prog.config.robot_search import ENV_VAR, robots_in, search_path
    from offline_prog.errors import InputError
    from offline_prog.robot.model import ROBOTS_DIR, load_robot

    if args.robots_command == "list":
        from offline_prog.robot_import.folder import remark

        for name, folder, used in robots_in(search_path(ROBOTS_DIR)):
            where = "bundled" if folder == ROBOTS_DIR else f"{ENV_VAR}: {folder}"
            notes = [] if used else ["hidden by the one above"]
            notes += [note] if (note := remark(folder / name)) else []
            console.print(
                f"{name:<24} {where}" + "".join(f"  ({n})" for n in notes),
                highlight=False,
                markup=False,
            )
        return
    if args.robots_command == "import":
        _run_import(args, console)
        return
    from offline_prog.scene.self_collision import MATRIX_FILE, write_matrix

    try:
        robot = load_robot(args.robot)
    except ValueError as error:
        raise InputError(ROBOTS_DIR, "", str(error)) from None
    file = args.out / MATRIX_FILE if args.out.is_dir() else args.out
    if file.exists() and not file.is_file():
        raise InputError(file, "--out", "exists and is not a file")
    pairs = write_matrix(robot, file, samples=args.samples, seed=args.seed)
    for kind in ("adjacent", "always", "constant", "never", "check"):
        names = [f"{p.a}-{p.b}" for p in pairs if p.kind == kind]
        console.print(f"  {kind:<9} {len(names):3d}  {', '.join(names)}", highlight=False)
    used = robot.urdf_path.parent / MATRIX_FILE
    console.print(
        f"wrote {file} ({args.samples} samples, seed {args.seed}). The planner reads "
        f"{used}"
        + (
            ""
            if file.resolve() == used.resolve()
            else f"; to plan with this matrix, copy it there: cp {file} {used}"
        ),
        highlight=False,
        markup=False,
    )


def _run_import(args, console: Console) -> None:
    import numpy as np

    from offline_prog.config.robot_search import ENV_VAR
    from offline_prog.robot_import.record import family as robot_family
    from offline_prog.robot_import.run import import_robot

    OPW_KEYS = ("a1", "a2", "b", "c1", "c2", "c3", "c4")

    out = args.out or Path("robots")
    with Console(stderr=True).status(f"importing {args.description.name}"):
        result = import_robot(
            args.description,
            name=args.name,
            out=out,
            package_paths=args.package_path or [],
            vendor=args.vendor,
            base=args.base,
            tip=args.tip,
            samples=args.samples,
            force=args.force,
            allow_file_meshes=args.allow_file_meshes,
            j23_coupled=args.j23_coupled,
        )
    p = result.params
    if p is not None:
        keys = ("d1", "a2", "a3", "d4", "d5", "d6") if robot_family(p) == "ur" else OPW_KEYS
        lengths = ", ".join(f"{k} {getattr(p, k):g}" for k in keys)
        console.print(f"  kinematics  {robot_family(p).upper()}: {lengths} m", highlight=False)
        if robot_family(p) == "opw":
            offsets = [round(float(v), 6) for v in np.degrees(p.offsets)]
            console.print(f"              offsets {offsets} deg, signs {list(p.sign_corrections)}")
        console.print(
            f"  FK check    {result.fk.samples} configurations: "
            f"max {result.fk.max_position_m:.1e} m, {result.fk.max_rotation_rad:.1e} rad"
        )
    else:
        console.print("  kinematics  no closed form fits: Drake InverseKinematics (family drake)")
    check = sum(pair.kind == "check" for pair in result.pairs)
    console.print(f"  self-collision  {len(result.pairs)} link pairs, {check} checked")
    console.print(
        f"wrote {result.folder} (cells: robot: {{model: {args.name}, robots_dir: {out}}} "
        f"or {ENV_VAR}={out.resolve()})",
        highlight=False,
    )
