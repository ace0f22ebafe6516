"""OPW parameters (Brandstötter et al. 2014) read off a six-revolute chain's geometry.

At q = 0 every joint axis is a line in the base frame B: unit direction u_k through
point p_k (the joint origin). An ortho-parallel robot with a spherical wrist has u1 along
±z of B through its origin, u2 ∥ u3 ⟂ u1, and axes 4, 5, 6 meeting in the wrist centre
C; the flange E (URDF tool0) has z along axis 6. In the paper's zero pose the arm stands
vertical; a description's zero pose differs by the joint offsets, and its axis
directions by the sign corrections (opw_kinematics conventions:
``q = (θ + offset) · sign``). Every number below is computed from the chain, then
:func:`opw_matches` checks the derived model against the chain's own FK; a chain that
does not fit returns None (the robot then uses Drake's IK, family ``drake``).
"""

from __future__ import annotations

import numpy as np

from offline_prog.robot import kinematics_opw
from offline_prog.robot.kinematics_opw import OpwParameters
from offline_prog.robot_import.chain import Chain, chain_forward

# Geometry tolerance of the structure tests (parallel, perpendicular, intersecting) [m]
# and [rad]-like dot products; the final verdict is the FK check, at 1e-9 m.
STRUCTURE_TOL = 1e-6
QUICK_CHECK_SAMPLES = 50
QUICK_CHECK_TOL_M = 1e-9


def axes_at_zero(chain: Chain) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, p, X_BE): (6, 3) unit joint axes and (6, 3) joint origins in B at q = 0 [m],
    and the tip's pose (4, 4) in B."""
    X_B, u, p = np.eye(4), [], []
    for joint in chain.joints:
        X_B = X_B @ joint.X_PC.GetAsMatrix4()
        if joint.kind == "revolute":
            u.append(X_B[:3, :3] @ joint.axis)
            p.append(X_B[:3, 3].copy())
    return np.array(u), np.array(p), X_B


def _closest_point(points: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, float]:
    """The point nearest to the lines (points[k], directions[k]) and its largest
    distance from any of them [m]."""
    A, rhs = np.zeros((3, 3)), np.zeros(3)
    for p, d in zip(points, directions, strict=True):
        P = np.eye(3) - np.outer(d, d)
        A += P
        rhs += P @ p
    c = np.linalg.lstsq(A, rhs, rcond=None)[0]
    gaps = [
        np.linalg.norm((np.eye(3) - np.outer(d, d)) @ (c - p))
        for p, d in zip(points, directions, strict=True)
    ]
    return c, max(gaps)


def _wrap(angle: float) -> float:
    """Angle in (-π, π], with -π written as π (as the published records do)."""
    wrapped = float(np.mod(angle + np.pi, 2 * np.pi) - np.pi)
    return np.pi if abs(wrapped + np.pi) < 1e-12 else wrapped


def derive_opw(chain: Chain) -> OpwParameters | None:
    """The OPW parameter record of ``chain``, or None when it is not an OPW robot."""
    u, p, X_BE = axes_at_zero(chain)
    _, y, z = np.eye(3)
    tol = STRUCTURE_TOL
    if abs(abs(u[0] @ z) - 1) > tol or np.hypot(p[0][0], p[0][1]) > tol:
        return None  # axis 1 is not the base z axis
    if abs(abs(u[1] @ y) - 1) > tol or abs(abs(u[2] @ y) - 1) > tol:
        return None  # axes 2 and 3 are not along y at q = 0 (or not parallel)
    c, gap = _closest_point(p[3:], u[3:])
    if gap > tol:
        return None  # no spherical wrist
    signs = [int(np.sign(u[0] @ z)), int(np.sign(u[1] @ y)), int(np.sign(u[2] @ y))]
    a1, c1 = p[1][0], p[1][2]
    # Axis 3 in the xz plane: θ2 at q = 0 is the lower arm's tilt from vertical.
    d2 = np.array([p[2][0] - a1, p[2][2] - c1])
    c2 = float(np.hypot(*d2))
    t2 = float(np.arctan2(d2[0], d2[1]))
    # Forearm: z of C along axis 4, pointing from axis 3 towards the wrist centre.
    z_C = u[3] if (c - p[2]) @ u[3] >= 0 else -u[3]
    if abs(z_C @ y) > tol:
        return None
    t23 = float(np.arctan2(z_C[0], z_C[2]))
    x_C = np.array([np.cos(t23), 0.0, -np.sin(t23)])
    d = c - p[2]
    c3, a2, b = float(d @ z_C), float(d @ x_C), float(c[1])
    z_E = X_BE[:3, 2]
    c4 = float((X_BE[:3, 3] - c) @ z_E)
    if np.linalg.norm(X_BE[:3, 3] - c - c4 * z_E) > tol:
        return None  # the flange origin is not on the line through C along its z axis
    theta = [0.0, t2, t23 - t2]
    signs.append(int(np.sign(u[3] @ z_C)))
    # Wrist at q = 0: R_CE = Rz(θ4) Ry(θ5) Rz(θ6); axis 5 = Rz(θ4) y_C, axis 6 = z_E.
    R_BC = _rot_y(t23)
    u5_C, z_E_C = R_BC.T @ u[4], R_BC.T @ z_E
    s5 = 1 if u5_C[1] >= 0 else -1  # the sign that keeps θ4 nearest 0
    t4 = float(np.arctan2(-s5 * u5_C[0], s5 * u5_C[1]))
    z_E_4 = _rot_z(-t4) @ z_E_C
    t5 = float(np.arctan2(z_E_4[0], z_E_4[2]))
    R_CE = R_BC.T @ X_BE[:3, :3]
    R_6 = _rot_y(-t5) @ _rot_z(-t4) @ R_CE
    t6 = float(np.arctan2(R_6[1, 0], R_6[0, 0]))
    u6_C = R_BC.T @ u[5]
    signs += [s5, int(np.sign(u6_C @ z_E_C))]
    theta += [t4, t5, t6]
    offsets = tuple(_wrap(-t) for t in theta)
    params = OpwParameters(
        a1=_clean(a1),
        a2=_clean(a2),
        b=_clean(b),
        c1=_clean(c1),
        c2=_clean(c2),
        c3=_clean(c3),
        c4=_clean(c4),
        offsets=offsets,
        sign_corrections=tuple(signs),
    )
    return params if opw_matches(chain, params) else None


def _clean(value: float) -> float:
    """Round to 1e-12 m: the description's numbers, not their rounding noise."""
    return float(np.round(value, 12)) + 0.0


def _rot_y(t: float) -> np.ndarray:
    return kinematics_opw._rot_y(np.array(t))


def _rot_z(t: float) -> np.ndarray:
    return kinematics_opw._rot_z(np.array(t))


def opw_matches(chain: Chain, params: OpwParameters, *, samples: int = QUICK_CHECK_SAMPLES) -> bool:
    """True if the OPW model's flange poses equal the chain's within QUICK_CHECK_TOL_M
    (positions; rotations compared as ‖ΔR‖ on the same scale) on seeded samples."""
    rng = np.random.default_rng(0)
    lower = np.array([j.lower for j in chain.revolute])
    upper = np.array([j.upper for j in chain.revolute])
    q = rng.uniform(lower, upper, size=(samples, 6))
    X_opw = kinematics_opw.forward(params, q)
    for k in range(samples):
        X_chain = chain_forward(chain, q[k])[-1].GetAsMatrix4()
        if np.abs(X_chain[:3] - X_opw[k, :3]).max() > QUICK_CHECK_TOL_M:
            return False
    return True
