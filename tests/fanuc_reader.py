"""Reads a FANUC LS program back (test helper): /MN statements and /POS positions, and
reconstructs each position's joints under FANUC's conventions (W, P, R about fixed
x, y, z; the CONFIG flags pick one of the eight OPW solutions, turn numbers fix J1, J4,
J6), independently of the writer's code."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw

_POS = re.compile(r"P\[(\d+)\]\{\s*GP1:\s*UF : (\d+), UT : (\d+),(.*?)\};", re.S)
_NUM = r"(-?\d+\.?\d*)"


def read_ls(file: Path) -> dict:
    """{'name', 'attr': {...}, 'mn': [statement, ...], 'pos': {k: dict}} of an LS file;
    asserts the section order /PROG /ATTR /MN /POS /END and the line numbering."""
    text = Path(file).read_text()
    assert text.startswith("/PROG  ") and text.rstrip().endswith("/END")
    head, rest = text.split("/MN\n", 1)
    mn_text, pos_text = rest.split("/POS\n", 1)
    lines = mn_text.splitlines()
    mn = []
    for k, line in enumerate(lines, start=1):
        match = re.match(r"\s*(\d+):(.*) ;$", line)
        assert match and int(match.group(1)) == k, line
        mn.append(match.group(2).strip())
    attr = dict(re.findall(r"^(\w+)\s*= (.*?);$", head, re.M))
    assert int(attr["LINE_COUNT"]) == len(mn)
    positions = {}
    for index, uf, ut, body in _POS.findall(pos_text):
        entry = {"uf": int(uf), "ut": int(ut)}
        config = re.search(r"CONFIG : '([NF]) ([UD]) ([TB]), (-?\d+), (-?\d+), (-?\d+)'", body)
        if config:
            entry["config"] = config.groups()[:3]
            entry["turns"] = tuple(int(t) for t in config.groups()[3:])
            values = {k: float(v) for k, v in re.findall(rf"([XYZWPR]) = {_NUM}", body)}
            entry["xyzwpr"] = [values[k] for k in "XYZWPR"]
        else:
            entry["joints"] = [float(v) for v in re.findall(rf"J\d= {_NUM} deg", body)]
        positions[int(index)] = entry
    return {"name": head.split()[1], "attr": attr, "mn": mn, "pos": positions}


def pose(xyzwpr) -> np.ndarray:
    """4x4 [m] from X, Y, Z [mm] and W, P, R [deg] (R = Rz(R) Ry(P) Rx(W))."""
    x, y, z, w, p, r = xyzwpr
    X = RigidTransform(RollPitchYaw(np.radians([w, p, r])), np.array([x, y, z]) * 1e-3)
    return X.GetAsMatrix4()


def joints_from_config(robot, X_BE: np.ndarray, config, turns) -> np.ndarray:
    """(6,) URDF joints [rad]: the IK solution whose FANUC flags equal ``config``,
    with J1, J4, J6 (FANUC axes) moved into the turn each number names."""
    p = robot.params
    solutions = robot.inverse(X_BE[None])[0]
    matches = []
    for q in solutions[np.isfinite(solutions).all(axis=1)]:
        axes = np.degrees(robot.controller_joints(q[None])[0])
        theta = q * np.asarray(p.sign_corrections) - np.asarray(p.offsets)
        psi3, k = np.arctan2(p.a2, p.c3), np.hypot(p.a2, p.c3)
        front = p.c2 * np.sin(theta[1]) + k * np.sin(theta[1] + theta[2] + psi3) + p.a1 >= 0
        up = np.sin(theta[2] + psi3) >= 0
        flags = ("F" if axes[4] > 0 else "N", "U" if up else "D", "T" if front else "B")
        if flags == tuple(config):
            for j, turn in zip((0, 3, 5), turns, strict=True):
                axes[j] += 360.0 * (turn - np.ceil((axes[j] - 180.0) / 360.0))
            matches.append(robot.urdf_joints(np.radians(axes)[None])[0])
    assert len(matches) == 1, f"{len(matches)} solutions match {config}"
    return matches[0]
