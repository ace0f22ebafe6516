"""A RobotModel as a JSON record, so a plan carries its robot.

The program writers build the robot from the record stored in the plan
(``export.program.ProgramData.robot_record``) instead of reloading ``robots/<name>``:
an edited, renamed or removed robot folder does not change the program of an existing
plan. The record is in SI units (radians, metres), exactly the model's values.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
from pathlib import Path

import numpy as np

from offline_prog.robot.kinematics_opw import OpwParameters
from offline_prog.robot.kinematics_ur import UrParameters
from offline_prog.robot.model import RobotModel

_PARAMS = {"opw": OpwParameters, "ur": UrParameters}
_ARRAYS = ("q_lower", "q_upper", "qd_max", "qdd_max", "qddd_max", "home_c")


def robot_source(robot: RobotModel) -> dict:
    """Where the robot came from: ``robot_folder`` (absolute) and ``robot_files_sha256``,
    a hash over every file in it (relative path and content), so a report says which
    robot folder, and which state of it, a plan used."""
    folder = robot.urdf_path.parent
    return {"robot_folder": str(folder), "robot_files_sha256": folder_sha256(folder)}


def folder_sha256(folder: Path) -> str:
    """sha256 over the sorted lines ``<relative path> <sha256 of the file>`` of every
    regular file below ``folder`` (symbolic links to folders not followed)."""
    folder = Path(folder)
    lines = []
    for root, _, names in os.walk(folder):
        for name in names:
            file = Path(root) / name
            if file.is_file():
                digest = hashlib.sha256(file.read_bytes()).hexdigest()
                lines.append(f"{file.relative_to(folder).as_posix()} {digest}\n")
    return hashlib.sha256("".join(sorted(lines)).encode()).hexdigest()


def robot_record(robot: RobotModel) -> dict:
    """The model as JSON-able data: names, family, kinematic parameters, joint limits
    [rad, rad/s, rad/s², rad/s³], controller conventions and home [rad], and where it
    came from (:func:`robot_source`; not read back)."""
    return {
        **robot_source(robot),
        "name": robot.name,
        "family": robot.family,
        "params": None if robot.params is None else dataclasses.asdict(robot.params),
        "joint_names": list(robot.joint_names),
        **{
            key: None if getattr(robot, key) is None else np.asarray(getattr(robot, key)).tolist()
            for key in _ARRAYS
        },
        "urdf_path": str(robot.urdf_path),
        "j23_coupled": robot.j23_coupled,
        "j23_factor": robot.j23_factor,
        "vendor": robot.vendor,
        "language": robot.language,
    }


def robot_from_record(record: dict) -> RobotModel:
    """The RobotModel of :func:`robot_record`'s output (no file is read).

    Raises:
        KeyError, TypeError: an incomplete record.
    """
    params = record["params"]
    family = record["family"]
    if params is not None:
        params = _PARAMS[family](**{k: _tuple(v) for k, v in params.items()})
    arrays = {key: None if record[key] is None else _frozen(record[key]) for key in _ARRAYS}
    return RobotModel(
        name=record["name"],
        family=family,
        params=params,
        joint_names=tuple(record["joint_names"]),
        urdf_path=Path(record["urdf_path"]),
        j23_coupled=bool(record["j23_coupled"]),
        j23_factor=float(record["j23_factor"]),
        vendor=str(record["vendor"]),
        language=record["language"],
        **arrays,
    )


def _tuple(value):
    """JSON lists back to the parameter records' tuples."""
    return tuple(value) if isinstance(value, list) else value


def _frozen(values) -> np.ndarray:
    array = np.array(values, dtype=float)
    array.flags.writeable = False
    return array
