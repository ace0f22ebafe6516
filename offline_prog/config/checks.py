"""Semantic checks of a cell file that its types alone cannot express.

Every failure is a InputError naming the file and key (one line).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from offline_prog.config.cad_keys import check_cad, check_part_model
from offline_prog.config.calibration_keys import check_calibration, check_controller_frames
from offline_prog.config.cell import GRIPPER_MESH_NAME, Cell, PathConfig, transform
from offline_prog.config.job_checks import check_job
from offline_prog.config.payload_keys import check_payload
from offline_prog.config.process_keys import check_process
from offline_prog.config.robot_search import find_robot, robots_in, search_path
from offline_prog.config.unit_slips import far_translation
from offline_prog.constants import (
    MAX_DATA_FILE_BYTES,
    MAX_SAMPLE_RATE_HZ,
    MAX_SPEED_M_S,
    PROCESS_INTENTS,
    TIME_LAWS,
    UNIT_SCALE,
    ProcessIntent,
    TimeLaw,
)
from offline_prog.errors import InputError

ENTRIES = ("rest", "flying")  # path.entry / seams[].entry
MAX_LEAD_MM = 500.0  # motion.lead_mm: a lead is tens of millimetres


def _error(file, key, reason) -> InputError:
    return InputError(file, key, reason)


def _check_robots_dir(file: Path, model: str, folder: Path) -> None:
    """A cell's ``robot.robots_dir`` is a folder holding the robot: the robot is taken
    from there, never from a folder searched after it (a mistyped folder would plan
    with the bundled robot of the same name)."""
    if not folder.is_dir():
        raise _error(file, "robot.robots_dir", f"folder not found: {folder}")
    if find_robot(model, [folder]) is None:
        have = sorted({name for name, _, _ in robots_in([folder])})
        raise _error(
            file,
            "robot.robots_dir",
            f"{folder} holds no robot folder {model!r} (have: {', '.join(have) or 'none'}); "
            "without robots_dir the robot comes from OFFLINE_PROG_ROBOTS or the bundled ones",
        )


def check_cell(file: Path, cell: Cell, robots_dir: Path) -> None:
    """Semantic checks the types alone cannot express."""
    folders = search_path(robots_dir, cell_file=file, robots_dir=cell.robot.robots_dir)
    if cell.robot.robots_dir is not None:
        _check_robots_dir(file, cell.robot.model, folders[0])
    if find_robot(cell.robot.model, folders) is None:
        have = sorted({name for name, _, _ in robots_in(folders)})
        raise _error(
            file,
            "robot.model",
            f"{cell.robot.model!r} is not a robot folder in "
            f"{os.pathsep.join(map(str, folders))} (have: {', '.join(have) or 'none'})",
        )
    for key, pose in (
        ("robot.X_IB", cell.robot.X_IB),
        ("tool.X_IT", cell.tool.X_IT),
        ("part.X_PE", cell.part.X_PE),
    ):
        _check_translation(file, key, pose)
    motion = cell.motion
    if cell.part.mesh_units not in UNIT_SCALE:
        raise _error(
            file, "part.mesh_units", f"{cell.part.mesh_units!r} is not a unit (use m or mm)"
        )
    if cell.part.mesh is not None:
        _check_data_file(file, "part.mesh", file.parent / cell.part.mesh)
    check_part_model(file, cell, _check_data_file)
    if (cell.path is None) == (not cell.seams):
        raise _error(file, "seams", "give exactly one of path (one seam) or seams (a job)")
    for key, path in seam_keys(cell):
        _check_path(file, key, path, cell)
    # The process model first: it decides which of the flow's keys the cell gives.
    check_process(
        file, cell.process, None if cell.tool.process_io is None else cell.tool.process_io.flow
    )
    check_job(file, cell)
    for key, value in (
        ("motion.speed", motion.speed),
        ("motion.max_acceleration", motion.max_acceleration),
        ("motion.max_jerk", motion.max_jerk),
        ("motion.sample_rate_hz", motion.sample_rate_hz),
    ):
        if not value > 0:
            raise _error(file, key, f"must be > 0, got {value}")
    check_off_seam_speeds(file, motion)
    if motion.speed > MAX_SPEED_M_S:
        raise _error(
            file,
            "motion.speed",
            f"{motion.speed:g} m/s is more than {MAX_SPEED_M_S:g} m/s (the unit is m/s: "
            f"{motion.speed:g} mm/s is {motion.speed * 1e-3:g})",
        )
    if motion.sample_rate_hz > MAX_SAMPLE_RATE_HZ:
        raise _error(
            file,
            "motion.sample_rate_hz",
            f"{motion.sample_rate_hz:g} Hz is more than {MAX_SAMPLE_RATE_HZ:g} Hz",
        )
    if motion.speed_reference not in ("tcp", "flange"):
        raise _error(
            file, "motion.speed_reference", f"{motion.speed_reference!r} (use tcp or flange)"
        )
    if motion.time_law not in TIME_LAWS:
        raise _error(file, "motion.time_law", f"{motion.time_law!r} (use {' or '.join(TIME_LAWS)})")
    if motion.process not in PROCESS_INTENTS:
        raise _error(
            file, "motion.process", f"{motion.process!r} (use {' or '.join(PROCESS_INTENTS)})"
        )
    # The config boundary: from here on the law and the intent are enums.
    motion.time_law, motion.process = TimeLaw(motion.time_law), ProcessIntent(motion.process)
    if not 0.0 <= cell.tool.free_rotation_deg <= 180.0:
        raise _error(file, "tool.free_rotation_deg", "must be within [0, 180]")
    if cell.tool.symmetry_axis not in ("x", "y", "z"):
        raise _error(file, "tool.symmetry_axis", f"{cell.tool.symmetry_axis!r} (use x, y or z)")
    smoothing = cell.tool.turn_smoothing_mm
    if not (np.isfinite(smoothing) and smoothing >= 0.0):
        raise _error(file, "tool.turn_smoothing_mm", f"must be ≥ 0 mm, got {smoothing}")
    if smoothing > 0.0 and cell.tool.free_rotation_deg == 0.0:
        raise _error(file, "tool.turn_smoothing_mm", "needs tool.free_rotation_deg > 0")
    if motion.cusp_smoothing_mm is not None and not motion.cusp_smoothing_mm > 0:
        raise _error(file, "motion.cusp_smoothing_mm", "must be > 0")
    for key in ("clearance", "self_clearance"):
        if not getattr(motion, key) >= 0:
            raise _error(file, f"motion.{key}", f"must be ≥ 0 m, got {getattr(motion, key)}")
    check_payload(file, cell, _check_data_file)
    _check_shapes(file, cell)
    check_calibration(file, cell.calibration)
    check_controller_frames(file, cell, None)  # the robot's own ranges: stages.load_inputs


def seam_keys(cell: Cell) -> list[tuple[str, PathConfig]]:
    """(key, path) of each seam: ``[("path", cell.path)]`` for the one-seam shorthand,
    else ``("seams[k]", seam)``: the key that errors about it name."""
    if cell.path is not None:
        return [("path", cell.path)]
    return [(f"seams[{k}]", seam) for k, seam in enumerate(cell.seams)]


def _check_path(file: Path, key: str, path: PathConfig, cell: Cell) -> None:
    """One processing path (``path:`` or a seam): one source, units, normals, fit."""
    if path.units is None and path.cad is None:
        raise _error(file, f"{key}.units", "missing (required)")
    if path.units is not None and path.units not in UNIT_SCALE:
        raise _error(file, f"{key}.units", f"{path.units!r} is not a unit (use m or mm)")
    sources = [k for k in ("points", "dxf", "analytic", "cad") if getattr(path, k) is not None]
    if len(sources) != 1:
        raise _error(
            file,
            key,
            f"give exactly one of points, dxf, analytic, cad (got {', '.join(sources) or 'none'})",
        )
    if path.cad is not None:
        check_cad(file, key, path, cell, _check_data_file)
    for name in ("points", "dxf"):
        if getattr(path, name) is not None:
            _check_data_file(file, f"{key}.{name}", file.parent / getattr(path, name))
    if path.normal_from_mesh and cell.part.mesh is None:
        raise _error(file, f"{key}.normal_from_mesh", "needs part.mesh")
    if path.normal is not None and np.linalg.norm(path.normal) < 1e-9:
        raise _error(file, f"{key}.normal", "is the zero vector")
    if path.degree < 5:
        raise _error(file, f"{key}.degree", f"{path.degree} < 5 (the paper needs degree ≥ 5)")
    if path.entry not in ENTRIES:
        raise _error(
            file, f"{key}.entry", f"{path.entry!r} is not an entry (use {' or '.join(ENTRIES)})"
        )
    for name in ("fit_tolerance_mm", "normal_tolerance_deg"):
        if getattr(path, name) is not None and not getattr(path, name) > 0:  # None: cad:'s
            raise _error(file, f"{key}.{name}", f"must be > 0, got {getattr(path, name)}")


def _check_data_file(file: Path, key: str, data_file: Path) -> None:
    """A path or mesh file exists and is at most MAX_DATA_FILE_BYTES."""
    if not data_file.is_file():
        raise _error(file, key, f"file {data_file} does not exist")
    size = data_file.stat().st_size
    if size > MAX_DATA_FILE_BYTES:
        raise _error(file, key, f"{data_file}: {size:,} bytes, more than {MAX_DATA_FILE_BYTES:,}")


def _check_translation(file: Path, key: str, pose) -> None:
    """A pose's translation [m] within a cell (a pose typed in mm: the unit hint)."""
    too_far = far_translation(transform(pose).translation())
    if too_far:
        raise _error(file, f"{key}.translation", too_far)


