"""KUKA conventions: A, B, C angles, Status and Turn, and the flange frame.

Used by the KRL writer (``export.kuka.krl``); sources in each function's docstring.
"""

from __future__ import annotations

import numpy as np

from offline_prog.robot.kinematics_opw import OpwParameters

# URDF tool0 E in KUKA's $FLANGE K: the same frame (kuka_experimental marks tool0 as
# "the $FLANGE coordinate system in KUKA KRC controllers").
X_KE = np.eye(4)
VEL_CP_STEP_M_S = 1e-4  # $VEL.CP is floored to 0.1 mm/s: never above the plan
VEL_CP_MIN_M_S = 1e-3
# $VEL.CP is in m/s; KSS accepts at most 3 m/s ($VEL_MA.CP, KSS 8 system variables).
VEL_CP_MAX_M_S = 3.0


def vel_cp(speed_m_s: float) -> float:
    """``$VEL.CP`` [m/s] for a planned speed: floored to 0.1 mm/s, at least 1 mm/s.

    Raises:
        ValueError: the speed is not finite or above VEL_CP_MAX_M_S (a unit slip: mm/s).
    """
    if not 0.0 <= speed_m_s <= VEL_CP_MAX_M_S:
        raise ValueError(
            f"krl: speed {speed_m_s:g} m/s is beyond $VEL.CP's {VEL_CP_MAX_M_S:g} m/s "
            "(speeds are m/s, not mm/s)"
        )
    return max(np.floor(speed_m_s / VEL_CP_STEP_M_S + 1e-6) * VEL_CP_STEP_M_S, VEL_CP_MIN_M_S)


def kuka_abc_deg(R: np.ndarray) -> np.ndarray:
    """(N, 3) KUKA A, B, C [deg] of (N, 3, 3) rotations: R = Rz(A)·Ry(B)·Rx(C), B in
    [-90, 90]; at B = ±90° (gimbal lock) C = 0."""
    cos_b = np.hypot(R[:, 0, 0], R[:, 1, 0])
    lock = cos_b < 1e-9
    a = np.where(lock, np.arctan2(-R[:, 0, 1], R[:, 1, 1]), np.arctan2(R[:, 1, 0], R[:, 0, 0]))
    c = np.where(lock, 0.0, np.arctan2(R[:, 2, 1], R[:, 2, 2]))
    return np.rad2deg(np.stack([a, np.arctan2(-R[:, 2, 0], cos_b), c], axis=1))


def status_turn(params: OpwParameters, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """KUKA Status and Turn (N,) of joint vectors q (N, 6) [rad].

    Status bit 0: the wrist centre lies behind the A1 axis (x < 0 in the frame turned with
    A1: overhead area). Bit 1: A3 on the elbow-up side of the stretched arm, i.e. the
    wrist centre above the A2-A3 line (A3 >= -atan2(a2, c3) = -2.99° on the KR 16-2).
    Bit 2: A5 < 0. Turn bit i: A(i+1) < 0. Computed with the OPW paper angles theta.
    Sources: KSS manuals as quoted on robot-forum.com (bit 0); KRL data written by KSS
    pairs S 2 with A3 > 0, A5 >= 0 and S 6 with A5 < 0 (bits 1, 2); Beckhoff/ISG's KUKA-style
    Status & Turn (bit 1: wrist in front of the A2-A3 line; Turn).
    """
    theta = q * np.asarray(params.sign_corrections) - np.asarray(params.offsets)
    psi3, k = np.arctan2(params.a2, params.c3), np.hypot(params.a2, params.c3)
    x_wrist = (
        params.c2 * np.sin(theta[:, 1]) + k * np.sin(theta[:, 1] + theta[:, 2] + psi3) + params.a1
    )
    status = (x_wrist < 0) + 2 * (theta[:, 2] + psi3 >= 0) + 4 * (q[:, 4] < 0)
    return status.astype(int), ((q < 0) * (1 << np.arange(6))).sum(axis=1)


def krl_num(value: float, digits: int) -> str:
    """A KRL number with ``digits`` decimals, never "-0.0..."."""
    text = f"{value:.{digits}f}"
    return text[1:] if float(text) == 0.0 and text.startswith("-") else text


def krl_frame(X: np.ndarray) -> str:
    """``X .., Y .., Z .., A .., B .., C ..`` of a pose (4, 4) [m] in mm and degrees."""
    values = [krl_num(v, 4) for v in X[:3, 3] * 1e3] + [
        krl_num(v, 5) for v in kuka_abc_deg(X[None, :3, :3])[0]
    ]
    return ",".join(f"{key} {v}" for key, v in zip("XYZABC", values, strict=True))
