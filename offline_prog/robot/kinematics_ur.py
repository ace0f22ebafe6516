"""Analytic kinematics of Universal Robots arms (UR3/5/10/16, e-Series included).

Closed-form solution of

    K. P. Hawkins, "Analytic Inverse Kinematics for the Universal Robots UR-5/UR-10
    Arms", Georgia Institute of Technology, 2013 (also ros-industrial ur_kinematics),

on UR's published Denavit-Hartenberg parameters, vectorized over samples.

Frames: B is the ROS-Industrial ``base_link`` (REP-103: x forward, z up). UR's
controller "Base" frame, which is the DH frame 0 (here called U), is B turned by pi
about z (Universal_Robots_ROS2_Description puts the same rotation between
``base_link`` and ``base_link_inertia``): ``X_BU = Rz(pi)``. E is the flange
``tool0`` = DH frame 6 (z out of the flange).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from offline_prog.robot.kinematics_opw import acos_clipped, check_joints, check_poses, wrap_to_pi

# |sin(theta5)| below this counts as the wrist singularity (axes 2, 3, 4, 6 parallel):
# joint 6 is set to zero and joints 2-4 take the whole rotation.
WRIST_SINGULAR_SIN = 1e-12
# DH twist angles alpha_i of every UR arm [rad].
_ALPHA = (np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0)
# X_BU: DH base U in ROS base_link B.
_X_BU = np.diag([-1.0, -1.0, 1.0, 1.0])


@dataclass(frozen=True)
class UrParameters:
    """UR Denavit-Hartenberg lengths (UR's "DH parameters" support article) [m].

    Attributes:
        d1: Shoulder height (DH d1).
        a2: Upper-arm length (DH a2, negative on UR arms).
        a3: Forearm length (DH a3, negative on UR arms).
        d4: Wrist-1 offset along the shoulder axis (DH d4).
        d5: Wrist-2 offset (DH d5).
        d6: Wrist-3 to flange (DH d6).
    """

    d1: float
    a2: float
    a3: float
    d4: float
    d5: float
    d6: float

    @property
    def d(self) -> tuple[float, ...]:
        """DH offsets d1..d6 [m]."""
        return (self.d1, 0.0, 0.0, self.d4, self.d5, self.d6)

    @property
    def a(self) -> tuple[float, ...]:
        """DH lengths a1..a6 [m]."""
        return (0.0, self.a2, self.a3, 0.0, 0.0, 0.0)


def _dh(theta: np.ndarray, d: float, a: float, alpha: float) -> np.ndarray:
    """DH link transforms Rz(theta) Tz(d) Tx(a) Rx(alpha): theta (...,) -> (..., 4, 4)."""
    c, s = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    z, o = np.zeros_like(theta), np.ones_like(theta)
    rows = [c, -s * ca, s * sa, a * c, s, c * ca, -c * sa, a * s, z, z + sa, z + ca, z + d]
    return np.stack(rows + [z, z, z, o], axis=-1).reshape(theta.shape + (4, 4))


def _dh_inv(theta: np.ndarray, d: float, a: float, alpha: float) -> np.ndarray:
    """Inverse of :func:`_dh` (rigid-transform inverse): theta (...,) -> (..., 4, 4)."""
    X = _dh(theta, d, a, alpha)
    X_inv = np.zeros_like(X)
    R_T = np.swapaxes(X[..., :3, :3], -1, -2)
    X_inv[..., :3, :3] = R_T
    X_inv[..., :3, 3] = -np.einsum("...ij,...j->...i", R_T, X[..., :3, 3])
    X_inv[..., 3, 3] = 1.0
    return X_inv


def forward(params: UrParameters, q: np.ndarray) -> np.ndarray:
    """Pose of the flange in ``base_link`` for each joint vector.

    Args:
        params: UR DH lengths.
        q: (N, 6) joint angles as the UR controller counts them [rad].

    Returns:
        X_BE: (N, 4, 4) flange E (``tool0``) in base B (``base_link``) [m].

    Raises:
        ValueError: If q is not (N, 6).
    """
    q = check_joints(q)
    X_UE = np.broadcast_to(np.eye(4), (q.shape[0], 4, 4))
    for i in range(6):  # six joints, not samples: every product is over all N rows
        X_UE = X_UE @ _dh(q[:, i], params.d[i], params.a[i], _ALPHA[i])
    return _X_BU @ X_UE


def _theta6_singular(
    params: UrParameters, R_UE: np.ndarray, p_U5: np.ndarray, theta1: np.ndarray
) -> np.ndarray:
    """Joint 6 at the wrist singularity (theta5 = 0), where it is free.

    Joints 2, 3, 4 and 6 are then parallel and theta6 only decides where, on a
    circle of radius d5 about the wrist-2 origin, the wrist-1 origin lies. Hawkins
    takes theta6 = 0, which can leave wrist 1 out of the arm's reach; this picks the
    point towards the shoulder axis (or away from it when that is too close), so
    the planar arm problem keeps its solution. Uses z4 = -sin(theta6) x6 -
    cos(theta6) y6 and p4 = p5 - d5 z4 (DH).

    Args:
        params: UR DH lengths.
        R_UE: (N, 3, 3) flange orientation in the DH base U.
        p_U5: (N, 3) wrist-2 origin in U [m].
        theta1: (N, 2) both shoulder solutions [rad].

    Returns:
        theta6: (N, 2, 1) [rad], broadcastable over the two theta5 signs.
    """
    z1 = np.stack([np.sin(theta1), -np.cos(theta1), np.zeros_like(theta1)], axis=-1)
    v = (p_U5 - np.array([0.0, 0.0, params.d1]))[:, None]  # from the shoulder, (N, 1, 3)
    v = v - np.sum(v * z1, axis=-1, keepdims=True) * z1  # in the arm plane, (N, 2, 3)
    distance = np.linalg.norm(v, axis=-1, keepdims=True)
    w = v / distance  # z4 pointing away from the shoulder: wrist 1 nearer to it
    too_close = distance - params.d5 < abs(abs(params.a2) - abs(params.a3))
    w = np.where(too_close, -w, w)
    w_x = np.einsum("nk,nsk->ns", R_UE[:, :, 0], w)
    w_y = np.einsum("nk,nsk->ns", R_UE[:, :, 1], w)
    return np.arctan2(-w_x, -w_y)[..., None]


def inverse(params: UrParameters, X_BE: np.ndarray) -> np.ndarray:
    """All eight joint solutions for each flange pose (Hawkins 2013, Sec. 2).

    Solution index ``4 * i1 + 2 * i5 + i3``: i1 picks the shoulder (theta1 with
    +acos or -acos), i5 the wrist (theta5 >= 0 or <= 0), i3 the elbow (theta3 >= 0
    or <= 0).

    Args:
        params: UR DH lengths.
        X_BE: (N, 4, 4) flange E (``tool0``) in base B (``base_link``) [m].

    Returns:
        q: (N, 8, 6) joint angles wrapped to [-pi, pi) [rad]; a row is all NaN where
        that solution does not exist. Joint limits are not applied; UR joints turn
        +-2*pi, so q and q -+ 2*pi are both reachable.

    Raises:
        ValueError: If X_BE is not (N, 4, 4).
    """
    X_BE = check_poses(X_BE)
    d1, a2, a3, d4, d5, d6 = (params.d1, params.a2, params.a3, params.d4, params.d5, params.d6)
    X_UE = _X_BU.T @ X_BE
    R, p = X_UE[:, :3, :3], X_UE[:, :3, 3]
    n = X_BE.shape[0]
    with np.errstate(invalid="ignore", divide="ignore"):
        # theta1 (N, 2): the wrist-2 origin lies d4 off the plane of joints 2-4.
        p_5 = p - d6 * R[:, :, 2]
        psi = acos_clipped(d4 / np.hypot(p_5[:, 0], p_5[:, 1]))
        t1 = np.arctan2(p_5[:, 1], p_5[:, 0])[:, None] + np.stack([psi, -psi], -1) + np.pi / 2
        s1, c1 = np.sin(t1), np.cos(t1)
        # theta5, theta6 (N, 2, 2) from z1 = (s1, -c1, 0) seen from the flange:
        # R^T z1 = (s5 c6, -s5 s6, c5). Hawkins takes c5 = (p . z1 - d4) / d6, which
        # is the same number once theta1 holds, but its arccos loses half the digits
        # near theta5 = 0; the atan2 form keeps them.
        v_x = (R[:, None, 0, 0] * s1 - R[:, None, 1, 0] * c1)[..., None]
        v_y = (R[:, None, 0, 1] * s1 - R[:, None, 1, 1] * c1)[..., None]
        v_z = (R[:, None, 0, 2] * s1 - R[:, None, 1, 2] * c1)[..., None]
        t5_abs = np.arctan2(np.hypot(v_x, v_y), v_z)
        t5 = np.concatenate([t5_abs, -t5_abs], axis=-1)
        s5 = np.sin(t5)
        sign5 = np.where(s5 >= 0.0, 1.0, -1.0)
        t6_regular = np.arctan2(-v_y * sign5, v_x * sign5)
        t6 = np.where(
            np.abs(s5) < WRIST_SINGULAR_SIN, _theta6_singular(params, R, p_5, t1), t6_regular
        )
        # Planar 3R problem for joints 2-4 in frame 1: X_14 = A1^-1 X_UE A6^-1 A5^-1.
        X_14 = (
            _dh_inv(t1, d1, 0.0, _ALPHA[0])[:, :, None]
            @ X_UE[:, None, None]
            @ _dh_inv(t6, d6, 0.0, _ALPHA[5])
            @ _dh_inv(t5, d5, 0.0, _ALPHA[4])
        )
        x, y = X_14[..., 0, 3], X_14[..., 1, 3]
        t3_abs = acos_clipped((x**2 + y**2 - a2**2 - a3**2) / (2.0 * a2 * a3))
        t3 = np.stack([t3_abs, -t3_abs], axis=-1)
        t2 = np.arctan2(y, x)[..., None] - np.arctan2(a3 * np.sin(t3), a2 + a3 * np.cos(t3))
        t234 = np.arctan2(X_14[..., 1, 0], X_14[..., 0, 0])[..., None]
        t4 = t234 - t2 - t3
    shape = (n, 2, 2, 2)
    q = np.stack(
        [
            np.broadcast_to(t1[:, :, None, None], shape),
            t2,
            t3,
            t4,
            np.broadcast_to(t5[..., None], shape),
            np.broadcast_to(t6[..., None], shape),
        ],
        axis=-1,
    ).reshape(n, 8, 6)
    q = wrap_to_pi(q)
    q[np.isnan(q).any(axis=-1)] = np.nan
    return q
