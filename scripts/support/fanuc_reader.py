"""Reads a FANUC LS program back (the tests' and figures scripts' reader): /MN
statements and /POS positions, the job's run replayed along the part (``walk``), and
reconstructs each position's joints under FANUC's conventions (W, P, R about fixed
x, y, z; the CONFIG flags pick one of the eight OPW solutions, turn numbers fix J1, J4,
J6), independently of the writer's code."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from program_replay import fractional_row
from pydrake.math import RigidTransform, RollPitchYaw
from scipy.spatial.transform import Rotation, Slerp

_POS = re.compile(r"P\[(\d+)\]\{\s*GP1:\s*UF : (\d+), UT : (\d+),(.*?)\};", re.S)
_NUM = r"(-?\d+\.?\d*)"
START_TOL_M = 1e-4  # the seam's start on the replayed curve (points 0.05 mm apart)


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


def run_statements(folder, name="OFFLINE_PROG"):
    """Statements in execution order: (statement, position entry or None)."""
    out = []

    def read(program):
        ls = read_ls(folder / f"{program}.ls")
        for statement in ls["mn"]:
            if statement.startswith("CALL "):
                read(statement.split()[1])
            elif m := re.match(r"([JL]) P\[(\d+)\]", statement):
                out.append((statement, ls["pos"][int(m[2])]))
            elif statement.startswith(("AO[", "DO[")):
                out.append((statement, None))

    read(name)
    return out


def nominal_frames(folder, robot, name="OFFLINE_PROG"):
    """{"UFRAME": (number, X_BT), "UTOOL": (number, X_EP)} (4, 4) [m] as ``<name>_FRAMES``
    sets them (``PR[r]=P[j]`` then ``UFRAME[i]=PR[r]``); the user frame turned from FANUC's
    world (on axis 1 at axis 2's height: base_link raised by c1) into base_link."""
    ls, held, frames = read_ls(folder / f"{name}_FRAMES.ls"), {}, {}
    for statement in ls["mn"]:
        if m := re.fullmatch(r"PR\[(\d+)\]=P\[(\d+)\]", statement):
            held[m[1]] = pose(ls["pos"][int(m[2])]["xyzwpr"])
        elif m := re.fullmatch(r"(UFRAME|UTOOL)\[(\d+)\]=PR\[(\d+)\]", statement):
            frames[m[1]] = (int(m[2]), held[m[3]])
    number, X_WT = frames["UFRAME"]
    X_BW = np.eye(4)
    X_BW[2, 3] = robot.params.c1
    frames["UFRAME"] = (number, X_BW @ X_WT)
    return frames


def tool_curve(X_a: np.ndarray, X_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The controller's L motion from pose X_a to X_b (4, 4) of P in the user frame T:
    (G,) shares λ of the TCP's (P's origin) straight chord and (G, 3) the tool's point
    (T's origin) on the part there, the orientation slerped, 0.05 mm apart or closer."""
    length = np.linalg.norm(X_b[:3, 3] - X_a[:3, 3])
    turn = np.linalg.norm(Rotation.from_matrix(X_a[:3, :3].T @ X_b[:3, :3]).as_rotvec())
    lam = np.linspace(0.0, 1.0, max(2, int(max(length, turn) / 5e-5) + 2))
    R = Slerp([0, 1], Rotation.from_matrix([X_a[:3, :3], X_b[:3, :3]]))(lam).as_matrix()
    p = X_a[:3, 3] + lam[:, None] * (X_b[:3, 3] - X_a[:3, 3])
    return lam, np.einsum("gji,gj->gi", R, -p)


def walk(data, folder, robot):
    """Replays the program: per seam (in run order), the DB switches as (output, state,
    position [m]) and the L motions as (start, end [m], AO value), positions along the
    tool's path on the part from the seam's start, from the program's own poses in the
    frames the frames program sets. The controller moves P's origin (the TCP UTOOL
    names) on a straight line with the orientation slerped, and sets a DB output when
    that TCP comes within the DB distance of the motion's end: the switch lands where
    the tool's point on the part is then."""
    frames = nominal_frames(folder, robot)
    (uf, X_BT), (ut, X_EP) = frames["UFRAME"], frames["UTOOL"]
    X_PE, X_TB = np.linalg.inv(X_EP), np.linalg.inv(X_BT)
    here, cumulative, ao, seams = None, 0.0, None, []
    # The seams' planned starts (σ = 0: a flying seam's samples begin on its lead-in).
    starts = [data.job.X_PT[g.start, :3, 3] for g in data.segments if g.kind == "process"]
    for statement, entry in run_statements(folder):
        if entry is None:
            assert statement.startswith("AO["), statement  # no plain DO statements
            ao = float(statement.split("=")[1])
            continue
        if statement.startswith("J "):
            q = robot.urdf_joints(np.radians(entry["joints"])[None])[0]
            X_BE = robot.forward(q[None])[0]
        else:
            assert (entry["uf"], entry["ut"]) == (uf, ut)
            X_BE = X_BT @ pose(entry["xyzwpr"]) @ X_PE
            q = joints_from_config(robot, X_BE, entry["config"], entry["turns"])
            np.testing.assert_allclose(robot.forward(q[None])[0], X_BE, atol=1e-9)
        X_TP = X_TB @ X_BE @ X_EP
        if statement.startswith("J "):
            if seams and "open" in seams[-1]:
                del seams[-1]["open"]
            cumulative = 0.0
        else:
            if not seams or "open" not in seams[-1]:
                seams.append({"open": True, "db": [], "moves": []})
            lam, curve = tool_curve(here, X_TP)
            along = np.concatenate(
                [[0.0], np.cumsum(np.linalg.norm(np.diff(curve, axis=0), axis=1))]
            )
            seams[-1]["moves"].append((cumulative, cumulative + along[-1], ao))
            assert len(re.findall(r"\bDB\b", statement)) <= 1, statement
            if m := re.search(r"DB ([\d.]+)mm,DO\[(\d+)\]=(ON|OFF)", statement):
                chord = np.linalg.norm(X_TP[:3, 3] - here[:3, 3])
                at = 1.0 - min(float(m[1]) * 1e-3 / chord, 1.0) if chord > 0 else 1.0
                seams[-1]["db"].append(
                    (int(m[2]), m[3] == "ON", cumulative + np.interp(at, lam, along))
                )
            start = starts[len(seams) - 1]
            gap = np.linalg.norm(curve - start, axis=1)
            if "zero" not in seams[-1] and gap.min() < START_TOL_M:  # the curve's spacing
                i = int(np.argmin(gap))
                seams[-1]["zero"] = cumulative + np.interp(
                    fractional_row(curve, start, i), np.arange(len(along)), along
                )
            cumulative += along[-1]
        here = X_TP
    for seam in seams:
        zero = seam.pop("zero")
        seam["db"] = [(n, s, p - zero) for n, s, p in seam["db"]]
        seam["moves"] = [(a - zero, b - zero, v) for a, b, v in seam["moves"]]
        seam.pop("open", None)
    return seams
