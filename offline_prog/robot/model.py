"""Robots as data: one folder per robot with a URDF and a small parameter record.

Layout (``robots/`` at the repository root carries a ``package.xml`` naming the ROS
package ``offline_prog_robots``)::

    robots/<name>/<name>.urdf   standard URDF: base_link, link_1..link_6, tool0
    robots/<name>/robot.yaml    family, kinematic parameters, joint limits
    robots/<name>/README.md     the source of every number

``robot.yaml`` keeps degrees at the edge (``position_deg``, ``velocity_deg_s``,
``acceleration_deg_s2``, ``offsets_deg``); :func:`load_robot` converts to SI.
Frames: B robot base (URDF ``base_link``), E flange (URDF ``tool0``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from offline_prog.config.names import MAX_ROBOT_NAME_CHARS, name_problem
from offline_prog.config.robot_search import find_robot, robots_in, search_path
from offline_prog.robot import kinematics_opw, kinematics_ur
from offline_prog.robot.kinematics_opw import OpwParameters
from offline_prog.robot.kinematics_ur import UrParameters
from offline_prog.robot.record_checks import RecordChecker as _Checker

ROBOTS_DIR = Path(__file__).resolve().parents[1] / "robots"
PARAMS_FILE = "robot.yaml"
_TOP_KEYS = {"vendor", "family", "urdf", "joint_names", "kinematics", "limits", "controller"}
# Controller program languages a robot record may name (offline_prog.export writes each).
LANGUAGES = ("krl", "rapid", "urscript", "fanuc")
_KINEMATIC_KEYS = {
    "opw": ("a1", "a2", "b", "c1", "c2", "c3", "c4", "offsets_deg", "sign_corrections"),
    "ur": ("d1", "a2", "a3", "d4", "d5", "d6"),
    "drake": (),  # no closed form: joint paths come from Drake InverseKinematics
}
_LIMIT_KEYS = ("position_deg", "velocity_deg_s", "acceleration_deg_s2")
# limits.jerk_deg_s3 is optional: without it a joint reaches its acceleration limit in
# this time [s] (the bundled robots state the same assumption with its source).
JERK_RAMP_S = 0.1


@dataclass(frozen=True, eq=False)
class RobotModel:
    """One robot's kinematics and joint limits, in SI units.

    Attributes:
        name: Folder name under ``robots/``, e.g. ``"kuka_kr16_2"``.
        family: ``"opw"`` or ``"ur"``: which analytic kinematics applies; ``"drake"``
            for a robot without a closed form (Drake InverseKinematics only).
        params: Kinematic parameter record of that family (None for ``"drake"``).
        joint_names: The six URDF revolute joints, base to flange.
        q_lower: (6,) lower joint position limits [rad].
        q_upper: (6,) upper joint position limits [rad].
        qd_max: (6,) joint speed limits [rad/s].
        qdd_max: (6,) joint acceleration limits [rad/s^2].
        qddd_max: (6,) joint jerk limits [rad/s^3] (``limits.jerk_deg_s3``, else
            qdd_max / JERK_RAMP_S).
        urdf_path: Absolute path of the URDF.
        j23_coupled: the controller counts axis 3 from the horizontal, q3 + j23_factor·q2
            (see controller_joints).
        j23_factor: +1 (ABB: axis 3 = q2 + q3) or -1 (FANUC's ROS-I URDFs, whose axis 3
            turns the other way about the same line: J3 = q3 − q2).
        vendor: the maker, e.g. ``"kuka"`` (robot.yaml ``vendor``).
        language: the controller's program format (``krl``, ``rapid``, ``urscript``) or
            None (robot.yaml ``controller.language``).
        home_c: (6,) a safe home pose in the controller's axes [rad] (robot.yaml
            ``controller.home_deg``), where a job starts and ends unless the cell says.
    """

    name: str
    family: str
    params: OpwParameters | UrParameters | None
    joint_names: tuple[str, ...]
    q_lower: np.ndarray
    q_upper: np.ndarray
    qd_max: np.ndarray
    qdd_max: np.ndarray
    urdf_path: Path
    qddd_max: np.ndarray | None = None  # (6,) [rad/s³]; None: qdd_max / JERK_RAMP_S
    j23_coupled: bool = False
    j23_factor: float = 1.0
    vendor: str = ""
    language: str | None = None
    home_c: np.ndarray | None = None  # (6,) the controller's home axes [rad], or None

    @property
    def jerk_limits(self) -> np.ndarray:
        """(6,) joint jerk limits [rad/s³]: qddd_max, else qdd_max / JERK_RAMP_S."""
        return self.qdd_max / JERK_RAMP_S if self.qddd_max is None else self.qddd_max

    def controller_joints(self, q: np.ndarray) -> np.ndarray:
        """(..., 6) the joint values the controller counts (and limits) from URDF q.

        Equal to q, except on robots whose controller couples axis 3 to axis 2
        (``controller: {j23_coupled: true}``, e.g. the ABB IRB 2400: axis 3 = q2 + q3;
        FANUC: ``j23_factor: -1``, J3 = q3 − q2). Linear, so it maps joint speeds and
        accelerations the same way.
        """
        if not self.j23_coupled:
            return q
        out = np.array(q, dtype=float, copy=True)
        out[..., 2] = q[..., 2] + self.j23_factor * q[..., 1]
        return out

    def urdf_joints(self, q_c: np.ndarray) -> np.ndarray:
        """(..., 6) URDF q from the controller's axes: the inverse of controller_joints."""
        if not self.j23_coupled:
            return q_c
        out = np.array(q_c, dtype=float, copy=True)
        out[..., 2] = q_c[..., 2] - self.j23_factor * q_c[..., 1]
        return out

    def forward(self, q: np.ndarray) -> np.ndarray:
        """Flange poses X_BE (N, 4, 4) [m] for joint vectors q (N, 6) [rad]."""
        module = kinematics_opw if self.family == "opw" else kinematics_ur
        return module.forward(self.params, q)

    def inverse(self, X_BE: np.ndarray) -> np.ndarray:
        """All eight solutions (N, 8, 6) [rad] for flange poses X_BE (N, 4, 4) [m].

        Rows of NaN mark solutions that do not exist; limits are not applied.
        """
        module = kinematics_opw if self.family == "opw" else kinematics_ur
        return module.inverse(self.params, X_BE)

    def inverse_branch(self, X_BE: np.ndarray, branch: int) -> np.ndarray:
        """Solution ``branch`` (N, 6) [rad] of :meth:`inverse` for flange poses X_BE
        (N, 4, 4) [m]: the same numbers, computed alone where the family can.

        Raises:
            ValueError: branch is not one of 0..7.
        """
        if branch not in range(8):
            raise ValueError(f"branch: expected 0..7, got {branch!r}")
        if self.family == "opw":
            return kinematics_opw.inverse_branch(self.params, X_BE, branch)
        return self.inverse(X_BE)[:, branch]