def _check_shapes(file: Path, cell: Cell) -> None:
    """Shape names unique, mesh files present, allowed contacts naming known shapes."""
    owners = [
        ("part.geometry", cell.part.geometry),
        ("tool.geometry", cell.tool.geometry),
        ("obstacles", cell.obstacles),
        ("gripper.geometry", cell.gripper.geometry if cell.gripper else []),
    ]
    names = {cell.part.name} if cell.part.mesh or cell.part.model else set()
    if cell.gripper is not None and cell.gripper.mesh:
        if GRIPPER_MESH_NAME in names:
            raise _error(file, "gripper.mesh", f"shape name {GRIPPER_MESH_NAME!r} used twice")
        names.add(GRIPPER_MESH_NAME)
    for key, shapes in owners:
        for i, shape in enumerate(shapes):
            where = f"{key}[{i}]"
            if shape.name in names:
                raise _error(file, f"{where}.name", f"{shape.name!r} is used twice")
            names.add(shape.name)
            _check_translation(file, f"{where}.pose", shape.pose)
            if shape.shape not in ("box", "cylinder", "sphere", "capsule", "mesh"):
                raise _error(
                    file,
                    f"{where}.shape",
                    f"{shape.shape!r} (use box, cylinder, sphere, capsule or mesh)",
                )
            if shape.mesh_units not in UNIT_SCALE:
                raise _error(file, f"{where}.mesh_units", f"{shape.mesh_units!r} (use m or mm)")
            if shape.shape == "mesh":
                _check_data_file(file, f"{where}.mesh", file.parent / (shape.mesh or ""))
    for i, pair in enumerate(cell.allowed_contact):
        if len(pair) != 2:
            raise _error(file, f"allowed_contact[{i}]", f"expected [name, name], got {pair}")
        for name in pair:
            if name not in names:
                raise _error(
                    file,
                    f"allowed_contact[{i}]",
                    f"{name!r} is not a shape of the "
                    f"cell (have: {', '.join(sorted(names)) or 'none'})",
                )


def check_off_seam_speeds(file: Path, motion) -> None:
    """``motion.approach_speed`` within (0, MAX_SPEED_M_S] m/s (the controllers' path
    speed limit: KUKA $VEL.CP, FANUC 2000 mm/sec), ``motion.link_speed_percent``
    within (0, 100] % and ``motion.lead_mm`` within [0, MAX_LEAD_MM]."""
    speed = motion.approach_speed
    if speed is not None and not (np.isfinite(speed) and 0.0 < speed <= MAX_SPEED_M_S):
        raise _error(
            file,
            "motion.approach_speed",
            f"must be within (0, {MAX_SPEED_M_S:g}] m/s (the robot's path speed limit), "
            f"got {speed:g}",
        )
    percent = motion.link_speed_percent
    if not (np.isfinite(percent) and 0.0 < percent <= 100.0):
        raise _error(
            file, "motion.link_speed_percent", f"must be within (0, 100] %, got {percent:g}"
        )
    lead = motion.lead_mm
    if lead is not None and not (np.isfinite(lead) and 0.0 <= lead <= MAX_LEAD_MM):
        raise _error(
            file, "motion.lead_mm", f"must be within [0, {MAX_LEAD_MM:g}] mm, got {lead:g}"
        )
