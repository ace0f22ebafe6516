"""ProgramData: what a controller program needs from a plan, saved with the plan.

Frames (paper letters): B robot base (URDF base_link), E flange (tool0), P part,
F process frame on the path, T fixed tool. All poses are 4×4 arrays in SI units;
the writers convert to each vendor's units and angle conventions at the edge.
``plan.npz`` in the plan folder holds it, so ``offline-prog export`` re-exports
without re-planning.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from offline_prog.atomic import atomic_stream

PLAN_FILE = "plan.npz"
_ARRAYS = (
    "t",
    "sigma",
    "q",
    "qd",
    "X_BE",
    "X_PF",
    "X_BT",
    "X_EP",
    "tcp_speed",
    "q_lower",
    "q_upper",
    "qd_max",
)
# The continuous path on a fine grid of s (plans written before it existed lack it).
_DENSE_ARRAYS = ("sigma_dense", "X_PF_dense", "q_dense")


@dataclasses.dataclass(frozen=True)
class ProgramData:
    """A finished plan, as the program writers see it.

    Attributes:
        cell_name, cell_file, robot, tool, part: names for the program header.
        process_speed_m_s: the commanded TCP speed [m/s]; speed_reference: tcp | flange.
        cycle_time_s: planned duration [s].
        feasible: the plan passed every check; failure: why not ("" if feasible).
        joint_names: the six URDF joint names, in q's column order.
        t: (N,) time [s]; sigma: (N,) arc length on the processing path [m].
        q: (N, 6) joint positions [rad]; qd: (N, 6) joint speeds [rad/s].
        X_BE: (N, 4, 4) flange E in the robot base B.
        X_PF: (N, 4, 4) process frame F (the tool's pose on the part) in P.
        X_BT: (4, 4) the fixed tool frame T in B (with any free rotation applied).
        X_EP: (4, 4) the part frame P in the flange frame E.
        tcp_speed: (N,) speed of the path point under the TCP [m/s].
        q_lower, q_upper, qd_max: (6,) joint limits [rad, rad/s] of the controller's
            joints (see j23_coupled).
        generated: ISO time the plan was made.
        sigma_dense: (M,) a fine grid of s [m] over the whole path (export.densify).
        X_PF_dense: (M, 4, 4) the process frames of the continuous plan at sigma_dense,
            so that point selection measures deviations between the samples too.
        q_dense: (M, 6) the planned joints [rad] at sigma_dense (robot.dense_joints),
            which the writers read for points they insert (empty: an older plan).
    """

    cell_name: str
    cell_file: str
    robot: str
    tool: str
    part: str
    process_speed_m_s: float
    speed_reference: str
    cycle_time_s: float
    feasible: bool
    failure: str
    joint_names: tuple[str, ...]
    generated: str
    t: np.ndarray
    sigma: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    X_BE: np.ndarray
    X_PF: np.ndarray
    X_BT: np.ndarray
    X_EP: np.ndarray
    tcp_speed: np.ndarray
    q_lower: np.ndarray
    q_upper: np.ndarray
    qd_max: np.ndarray
    j23_coupled: bool = False  # the controller counts axis 3 as q3 + j23_factor·q2
    j23_factor: float = 1.0  # +1: ABB (q2 + q3); -1: FANUC (q3 − q2)
    robots_dir: str = ""  # the folder the plan's robot folder was found in ("": search)
    language: str | None = None  # the controller's program format (robot.yaml)
    payload: dict | None = None  # export.payload.payload_record (None: plan before payloads)
    # The process time law (motion.time_law, and motion.process for time_optimal).
    time_law: str = "sin2"
    sigma_dense: np.ndarray = dataclasses.field(default_factory=lambda: np.empty(0))
    X_PF_dense: np.ndarray = dataclasses.field(default_factory=lambda: np.empty((0, 4, 4)))
    q_dense: np.ndarray = dataclasses.field(default_factory=lambda: np.empty((0, 6)))
    # These rows are a whole job's (job.npz beside them holds its segments and I/O).
    whole_job: bool = False
    # The plan's robot (robot.record.robot_record); None: a plan made before plans
    # carried it, whose robot is looked up by name.
    robot_record: dict | None = None

    def load_robot(self):
        """The plan's RobotModel, built from the robot record the plan carries (no
        robot folder is read). A plan made before plans carried it: from robots_dir
        when it still holds the robot, else from the search path."""
        from offline_prog.robot.model import load_robot
        from offline_prog.robot.record import robot_from_record

        if self.robot_record is not None:
            return robot_from_record(self.robot_record)
        folder = Path(self.robots_dir) if self.robots_dir else None
        has = folder is not None and (folder / self.robot / "robot.yaml").is_file()
        return load_robot(self.robot, folder if has else None)

    def controller_column(self, col: dict, prefix: str, j: int) -> np.ndarray:
        """Column ``<prefix><j+1>`` of a trajectory table as the controller counts it
        (the joint limits apply to that): axis 3 is q3 + j23_factor·q2 on coupled robots."""
        values = col[f"{prefix}{j + 1}"]
        coupled = self.j23_coupled and j == 2
        return values + self.j23_factor * col[f"{prefix}2"] if coupled else values

    def packed(self) -> tuple[dict, dict[str, np.ndarray]]:
        """(meta, arrays): the JSON-able header fields and the arrays by name."""
        meta = {
            f.name: getattr(self, f.name)
            for f in dataclasses.fields(self)
            if f.name not in _ARRAYS + _DENSE_ARRAYS
        }
        meta["joint_names"] = list(self.joint_names)
        return meta, {name: getattr(self, name) for name in _ARRAYS + _DENSE_ARRAYS}

    @classmethod
    def unpacked(cls, meta: dict, arrays: dict[str, np.ndarray]) -> ProgramData:
        """The inverse of :meth:`packed` (KeyError / TypeError when incomplete)."""
        meta = {**meta, "joint_names": tuple(meta["joint_names"])}
        return cls(**meta, **{k: v for k, v in arrays.items() if k in _ARRAYS + _DENSE_ARRAYS})

    def save(self, folder: Path) -> Path:
        """Write ``folder/plan.npz`` (arrays plus a JSON header), atomically; stored
        uncompressed (np.savez): zlib took 15 times as long to save a third of the size
        of the floats."""
        meta, arrays = self.packed()
        target = Path(folder) / PLAN_FILE
        with atomic_stream(target) as stream:
            np.savez(stream, meta=json.dumps(meta), **arrays)
        return target

    @classmethod
    def load(cls, folder: Path) -> ProgramData:
        """Read ``folder/plan.npz``.

        Raises:
            ValueError: one line naming the file when it is missing or unreadable.
        """
        file = Path(folder) / PLAN_FILE
        try:
            with np.load(file) as data:
                meta = json.loads(str(data["meta"]))
                arrays = {name: np.asarray(data[name]) for name in _ARRAYS}
                arrays |= {name: np.asarray(data[name]) for name in _DENSE_ARRAYS if name in data}
        except FileNotFoundError:
            raise ValueError(f"{file}: not a plan folder (no {PLAN_FILE})") from None
        except Exception as error:  # truncated or foreign: zipfile, zlib, pickle, json ...
            raise ValueError(f"{file}: unreadable, not a complete plan ({error})") from None
        try:
            return cls.unpacked(meta, arrays)
        except (KeyError, TypeError) as error:
            raise ValueError(f"{file}: not a plan of this version ({error})") from None
