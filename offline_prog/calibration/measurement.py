"""The measurement model: each touch as a flange pose and the distance it leaves
between the two points the technician put together.

Frames (paper letters): I inertial, B robot base, E flange, T fixed tool, P part. A
touch with joints q puts the flange at X_IE = X_IB · X_BE(q), with the robot's own
forward kinematics (``RobotModel.forward``, the plan's; the URDF chain for a robot
without a closed form). Unknowns (positions in mm, angles in rad):

- ``p_IT``: the tool's tip T in I (3);
- ``pointer``: the pointer's tip p_EQ in E (3);
- ``axis``: the tilt (a1, a2) of T's +z axis: z_T = unit(z0 + a1 x0 + a2 y0), with
  x0, y0, z0 the cell's axes of T in I (2); R_IT is then the cell's turned by the
  smallest rotation from z0 to z_T, so the rotation about the axis stays the cell's;
- ``grasp_translation`` (3) and ``grasp_rotation`` (3): X_PE with p_PE = p0 + δp and
  R_PE = R0 · exp([ω]×) (ω in E).

Residual of a touch, in I [mm] (zero for perfect data):

- ``tool_tip``:  X_IE p_EQ − p_IT;
- ``tool_axis``: X_IE p_EQ − (p_IT + d z_T), d = ``tool_axis_point_mm``;
- a part point p_PK: X_IE X_EP p_PK − p_IT, X_EP = X_PE⁻¹.

The Jacobian is analytic (:meth:`Problem.jacobian`): −I for p_IT, R_IE for the
pointer, −d (I − z zᵀ)/|w| [x0 y0] for the tilt, −R_IE R_PEᵀ for δp and
R_IE [p_EK]× J_r(ω) for ω (J_r the right Jacobian of SO(3), p_EK = R_PEᵀ (p_PK − p_PE)).

Only the blocks the touches can determine are unknowns; the others keep the cell's
values. Least squares over these residuals (``estimate``) identifies the frames from
the measurements as Rameder, Gattringer, Müller, arXiv 2510.25338 (2025), identify
error parameters.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.calibration.touches import Touches
from offline_prog.config.calibration_keys import TOOL_AXIS, TOOL_TIP, CalibrationConfig
from offline_prog.robot.jacobian import joint_frames, urdf_chain
from offline_prog.robot.model import RobotModel

TIP, AXIS, PART = 0, 1, 2  # the kinds of touch
BLOCKS = {"p_IT": 3, "pointer": 3, "axis": 2, "grasp_translation": 3, "grasp_rotation": 3}


def flange_poses(robot: RobotModel, X_IB: np.ndarray, q: np.ndarray) -> np.ndarray:
    """X_IE (N, 4, 4) [m] of joint vectors q (N, 6) [rad] (URDF convention), the base
    at X_IB (4, 4) [m]."""
    if robot.params is not None:
        X_BE = robot.forward(q)
    else:  # family drake: the URDF's chain
        X_BE = joint_frames(urdf_chain(robot.urdf_path, robot.joint_names), q)[2]
    return X_IB @ X_BE


def axis_derivative(R_IT: np.ndarray, a: np.ndarray) -> np.ndarray:
    """(3, 2) dz_T/da: how the tilted axis unit(z0 + a1 x0 + a2 y0) moves with (a1, a2)."""
    w = R_IT[:, 2] + R_IT[:, :2] @ a
    z = w / np.linalg.norm(w)
    return (np.eye(3) - np.outer(z, z)) / np.linalg.norm(w) @ R_IT[:, :2]


@dataclasses.dataclass(frozen=True)
class Nominal:
    """The cell's values: the start of the estimate and what an unknown not estimated
    keeps. Positions [mm], rotations (3, 3)."""

    p_IT: np.ndarray
    R_IT: np.ndarray
    pointer: np.ndarray  # pointer_mm, or zeros
    axis_mm: float | None  # tool_axis_point_mm
    p_PE: np.ndarray
    R_PE: np.ndarray


@dataclasses.dataclass(frozen=True)
class Values:
    """The cell's frames a parameter vector means: p_IT [mm], R_IT, the pointer's tip
    p_EQ [mm], p_PE [mm], R_PE."""

    p_IT: np.ndarray
    R_IT: np.ndarray
    pointer: np.ndarray
    p_PE: np.ndarray
    R_PE: np.ndarray


def skew(v: np.ndarray) -> np.ndarray:
    """(..., 3, 3) [v]×: skew(v) @ u = v × u, for v (..., 3)."""
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2], out[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    out[..., 1, 0], out[..., 2, 0], out[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    return out


def right_jacobian(rotvec: np.ndarray) -> np.ndarray:
    """(3, 3) J_r(ω) of SO(3): exp([ω + dω]×) ≈ exp([ω]×) exp([J_r(ω) dω]×)."""
    angle = float(np.sqrt(rotvec @ rotvec))
    K = skew(rotvec)
    if angle < 1e-8:
        return np.eye(3) - 0.5 * K
    return (
        np.eye(3)
        - (1.0 - np.cos(angle)) / angle**2 * K
        + (angle - np.sin(angle)) / angle**3 * (K @ K)
    )


def rotation(rotvec: np.ndarray) -> np.ndarray:
    """(3, 3) the rotation by a rotation vector (3,) [rad] (Rodrigues; the residuals call
    it often, scipy's Rotation costs ten times as much per call)."""
    angle = float(np.sqrt(rotvec @ rotvec))
    if angle < 1e-12:
        return np.eye(3)
    K = skew(rotvec / angle)
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)


