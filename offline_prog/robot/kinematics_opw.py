"""Analytic kinematics of ortho-parallel robots with a spherical wrist (OPW).

Implements the closed-form forward and inverse kinematics of

    M. Brandstötter, A. Angerer, M. Hofbaur, "An Analytical Solution of the Inverse
    Kinematics Problem of Industrial Serial Manipulators with an Ortho-parallel Basis
    and a Spherical Wrist", Austrian Robotics Workshop 2014,

with the parameter conventions of Jmeyer1292/opw_kinematics (offsets and sign
corrections map the paper's joint angles onto the controller's). Every function
is vectorized over samples: one row per joint vector or pose, no Python loops.

Frames: B is the robot base (URDF ``base_link``), E the flange (URDF ``tool0``,
z out of the flange). C is the paper's wrist-centre frame (axis 4 along its z).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# |sin(theta5)| below this counts as the wrist singularity: joint 4 is set to zero and
# joint 6 takes the whole rotation about the common axis.
WRIST_SINGULAR_SIN = 1e-12
# acos/sqrt arguments this far outside their domain are rounding, not unreachability.
DOMAIN_SLACK = 1e-12


@dataclass(frozen=True)
class OpwParameters:
    """Geometry of an OPW robot, as in the paper's Fig. 1 and opw_kinematics.

    Attributes:
        a1: Offset of axis 2 from axis 1, along the base x axis [m].
        a2: Offset of the wrist centre from the axis-3 line, perpendicular to the
            forearm [m] (the sign is the paper's: positive lowers the wrist when the
            forearm is horizontal).
        b: Lateral offset of the arm plane from axis 1 [m].
        c1: Height of axis 2 above the base [m].
        c2: Length from axis 2 to axis 3 [m].
        c3: Length from axis 3 to the wrist centre [m].
        c4: Length from the wrist centre to the flange [m].
        offsets: (6,) angle added to the paper's joint angle before sign correction
            [rad]: ``q_robot = (theta + offset) * sign``.
        sign_corrections: (6,) +1 or -1 per joint.
    """

    a1: float
    a2: float
    b: float
    c1: float
    c2: float
    c3: float
    c4: float
    offsets: tuple[float, float, float, float, float, float] = (0.0,) * 6
    sign_corrections: tuple[int, int, int, int, int, int] = (1,) * 6


def _rot_z(theta: np.ndarray) -> np.ndarray:
    """Rotation matrices about z: theta (...,) [rad] -> (..., 3, 3)."""
    c, s = np.cos(theta), np.sin(theta)
    z, o = np.zeros_like(theta), np.ones_like(theta)
    return np.stack([c, -s, z, s, c, z, z, z, o], axis=-1).reshape(theta.shape + (3, 3))


def _rot_y(theta: np.ndarray) -> np.ndarray:
    """Rotation matrices about y: theta (...,) [rad] -> (..., 3, 3)."""
    c, s = np.cos(theta), np.sin(theta)
    z, o = np.zeros_like(theta), np.ones_like(theta)
    return np.stack([c, z, s, z, o, z, -s, z, c], axis=-1).reshape(theta.shape + (3, 3))


def _rot_z_rot_y(theta_z: np.ndarray, theta_y: np.ndarray) -> np.ndarray:
    """Rz(theta_z) Ry(theta_y) for theta_z, theta_y (...,) [rad] -> (..., 3, 3), written
    out: the numbers of ``_rot_z(theta_z) @ _rot_y(theta_y)`` (each entry one product
    or one factor; the product's other terms are zeros) at a third of its cost."""
    cz, sz, cy, sy = np.cos(theta_z), np.sin(theta_z), np.cos(theta_y), np.sin(theta_y)
    R = np.empty(theta_z.shape + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 0, 2] = cz * cy, -sz, cz * sy
    R[..., 1, 0], R[..., 1, 1], R[..., 1, 2] = sz * cy, cz, sz * sy
    R[..., 2, 0], R[..., 2, 1], R[..., 2, 2] = -sy, 0.0, cy
    return R


def acos_clipped(x: np.ndarray) -> np.ndarray:
    """arccos that forgives rounding just outside [-1, 1] and is NaN beyond it."""
    x = np.where(np.abs(x) <= 1.0 + DOMAIN_SLACK, np.clip(x, -1.0, 1.0), np.nan)
    return np.arccos(x)


def wrap_to_pi(q: np.ndarray) -> np.ndarray:
    """Wraps angles to [-pi, pi); NaN stays NaN."""
    return np.mod(q + np.pi, 2.0 * np.pi) - np.pi


def check_joints(q: np.ndarray) -> np.ndarray:
    """Returns q as float (N, 6), or raises ValueError naming the argument."""
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or q.shape[1] != 6:
        raise ValueError(f"q: expected joint vectors of shape (N, 6), got {q.shape}")
    return q


def check_poses(X_BE: np.ndarray) -> np.ndarray:
    """Returns X_BE as float (N, 4, 4), or raises ValueError naming the argument."""
    X_BE = np.asarray(X_BE, dtype=float)
    if X_BE.ndim != 3 or X_BE.shape[1:] != (4, 4):
        raise ValueError(f"X_BE: expected poses of shape (N, 4, 4), got {X_BE.shape}")
    return X_BE


def forward(params: OpwParameters, q: np.ndarray) -> np.ndarray:
    """Pose of the flange in the base for each joint vector (paper Sec. 3).

    Args:
        params: Robot geometry.
        q: (N, 6) joint angles as the controller counts them [rad].

    Returns:
        X_BE: (N, 4, 4) homogeneous transforms of flange E in base B [m].

    Raises:
        ValueError: If q is not (N, 6).
    """
    q = check_joints(q)
    sign = np.asarray(params.sign_corrections, dtype=float)
    theta = q * sign - np.asarray(params.offsets, dtype=float)
    t1, t2, t23 = theta[:, 0], theta[:, 1], theta[:, 1] + theta[:, 2]
    psi3 = np.arctan2(params.a2, params.c3)
    k = np.hypot(params.a2, params.c3)
    # Wrist centre in the frame turned by theta1 (paper eq. 1), then in B.
    p_1C = np.stack(
        [
            params.c2 * np.sin(t2) + k * np.sin(t23 + psi3) + params.a1,
            np.full_like(t1, params.b),
            params.c2 * np.cos(t2) + k * np.cos(t23 + psi3),
        ],
        axis=-1,
    )
    R_B1 = _rot_z(t1)
    p_BC = np.einsum("nij,nj->ni", R_B1, p_1C)
    p_BC[:, 2] += params.c1
    R_BC = R_B1 @ _rot_y(t23)
    R_CE = _rot_z(theta[:, 3]) @ _rot_y(theta[:, 4]) @ _rot_z(theta[:, 5])
    R_BE = R_BC @ R_CE
    X_BE = np.zeros((q.shape[0], 4, 4))
    X_BE[:, :3, :3] = R_BE
    X_BE[:, :3, 3] = p_BC + params.c4 * R_BE[:, :, 2]
    X_BE[:, 3, 3] = 1.0
    return X_BE


def _arm_solutions(params: OpwParameters, p_BC: np.ndarray) -> tuple[np.ndarray, ...]:
    """Joints 1-3 for the four arm branches (paper Sec. 4.1).

    Args:
        params: Robot geometry.
        p_BC: (N, 3) wrist centre in B [m].

    Returns:
        theta1, theta2, theta3: each (N, 4) in the paper's convention [rad], branch
        order (front, elbow i), (front, elbow ii), (back, elbow i), (back, elbow ii);
        NaN where the wrist centre is out of reach for that branch.
    """
    a1, a2, b, c1, c2, c3 = params.a1, params.a2, params.b, params.c1, params.c2, params.c3
    cx, cy, cz = p_BC.T
    with np.errstate(invalid="ignore", divide="ignore"):
        nx1 = np.sqrt(cx**2 + cy**2 - b**2) - a1
        phi = np.arctan2(cy, cx)
        tilt = np.arctan2(b, nx1 + a1)
        t1_front, t1_back = phi - tilt, phi + tilt - np.pi
        dz = cz - c1
        s1_sq = nx1**2 + dz**2
        s2_sq = (nx1 + 2.0 * a1) ** 2 + dz**2
        kappa_sq = a2**2 + c3**2
        g1 = acos_clipped((s1_sq + c2**2 - kappa_sq) / (2.0 * np.sqrt(s1_sq) * c2))
        g2 = acos_clipped((s2_sq + c2**2 - kappa_sq) / (2.0 * np.sqrt(s2_sq) * c2))
        lean1 = np.arctan2(nx1, dz)
        lean2 = np.arctan2(nx1 + 2.0 * a1, dz)
        two_c2_kappa = 2.0 * c2 * np.sqrt(kappa_sq)
        e1 = acos_clipped((s1_sq - c2**2 - kappa_sq) / two_c2_kappa)
        e2 = acos_clipped((s2_sq - c2**2 - kappa_sq) / two_c2_kappa)
    psi3 = np.arctan2(a2, c3)
    theta1 = np.stack([t1_front, t1_front, t1_back, t1_back], axis=-1)
    theta2 = np.stack([lean1 - g1, lean1 + g1, -g2 - lean2, g2 - lean2], axis=-1)
    theta3 = np.stack([e1 - psi3, -e1 - psi3, e2 - psi3, -e2 - psi3], axis=-1)
    return theta1, theta2, theta3


def inverse(params: OpwParameters, X_BE: np.ndarray) -> np.ndarray:
    """All eight joint solutions for each flange pose (paper Sec. 4).

    Solutions 0-3 are the arm branches of :func:`_arm_solutions` with
    theta5 >= 0, solutions 4-7 the same arm branches with the wrist flipped
    (theta4 + pi, -theta5, theta6 - pi), the order of opw_kinematics. At the wrist
    singularity (theta5 = 0 or pi) joint 4 is set to zero.

    Args:
        params: Robot geometry.
        X_BE: (N, 4, 4) flange E in base B [m].

    Returns:
        q: (N, 8, 6) joint angles as the controller counts them, wrapped to
        [-pi, pi) [rad]; a row is all NaN where that solution does not exist. Joint
        limits are not applied, and for joints whose range exceeds one turn the
        caller picks the 2*pi-equivalent it wants.

    Raises:
        ValueError: If X_BE is not (N, 4, 4).
    """
    return _solutions(params, X_BE, slice(0, 4), (False, True))


def inverse_branch(params: OpwParameters, X_BE: np.ndarray, branch: int) -> np.ndarray:
    """Solution ``branch`` (0-7) of :func:`inverse` alone, (N, 6) [rad]: the same
    numbers as ``inverse(params, X_BE)[:, branch]`` for an eighth of the wrist work
    (a joint path evaluates its chosen branch at every output sample)."""
    if not 0 <= branch < 8:
        raise ValueError(f"branch: expected 0..7, got {branch}")
    arm = branch % 4
    return _solutions(params, X_BE, slice(arm, arm + 1), (branch >= 4,))[:, 0]


def _solutions(params: OpwParameters, X_BE: np.ndarray, arms: slice, flips: tuple) -> np.ndarray:
    """(N, len(flips) · A, 6) the solutions of the arm branches ``arms`` (A of them),
    first unflipped then flipped as ``flips`` says (module doc of :func:`inverse`)."""
    X_BE = check_poses(X_BE)
    R_BE = X_BE[:, :3, :3]
    p_BC = X_BE[:, :3, 3] - params.c4 * R_BE[:, :, 2]
    theta1, theta2, theta3 = (t[:, arms] for t in _arm_solutions(params, p_BC))
    # Wrist: R_CE = R_BC^T R_BE = Rz(theta4) Ry(theta5) Rz(theta6) (paper eq. 11-13).
    R_BC = _rot_z_rot_y(theta1, theta2 + theta3)
    R_CE = np.swapaxes(R_BC, -1, -2) @ R_BE[:, None]
    sin5 = np.hypot(R_CE[..., 0, 2], R_CE[..., 1, 2])
    theta5 = np.arctan2(sin5, R_CE[..., 2, 2])
    singular = sin5 < WRIST_SINGULAR_SIN
    theta4 = np.where(singular, 0.0, np.arctan2(R_CE[..., 1, 2], R_CE[..., 0, 2]))
    # At theta5 = 0, R_CE = Rz(theta6); at theta5 = pi, R_CE = Ry(pi) Rz(theta6).
    cos6_singular = np.where(R_CE[..., 2, 2] > 0.0, R_CE[..., 0, 0], R_CE[..., 1, 1])
    theta6 = np.where(
        singular,
        np.arctan2(R_CE[..., 1, 0], cos6_singular),
        np.arctan2(R_CE[..., 2, 1], -R_CE[..., 2, 0]),
    )
    count = theta1.shape[1]
    theta = np.empty((X_BE.shape[0], count * len(flips), 6))
    for k, flip in enumerate(flips):
        rows = slice(k * count, (k + 1) * count)
        theta[:, rows, 0] = theta1
        theta[:, rows, 1] = theta2
        theta[:, rows, 2] = theta3
        theta[:, rows, 3] = theta4 + np.pi if flip else theta4
        theta[:, rows, 4] = -theta5 if flip else theta5
        theta[:, rows, 5] = theta6 - np.pi if flip else theta6
    sign = np.asarray(params.sign_corrections, dtype=float)
    q = wrap_to_pi((theta + np.asarray(params.offsets, dtype=float)) * sign)
    q[np.isnan(q).any(axis=-1)] = np.nan
    return q
