"""Bounds a robot description's numbers must meet before they become a robot folder.

A URDF gives angles in radians and lengths in metres; a description written in
degrees or millimetres parses as well and gives a robot that plans, wrongly: joint
ranges of ±9740°, speeds of 1e9 rad/s, a 525 m arm. Each bound below is far outside
every industrial six-axis arm and far inside the unit mistake it catches; a value
beyond it is one line naming the joint and the likely unit. Names that reach CSV
headers and controller programs follow :mod:`offline_prog.config.names`.
"""

from __future__ import annotations

import numpy as np

from offline_prog.config.names import MAX_ROBOT_NAME_CHARS, name_problem
from offline_prog.errors import InputError
from offline_prog.robot_import.chain import Chain

# Largest |position limit| of a revolute joint [deg]: three turns (wrist axes of arms
# reach ±720°; a limit written in degrees, e.g. 170, reads as 9740°).
MAX_POSITION_DEG = 1080.0
# Largest joint speed [deg/s]: ten turns a second (the fastest arm axes turn ~2000°/s).
MAX_SPEED_DEG_S = 3600.0
# Longest chain [m], the joint origins' lengths summed at q = 0 (the largest arms
# reach under 5 m; a description in millimetres is a thousand times longer).
MAX_CHAIN_LENGTH_M = 20.0


def check_plausible(chain: Chain) -> None:
    """Joint names, limits, speeds and the chain's length within the bounds above.

    Raises:
        InputError: the first value beyond a bound (file, joint key, the likely unit).
    """
    file = chain.file
    for joint in chain.revolute:
        problem = name_problem(joint.name, max_chars=MAX_ROBOT_NAME_CHARS)
        if problem:
            csv = "it heads a column of joint_trajectory.csv"
            raise InputError(file, f"joint {joint.name!r}", f"{problem}: {csv}")
        widest = max(abs(joint.lower), abs(joint.upper))
        if np.degrees(widest) > MAX_POSITION_DEG:
            raise InputError(
                file,
                f"joint {joint.name} limit",
                f"±{np.degrees(widest):.0f}° is more than {MAX_POSITION_DEG:g}°: URDF limits "
                f"are radians (these look like degrees: {widest:g} rad)",
            )
        if joint.velocity is not None and np.degrees(joint.velocity) > MAX_SPEED_DEG_S:
            raise InputError(
                file,
                f"joint {joint.name} limit velocity",
                f"{joint.velocity:g} rad/s ({np.degrees(joint.velocity):.3g}°/s) is more than "
                f"{MAX_SPEED_DEG_S:g}°/s: URDF speeds are rad/s",
            )
    length = sum(float(np.linalg.norm(j.X_PC.translation())) for j in chain.joints)
    if length > MAX_CHAIN_LENGTH_M:
        raise InputError(
            file,
            f"chain {chain.base} -> {chain.tip}",
            f"{length:.4g} m long (joint origins summed), more than {MAX_CHAIN_LENGTH_M:g} m: "
            "URDF lengths are metres (these look like millimetres)",
        )
