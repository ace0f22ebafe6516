"""The flange Jacobian of a serial robot and exact joint-path derivatives through it.

The chain is read from the robot's URDF (joint origins and axes, base_link to tool0),
so it holds for every family (OPW, UR, Drake IK). With the joints' axes z_k and
origins p_k in the base frame B and the flange origin p_E, column k of the
geometric Jacobian J (rows [ω; v], expressed in B) is [z_k; z_k × (p_E − p_k)].

Joint-path derivatives (issue 14, the time-optimal law needs them exact): along a
path parameter σ with flange twist derivatives V′ = [ω′; v′] and V″ = [α″; a″],
    J q′ = V′,        J q″ = V″ − J′ q′,
where J′ = Σ_k ∂J/∂q_k q′_k comes from the same chain: the axis of joint k turns
with ω_k = Σ_{i<k} z_i q′_i (so z_k′ = ω_k × z_k) and its origin moves with
p_k′ = Σ_{i<k} z_i × (p_k − p_i) q′_i. No finite differences anywhere.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from functools import cache
from pathlib import Path

import numpy as np

BASE_LINK, FLANGE_LINK = "base_link", "tool0"


def _rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    """(3, 3) URDF fixed-axis roll-pitch-yaw: R = Rz(y) Ry(p) Rx(r)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


@dataclasses.dataclass(frozen=True)
class Chain:
    """The URDF's serial chain base_link → tool0.

    Attributes:
        origins: (K, 4, 4) each joint's origin in its parent link (fixed joints too).
        axes: (K, 3) each joint's axis in its own frame (zero for fixed joints).
        movable: (K,) index of the joint in q, or −1 for a fixed joint.
    """

    origins: np.ndarray
    axes: np.ndarray
    movable: np.ndarray


@cache
def urdf_chain(urdf_path: Path, joint_names: tuple[str, ...]) -> Chain:
    """Reads the chain from base_link to tool0 (cached per file).

    Raises:
        ValueError: the URDF has no such serial chain, or a moving joint is not
            among ``joint_names``.
    """
    root = ET.parse(urdf_path).getroot()
    by_child = {j.find("child").get("link"): j for j in root.iter("joint")}
    joints, link = [], FLANGE_LINK
    while link != BASE_LINK:
        if link not in by_child:
            raise ValueError(f"{urdf_path}: no joint chain from {BASE_LINK} to {FLANGE_LINK}")
        joints.append(by_child[link])
        link = joints[-1].find("parent").get("link")
    origins, axes, movable = [], [], []
    for joint in reversed(joints):
        origin = joint.find("origin")
        X = np.eye(4)
        if origin is not None:
            X[:3, :3] = _rpy_matrix(np.array(origin.get("rpy", "0 0 0").split(), float))
            X[:3, 3] = np.array(origin.get("xyz", "0 0 0").split(), float)
        origins.append(X)
        if joint.get("type") == "fixed":
            axes.append(np.zeros(3))
            movable.append(-1)
            continue
        if joint.get("type") not in ("revolute", "continuous"):
            raise ValueError(f"{urdf_path}: joint {joint.get('name')}: only revolute joints")
        axis = joint.find("axis")
        axes.append(np.array((axis.get("xyz") if axis is not None else "1 0 0").split(), float))
        if joint.get("name") not in joint_names:
            raise ValueError(f"{urdf_path}: joint {joint.get('name')} is not in joint_names")
        movable.append(joint_names.index(joint.get("name")))
    return Chain(np.array(origins), np.array(axes), np.array(movable))


def _axis_rotations(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotations by angle (N,) about a unit axis (3,) (Rodrigues)."""
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    return np.eye(3) + s * K + (1 - c) * (K @ K)


def joint_frames(chain: Chain, q: np.ndarray):
    """Axes and origins of the moving joints, and the flange pose, all in B.

    Args:
        q: (N, 6) URDF joint angles [rad].

    Returns:
        z: (N, 6, 3) joint axes; p: (N, 6, 3) joint origins [m]; X_BE: (N, 4, 4).
    """
    n = len(q)
    R, p = np.broadcast_to(np.eye(3), (n, 3, 3)), np.zeros((n, 3))
    z, o = np.zeros((n, 6, 3)), np.zeros((n, 6, 3))
    for origin, axis, k in zip(chain.origins, chain.axes, chain.movable, strict=True):
        p = p + R @ origin[:3, 3]
        R = R @ origin[:3, :3]
        if k >= 0:
            unit = axis / np.linalg.norm(axis)
            z[:, k], o[:, k] = R @ unit, p
            R = R @ _axis_rotations(unit, q[:, k])
    X_BE = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    X_BE[:, :3, :3], X_BE[:, :3, 3] = R, p
    return z, o, X_BE


def jacobian(z: np.ndarray, p: np.ndarray, p_BE: np.ndarray) -> np.ndarray:
    """(N, 6, 6) geometric Jacobian, rows [ω; v] of the flange origin in B."""
    return np.concatenate([z, np.cross(z, p_BE[:, None, :] - p)], axis=2).transpose(0, 2, 1)


def jacobian_rate_times(z, p, p_BE, dq):
    """(N, 6) J′ q′ for joint rates dq (N, 6): the velocity-product term (module doc)."""
    w = np.cumsum(z * dq[:, :, None], axis=1) - z * dq[:, :, None]  # ω_k: joints before k
    dz = np.cross(w, z)
    # p_k′ = Σ_{i<k} z_i × (p_k − p_i) q′_i = ω_k × p_k − Σ_{i<k} (z_i × p_i) q′_i
    zp = np.cross(z, p) * dq[:, :, None]
    dp = np.cross(w, p) - (np.cumsum(zp, axis=1) - zp)
    dp_E = np.cross(np.sum(z * dq[:, :, None], axis=1), p_BE) - np.sum(zp, axis=1)
    dJ_w = dz
    dJ_v = np.cross(dz, p_BE[:, None, :] - p) + np.cross(z, dp_E[:, None, :] - dp)
    return np.concatenate(
        [np.einsum("nki,nk->ni", dJ_w, dq), np.einsum("nki,nk->ni", dJ_v, dq)], axis=1
    )


def joint_path_rates(chain: Chain, q: np.ndarray, V1: np.ndarray, V2: np.ndarray):
    """Exact q′ and q″ along a path from the flange twist's σ-derivatives.

    Args:
        q: (N, 6) joint angles on the path [rad].
        V1: (N, 6) [ω′; v′] flange angular and linear rates per σ, in B [rad/m, 1].
        V2: (N, 6) [α″; a″] their σ-derivatives, in B [rad/m², 1/m].

    Returns:
        (dq, ddq): (N, 6) q′ [rad/m] and q″ [rad/m²].
    """
    z, p, X_BE = joint_frames(chain, q)
    J = jacobian(z, p, X_BE[:, :3, 3])
    try:
        J_inv = np.linalg.inv(J)
    except np.linalg.LinAlgError:  # exactly singular somewhere: least squares there
        J_inv = np.linalg.pinv(J)
    dq = np.einsum("nij,nj->ni", J_inv, V1)
    bias = jacobian_rate_times(z, p, X_BE[:, :3, 3], dq)
    return dq, np.einsum("nij,nj->ni", J_inv, V2 - bias)