def axis_rotation(R_IT: np.ndarray, a: np.ndarray) -> np.ndarray:
    """R_IT tilted by (a1, a2) [rad] (module docstring): the smallest rotation from
    the cell's z axis of T to unit(z0 + a1 x0 + a2 y0), applied to R_IT (3, 3)."""
    z0 = R_IT[:, 2]
    z = z0 + a[0] * R_IT[:, 0] + a[1] * R_IT[:, 1]
    z = z / np.linalg.norm(z)
    axis = np.cross(z0, z)
    angle = np.arctan2(np.linalg.norm(axis), z0 @ z)
    if angle == 0.0:
        return R_IT
    return rotation(axis / np.linalg.norm(axis) * angle) @ R_IT


@dataclasses.dataclass(frozen=True)
class Problem:
    """The touches as a least-squares problem.

    Attributes:
        touches: the touches (targets, lines, joints).
        X_IE: (N, 4, 4) each touch's flange pose [m].
        kinds: (N,) TIP, AXIS or PART.
        p_PK: (N, 3) the part point of each PART touch in P [mm] (NaN otherwise).
        nominal: the cell's values.
        blocks: the unknowns estimated, in BLOCKS' order.
        part_points: calibration.part_points {name: [x, y, z] in P [mm]}, touched or not.
    """

    touches: Touches
    X_IE: np.ndarray
    kinds: np.ndarray
    p_PK: np.ndarray
    nominal: Nominal
    blocks: tuple[str, ...]
    part_points: dict[str, list[float]]

    @classmethod
    def of(cls, touches: Touches, X_IE: np.ndarray, calibration: CalibrationConfig, nominal):
        """The problem of ``touches`` (flange poses X_IE (N, 4, 4) [m])."""
        kinds = np.array(
            [{TOOL_TIP: TIP, TOOL_AXIS: AXIS}.get(t, PART) for t in touches.targets], dtype=int
        )
        points = calibration.part_points
        p_PK = np.array([points.get(t, [np.nan] * 3) for t in touches.targets], dtype=float)
        blocks = ["p_IT"]
        if np.isin(kinds, (TIP, AXIS)).any():
            blocks.append("pointer")
        if (kinds == AXIS).any():
            blocks.append("axis")
        if (kinds == PART).any():
            blocks += ["grasp_translation", "grasp_rotation"]
        return cls(touches, X_IE, kinds, p_PK, nominal, tuple(blocks), dict(points))

    def without(self, i: int) -> Problem:
        """The problem less touch i (the unknowns stay those of the whole file)."""
        keep = np.arange(len(self.kinds)) != i
        return dataclasses.replace(
            self,
            touches=self.touches.without(i),
            X_IE=self.X_IE[keep],
            kinds=self.kinds[keep],
            p_PK=self.p_PK[keep],
        )

    def layout(self) -> dict[str, slice]:
        """{block: its slice of the parameter vector}."""
        out, start = {}, 0
        for name in self.blocks:
            out[name] = slice(start, start + BLOCKS[name])
            start += BLOCKS[name]
        return out

    def size(self) -> int:
        return sum(BLOCKS[name] for name in self.blocks)

    def values(self, x: np.ndarray) -> Values:
        """The frames parameter vector x means (the cell's where not estimated)."""
        n, at = self.nominal, self.layout()
        p_IT = x[at["p_IT"]]
        pointer = x[at["pointer"]] if "pointer" in at else n.pointer
        R_IT = axis_rotation(n.R_IT, x[at["axis"]]) if "axis" in at else n.R_IT
        p_PE, R_PE = n.p_PE, n.R_PE
        if "grasp_translation" in at:
            p_PE = n.p_PE + x[at["grasp_translation"]]
            R_PE = n.R_PE @ rotation(x[at["grasp_rotation"]])
        return Values(p_IT, R_IT, pointer, p_PE, R_PE)

    def start(self, values: Values) -> np.ndarray:
        """The parameter vector of ``values`` (the inverse of :meth:`values`)."""
        n, x = self.nominal, np.zeros(self.size())
        at = self.layout()
        x[at["p_IT"]] = values.p_IT
        if "pointer" in at:
            x[at["pointer"]] = values.pointer
        if "axis" in at:
            z = values.R_IT[:, 2]
            x[at["axis"]] = (z @ n.R_IT[:, :2]) / (z @ n.R_IT[:, 2])
        if "grasp_translation" in at:
            x[at["grasp_translation"]] = values.p_PE - n.p_PE
            x[at["grasp_rotation"]] = Rotation.from_matrix(n.R_PE.T @ values.R_PE).as_rotvec()
        return x

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """(N, 3) each touch's residual in I [mm] (module docstring)."""
        v = self.values(x)
        R_IE, p_IE = self.X_IE[:, :3, :3], self.X_IE[:, :3, 3] * 1e3
        reached = np.empty((len(self.kinds), 3))
        target = np.broadcast_to(v.p_IT, reached.shape).copy()
        pointer = self.kinds != PART
        reached[pointer] = p_IE[pointer] + R_IE[pointer] @ v.pointer
        axis = self.kinds == AXIS
        if axis.any():
            target[axis] += self.nominal.axis_mm * v.R_IT[:, 2]
        part = ~pointer
        p_EK = (self.p_PK[part] - v.p_PE) @ v.R_PE  # R_PEᵀ (p_PK − p_PE), row by row
        reached[part] = p_IE[part] + np.einsum("nij,nj->ni", R_IE[part], p_EK)
        return reached - target

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """(3N, n) the residuals' derivatives by the unknowns (module docstring)."""
        v, at, n = self.values(x), self.layout(), self.nominal
        R_IE = self.X_IE[:, :3, :3]
        J = np.zeros((len(self.kinds), 3, self.size()))
        J[:, :, at["p_IT"]] = -np.eye(3)
        pointer = self.kinds != PART
        if "pointer" in at:
            J[pointer, :, at["pointer"]] = R_IE[pointer]
        if "axis" in at:
            dz = axis_derivative(n.R_IT, x[at["axis"]])
            J[self.kinds == AXIS, :, at["axis"]] = -n.axis_mm * dz
        if "grasp_translation" in at:
            part = ~pointer
            p_EK = (self.p_PK[part] - v.p_PE) @ v.R_PE
            J[part, :, at["grasp_translation"]] = -R_IE[part] @ v.R_PE.T
            J_r = right_jacobian(x[at["grasp_rotation"]])
            J[part, :, at["grasp_rotation"]] = R_IE[part] @ skew(p_EK) @ J_r
        return J.reshape(-1, self.size())
