"""The comment header of a KRL program: units, frames, conventions, sanitized lines."""

from __future__ import annotations

import textwrap

import numpy as np

from offline_prog.export.text import krl_comment


def krl_conventions(style: str, convention: str, n: int, chord_tol_m, angle_tol_rad) -> list[str]:
    """Header lines stating units, frames and conventions (the caller appends the
    achieved deviation to the second last)."""
    if style == "flange":
        points = "Style flange: $IPO_MODE=#BASE, $BASE=$NULLFRAME ($ROBROOT), $TOOL = part P in "
        points += "$FLANGE; points: pose of P in $ROBROOT."
    else:
        points = "Style external_tcp: $IPO_MODE=#TCP, $BASE = fixed tool T in $ROBROOT, $TOOL = "
        points += "part P in $FLANGE; points: " + (
            "pose of P in T (X_TP), flange = $BASE:POS:inv($TOOL)."
            if convention == "X_TP"
            else "pose of T in P (X_PF), flange = $BASE:inv(POS):inv($TOOL)."
        )
    return [
        "KRL for KSS 8. X, Y, Z in mm; A, B, C in deg, R = Rz(A)*Ry(B)*Rx(C) (Z-Y'-X''); "
        "$VEL.CP in m/s; $APO.CDIS in mm.",
        "E6AXIS A1..A6 = URDF joints 1..6 in deg (KUKA signs and zeros). $WORLD = $ROBROOT = "
        "URDF base_link (check on the controller). $FLANGE = URDF tool0 (z out of the flange).",
        points,
        "Status: bit0 wrist centre behind A1 (overhead), bit1 wrist centre above the A2-A3 line "
        "(elbow up), bit2 A5 < 0. Turn: bit i set when A(i+1) < 0.",
        f"{n} process points: chord <= {chord_tol_m * 1e3:g} mm, orientation <= "
        f"{np.rad2deg(angle_tol_rad):g} deg"
        + (
            " both if the controller moves the tool in straight lines across the part and if "
            "it interpolates the written poses"
            if style == "external_tcp"
            else " for the tool's curve on the part while the part frame moves linearly"
        ),
        "$LOAD: see Payload above. Not set here: process I/O. Approach and retract moves are "
        "not collision-checked.",
    ]


def krl_comments(lines: list[str]) -> list[str]:
    """KRL comment lines: each text line sanitized (export.text), wrapped at 100."""
    safe = [krl_comment(line) for line in lines]
    return ["; " + part for line in safe for part in textwrap.wrap(line, 100) or [""]]