def list_robots(robots_dir: Path | None = None) -> list[str]:
    """Names of the robot folders (those holding a robot.yaml), sorted; without
    robots_dir, those on the search path (config.robot_search)."""
    folders = search_path(ROBOTS_DIR) if robots_dir is None else [Path(robots_dir)]
    return sorted({name for name, _, _ in robots_in(folders)})


def load_robot(name: str, robots_dir: Path | None = None) -> RobotModel:
    """Loads ``<robots_dir>/<name>/robot.yaml`` and checks it.

    Args:
        name: Robot folder name, e.g. ``"ur10e"``.
        robots_dir: Folder holding the robot folders; default the search path
            (``OFFLINE_PROG_ROBOTS``, then the bundled ``robots/``: config.robot_search).

    Returns:
        The robot's model in SI units.

    Raises:
        ValueError: One line naming the file, the key and what was expected, when
            the folder, the record or the URDF is missing or a value is invalid.
    """
    folders = search_path(ROBOTS_DIR) if robots_dir is None else [Path(robots_dir)]
    folder = find_robot(name, folders) or folders[-1] / str(name)
    if not name or Path(name).name != name or name in (".", "..") or not folder.is_dir():
        known = ", ".join(list_robots(robots_dir)) or "none"
        raise ValueError(f"{folder}: no robot folder named {name!r} (known robots: {known})")
    problem = name_problem(name, max_chars=MAX_ROBOT_NAME_CHARS)
    if problem:
        raise ValueError(
            f"{folder}: {problem}: a robot's name heads its programs; rename the folder"
        )
    path = folder / PARAMS_FILE
    if not path.is_file():
        raise ValueError(f"{path}: file not found (each robot folder needs a {PARAMS_FILE})")
    try:
        record = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as error:
        raise ValueError(f"{path}: not valid YAML: {' '.join(str(error).split())}") from None
    check = _Checker(path)
    family = record.get("family") if isinstance(record, dict) else None
    optional = {"urdf", "controller", "vendor"} | ({"kinematics"} if family == "drake" else set())
    check.keys(record, "", required=_TOP_KEYS - optional, allowed=_TOP_KEYS)
    if family not in _KINEMATIC_KEYS:
        check.fail("family", family, f"one of {sorted(_KINEMATIC_KEYS)}")
    urdf_name = record.get("urdf", f"{name}.urdf")
    if (
        not isinstance(urdf_name, str)
        or Path(urdf_name).name != urdf_name
        or not (folder / urdf_name).is_file()
    ):
        check.fail("urdf", urdf_name, f"the name of a URDF file in {folder}")
    names = record["joint_names"]
    if (
        not isinstance(names, list)
        or len(names) != 6
        or not all(isinstance(n, str) and n for n in names)
        or len(set(names)) != 6
    ):
        check.fail("joint_names", names, "6 distinct joint names")
    for name_k in names:
        if problem := name_problem(name_k, max_chars=MAX_ROBOT_NAME_CHARS):
            check.fail("joint_names", names, f"joint names that head CSV columns ({problem})")
    limits = record["limits"]
    check.keys(limits, "limits", required=set(_LIMIT_KEYS), allowed={*_LIMIT_KEYS, "jerk_deg_s3"})
    position = check.numbers(limits["position_deg"], "limits.position_deg", shape=(6, 2))
    if not np.all(position[:, 0] < position[:, 1]):
        check.fail(
            "limits.position_deg", limits["position_deg"], "[lower, upper] with lower < upper"
        )
    velocity = check.numbers(limits["velocity_deg_s"], "limits.velocity_deg_s", positive=True)
    acceleration = check.numbers(
        limits["acceleration_deg_s2"], "limits.acceleration_deg_s2", positive=True
    )
    jerk = (
        np.radians(check.numbers(limits["jerk_deg_s3"], "limits.jerk_deg_s3", positive=True))
        if "jerk_deg_s3" in limits
        else np.radians(acceleration) / JERK_RAMP_S
    )
    return RobotModel(
        name=name,
        family=family,
        params=None
        if family == "drake"
        else _kinematic_params(check, family, record["kinematics"]),
        joint_names=tuple(names),
        q_lower=_frozen(np.radians(position[:, 0])),
        q_upper=_frozen(np.radians(position[:, 1])),
        qd_max=_frozen(np.radians(velocity)),
        qdd_max=_frozen(np.radians(acceleration)),
        urdf_path=(folder / urdf_name).resolve(),
        qddd_max=_frozen(jerk),
        j23_coupled=_j23_coupled(check, record.get("controller")),
        j23_factor=_j23_factor(check, record.get("controller")),
        vendor=str(record.get("vendor", "")),
        language=_language(check, record.get("controller")),
        home_c=_home(check, record.get("controller"), position),
    )


