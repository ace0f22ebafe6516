"""ProgramData: what a controller program needs from a plan, saved with the plan.

Frames (paper letters): B robot base (URDF base_link), E flange (tool0), P part,
F process frame on the path, T fixed tool. All poses are 4×4 arrays in SI units;
the writers convert to each vendor's units and angle conventions at the edge.
``plan.npz`` (the job's rows) and ``job.npz`` (each seam's rows, see ``job_program``)
in the plan folder hold it, so ``offline-prog export`` re-exports without re-planning.
They store ``path_m`` and the tool frame ``X_PT`` under the keys plans have always had
(``sigma``, ``X_PF``, ``sigma_dense``, ``X_PF_dense``): on a seam the tool frame is the
process frame and the path position is its arc length σ.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from offline_prog.atomic import atomic_stream

PLAN_FILE = "plan.npz"
# The arrays by field name, and the key each is stored under in the .npz files.
_ARRAYS = {
    "t": "t",
    "path_m": "sigma",
    "q": "q",
    "qd": "qd",
    "X_BE": "X_BE",
    "X_PT": "X_PF",
    "X_BT": "X_BT",
    "X_EP": "X_EP",
    "tcp_speed": "tcp_speed",
    "q_lower": "q_lower",
    "q_upper": "q_upper",
    "qd_max": "qd_max",
}
# The continuous path on a fine grid of s (plans written before it existed lack it).
_DENSE_ARRAYS = {"path_dense_m": "sigma_dense", "X_PT_dense": "X_PF_dense", "q_dense": "q_dense"}
_STORED = _ARRAYS | _DENSE_ARRAYS


@dataclasses.dataclass(frozen=True)
class ProgramData:
    """A finished plan, as the program writers see it.

    Attributes:
        cell_name, cell_file, robot, tool, part: names for the program header.
        process_speed_m_s: the commanded TCP speed [m/s]; speed_reference: tcp | flange.
        cycle_time_s: planned duration [s].
        feasible: the plan passed every check; failure: why not ("" if feasible).
        joint_names: the six URDF joint names, in q's column order.
        t: (N,) time [s].
        path_m: (N,) position along the tool's path on the part [m]: on a seam its arc
            length σ; on a job's rows signed from each seam's start (negative on the
            approach, beyond the seam's length on the retract, NaN on links).
        q: (N, 6) joint positions [rad]; qd: (N, 6) joint speeds [rad/s].
        X_BE: (N, 4, 4) flange E in the robot base B.
        X_PT: (N, 4, 4) the tool frame T in the part frame P: on a seam the process
            frame F (turned by any free rotation about the tool's axis), on the approach
            and retract the frame backed off the seam's end.
        X_BT: (4, 4) the fixed tool frame T in B (with any free rotation applied).
        X_EP: (4, 4) the part frame P in the flange frame E.
        tcp_speed: (N,) speed of the path point under the TCP [m/s].
        q_lower, q_upper, qd_max: (6,) joint limits [rad, rad/s] of the controller's
            joints (see j23_coupled).
        generated: ISO time the plan was made.
        path_dense_m: (M,) a fine grid of s [m] over the whole path (export.densify).
        X_PT_dense: (M, 4, 4) the tool frames of the continuous plan at path_dense_m,
            so that point selection measures deviations between the samples too.
        q_dense: (M, 6) the planned joints [rad] at path_dense_m (robot.dense_joints),
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
    path_m: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    X_BE: np.ndarray
    X_PT: np.ndarray
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
    # The controller's frame numbers from the cell: {"tool": n | None, "part": m | None}
    # (export.frames; None: a plan made before programs referenced them).
    controller_frames: dict | None = None
    # The process time law (motion.time_law, and motion.process for time_optimal).
    time_law: str = "sin2"
    path_dense_m: np.ndarray = dataclasses.field(default_factory=lambda: np.empty(0))
    X_PT_dense: np.ndarray = dataclasses.field(default_factory=lambda: np.empty((0, 4, 4)))
    q_dense: np.ndarray = dataclasses.field(default_factory=lambda: np.empty((0, 6)))
    # These rows are a whole job's (job.npz beside them holds its segments and I/O).
    whole_job: bool = False
    # The plan's robot (robot.record.robot_record); None: a plan made before plans
    # carried it, whose robot is looked up by name.
    robot_record: dict | None = None
    # A seam's approach and retract speed [m/s] (config.process_speed.approach_speed;
    # None: the job's rows, or a plan before motion.approach_speed: the process speed).
    approach_speed_m_s: float | None = None
    link_speed_percent: float = 100.0  # motion.link_speed_percent: the links' PTP override

    @property
    def off_seam_speed_m_s(self) -> float:
        """The speed the seam's approach and retract run at [m/s]."""
        if self.approach_speed_m_s is None:
            return self.process_speed_m_s
        return self.approach_speed_m_s

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
        """(meta, arrays): the JSON-able header fields, and the arrays by their stored
        names (see the module docstring)."""
        meta = {
            f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name not in _STORED
        }
        meta["joint_names"] = list(self.joint_names)
        return meta, {key: getattr(self, name) for name, key in _STORED.items()}

    @classmethod
    def unpacked(cls, meta: dict, arrays: dict[str, np.ndarray]) -> ProgramData:
        """The inverse of :meth:`packed` (KeyError / TypeError when incomplete)."""
        meta = {**meta, "joint_names": tuple(meta["joint_names"])}
        return cls(**meta, **{name: arrays[key] for name, key in _STORED.items() if key in arrays})

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
                arrays = {key: np.asarray(data[key]) for key in _ARRAYS.values()}
                arrays |= {
                    key: np.asarray(data[key]) for key in _DENSE_ARRAYS.values() if key in data
                }
        except FileNotFoundError:
            raise ValueError(f"{file}: not a plan folder (no {PLAN_FILE})") from None
        except Exception as error:  # truncated or foreign: zipfile, zlib, pickle, json ...
            raise ValueError(f"{file}: unreadable, not a complete plan ({error})") from None
        try:
            return cls.unpacked(meta, arrays)
        except (KeyError, TypeError) as error:
            raise ValueError(f"{file}: not a plan of this version ({error})") from None
