"""FANUC frames: the programs select the controller's user frame and tool frame by
number, and one separate program holds the cell's nominal values of the two.

- ``UFRAME_NUM = tool.controller_frame``: the user frame is the fixed tool T (its pose
  in FANUC's world, which sits on axis 1 at the height of axis 2: the URDF base_link
  raised by c1, see ``export.fanuc.fanuc``).
- ``UTOOL_NUM = part.controller_frame``: the tool frame is the part P in the faceplate
  (URDF tool0 = E).
- Positions: the part frame P in the user frame T (X_TP); the controller puts the
  faceplate at X_WE = UFRAME · X_TP · UTOOL⁻¹, so a calibration of either frame on
  the controller moves the whole program with it.

``<NAME>_FRAMES.ls`` writes the nominal values once (run it, or teach the frames
instead): each frame's value is a /POS entry copied into the scratch position register
``FRAMES_PR`` and from there into the frame (FANUC TP: ``PR[i]=P[j]``,
``UFRAME[i]=PR[j]``, ``UTOOL[i]=PR[j]``).
"""

from __future__ import annotations

import numpy as np

from offline_prog.export.fanuc.fanuc import cartesian_pos, ls_text, remarks
from offline_prog.export.frames import ControllerFrames

FRAMES_PR = 100  # the position register the frames program uses as scratch
FRAMES_SUFFIX = "_FRAMES"  # <NAME>_FRAMES.ls


def X_WB(robot) -> np.ndarray:
    """(4, 4) the URDF base_link B in FANUC's world W: (0, 0, -c1) [m]."""
    X = np.eye(4)
    X[2, 3] = -robot.params.c1
    return X


def frames_program(
    name: str, head: list[str], *, X_WT: np.ndarray, X_EP: np.ndarray, numbers: ControllerFrames
) -> str:
    """The LS text of ``name`` (``<NAME>_FRAMES``): UFRAME[tool] = X_WT (the fixed
    tool in FANUC's world), UTOOL[part] = X_EP (the part in the faceplate), both (4, 4)
    [m], through PR[FRAMES_PR]; ``head``: the header lines (as remarks)."""
    uf, ut = numbers.tool, numbers.part
    statements = [
        *remarks(head),
        "  ! NOMINAL FRAMES of the cell",
        "  ! run once, or teach instead",
        f"  PR[{FRAMES_PR}]=P[1]",
        f"  UFRAME[{uf}]=PR[{FRAMES_PR}]",
        f"  PR[{FRAMES_PR}]=P[2]",
        f"  UTOOL[{ut}]=PR[{FRAMES_PR}]",
    ]
    positions = [
        cartesian_pos(1, X_WT, "N U T, 0, 0, 0", uf=0, ut=ut),
        cartesian_pos(2, X_EP, "N U T, 0, 0, 0", uf=0, ut=ut),
    ]
    return ls_text(name, statements, positions, "nominal frames")


def frame_conventions(robot, numbers: ControllerFrames, *, frames_program_name: str) -> list[str]:
    """Header lines: the program's form, frames, configuration and axis conventions."""
    uf, ut = numbers.tool, numbers.part
    return [
        "FLANGE-STYLE PROGRAM, DENSE POINT LIST: not FANUC Remote TCP (no FANUC document",
        "cited for it).",
        numbers.note(f"UFRAME[{uf}]", f"UTOOL[{ut}]"),
        f"UFRAME[{uf}] = the fixed tool T in FANUC world, UTOOL[{ut}] = the part P in the "
        "faceplate (URDF tool0), as set on the controller; their nominal values: "
        f"{frames_program_name} (run once, or teach the frames); FANUC world = URDF "
        f"base_link raised by {robot.params.c1 * 1e3:.3f} mm.",
        f"Positions: P in UFRAME[{uf}] (X,Y,Z mm, W,P,R deg about fixed x, y, z).",
        "CONFIG: N/F = J5 <= 0 / > 0, U/D elbow, T/B wrist centre front/back of J1;",
        "turns of J1, J4, J6. Joint positions: FANUC axes, J3 from the horizontal",
        f"(J3 = q3 {'+' if robot.j23_factor > 0 else '-'} q2 of the URDF, "
        "ROS-I fanuc_driver J23_factor)."
        if robot.j23_coupled
        else "(J1..J6 = the URDF joints).",
    ]