def _j23_coupled(check: _Checker, controller: Any) -> bool:
    """The ``controller: {j23_coupled: bool}`` record (default False)."""
    if controller is None:
        return False
    check.keys(
        controller,
        "controller",
        required=set(),
        allowed={"j23_coupled", "j23_factor", "language", "home_deg"},
    )
    value = controller.get("j23_coupled", False)
    if not isinstance(value, bool):
        check.fail("controller.j23_coupled", value, "true or false")
    return value


def _j23_factor(check: _Checker, controller: Any) -> float:
    """``controller: {j23_factor: 1 | -1}``: the sign of q2 in the controller's axis 3
    (default 1, ABB)."""
    value = 1 if controller is None else controller.get("j23_factor", 1)
    if isinstance(value, bool) or value not in (1, -1):
        check.fail("controller.j23_factor", value, "1 or -1")
    return float(value)


def _home(check: _Checker, controller: Any, position: np.ndarray) -> np.ndarray | None:
    """``controller: {home_deg: [6 numbers]}``: the controller's home axes [deg],
    inside the position limits (in the controller's axes), as radians; or None."""
    if controller is None or controller.get("home_deg") is None:
        return None
    home = check.numbers(controller["home_deg"], "controller.home_deg")
    if home.shape != (6,) or not np.all((position[:, 0] <= home) & (home <= position[:, 1])):
        check.fail("controller.home_deg", controller["home_deg"], "6 axes inside the limits")
    return _frozen(np.radians(home))


def _language(check: _Checker, controller: Any) -> str | None:
    """The ``controller: {language: krl | rapid | urscript}`` record (default None)."""
    if controller is None or controller.get("language") is None:
        return None
    if controller["language"] not in LANGUAGES:
        check.fail("controller.language", controller["language"], f"one of {', '.join(LANGUAGES)}")
    return controller["language"]


def _kinematic_params(
    check: _Checker, family: str, kinematics: Any
) -> OpwParameters | UrParameters:
    """Builds the family's parameter record from the ``kinematics`` mapping."""
    keys = _KINEMATIC_KEYS[family]
    check.keys(kinematics, "kinematics", required=set(keys), allowed=set(keys))
    lengths = {
        key: float(check.numbers(kinematics[key], f"kinematics.{key}", shape=()))
        for key in keys
        if key not in ("offsets_deg", "sign_corrections")
    }
    if family == "ur":
        return UrParameters(**lengths)
    offsets = check.numbers(kinematics["offsets_deg"], "kinematics.offsets_deg")
    signs = kinematics["sign_corrections"]
    if not isinstance(signs, list) or len(signs) != 6 or any(s not in (1, -1) for s in signs):
        check.fail("kinematics.sign_corrections", signs, "6 entries, each 1 or -1")
    return OpwParameters(
        **lengths,
        offsets=tuple(float(o) for o in np.radians(offsets)),
        sign_corrections=tuple(int(s) for s in signs),
    )


def _frozen(array: np.ndarray) -> np.ndarray:
    """Read-only float copy, so a frozen RobotModel stays unchanged."""
    array = np.array(array, dtype=float)
    array.flags.writeable = False
    return array
