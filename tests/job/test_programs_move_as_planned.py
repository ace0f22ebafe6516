"""Every statement of a program that moves the robot goes to a pose the plan holds: a
row of trajectory.csv, which the whole job's collision check covered (issue 24).

On the one-seam demos (``path:`` cells, planned as one-seam jobs: KRL on the KR 16-2,
RAPID on the IRB 2400, URScript on the UR10e) and on the demo job, each program is read
back with a parser written here, and each motion statement's target is compared with
the plan's rows, in the order the controller runs them:

- KRL ``PTP`` to an ``E6AXIS`` and RAPID ``MoveAbsJ`` to a ``jointtarget``: the
  controller's joints equal a row's within 1e-6 rad;
- KRL ``LIN`` to an ``E6POS`` (the part P in the tool T) and RAPID ``MoveL`` /
  ``TriggL`` to a ``robtarget`` (the tool T in the part's work object): the pose from
  the row's joints by forward kinematics within 1 µm and 1e-6 rad;
- URScript ``movej`` equals a row; ``servoj`` (every 2 ms, the rows are 4 ms apart) lies
  on the straight joint step between two consecutive rows, within 1e-6 rad.

The first motion goes to the first row (home), the last one to the last row: the
program starts nowhere the plan does not, and no approach or retract of its own is
added.
"""

import csv
import json
import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from offline_prog.config.cell import load_cell, transform
from offline_prog.robot.model import load_robot

from conftest import CELLS
from rapid_reader import rapid_procs

POSITION_TOL_M = 1e-6
ANGLE_TOL_RAD = 1e-6
CASES = ["seal_plate_kr16", "weld_seam_irb2400", "tape_cylinder_ur10e", "seal_job_kr16"]


class Rows:
    """trajectory.csv of a plan folder: t (N,), segment (N,), q (N, 6) [rad], the
    controller's joints (N, 6) [rad] and the tool in the part X_PT (N, 4, 4)."""

    def __init__(self, folder, cell_file):
        with open(folder / "trajectory.csv") as stream:
            table = list(csv.DictReader(stream))
        self.t = np.array([float(r["t"]) for r in table])
        self.segment = np.array([r["segment"] for r in table])
        self.q = np.array([[float(r[f"q{i}"]) for i in range(1, 7)] for r in table])
        cell = load_cell(cell_file)
        robot = load_robot(cell.robot.model)
        self.q_c = robot.controller_joints(self.q)
        X_BT = (transform(cell.robot.X_IB).inverse() @ transform(cell.tool.X_IT)).GetAsMatrix4()
        X_PE = transform(cell.part.X_PE).GetAsMatrix4()
        # X_PT = X_PE · X_EB(q) · X_BT: where the fixed tool is on the part at each row.
        self.X_PT = X_PE @ np.linalg.inv(robot.forward(self.q)) @ X_BT

    def joints(self, q_c: np.ndarray) -> np.ndarray:
        """Rows whose controller joints equal q_c (6,) [rad]."""
        return np.flatnonzero(np.abs(self.q_c - q_c).max(axis=1) <= ANGLE_TOL_RAD)

    def pose(self, X_PT: np.ndarray) -> np.ndarray:
        """Rows whose tool-in-part pose equals X_PT (4, 4)."""
        dp = np.linalg.norm(self.X_PT[:, :3, 3] - X_PT[:3, 3], axis=1)
        near = np.flatnonzero(dp <= POSITION_TOL_M)
        R = Rotation.from_matrix(self.X_PT[near, :3, :3] @ X_PT[:3, :3].T)
        return near[R.magnitude() <= ANGLE_TOL_RAD]


def assert_in_order(matches: list[tuple[str, np.ndarray]], rows: Rows) -> None:
    """Each target (statement, its matching rows) has a row at or after the previous
    target's; the first is row 0 and the last the last row."""
    assert matches, "no motion statement found"
    at = 0
    for statement, found in matches:
        later = found[found >= at]
        assert len(later), f"{statement}: no planned row (after row {at}) has this target"
        at = int(later[0])
    assert 0 in matches[0][1], f"{matches[0][0]}: the first motion is not to the plan's start"
    assert len(rows.t) - 1 in matches[-1][1], f"{matches[-1][0]}: does not end at the plan's end"


# --- KRL ------------------------------------------------------------------------------------

KRL_DECL = re.compile(r"^DECL (E6POS|E6AXIS) (\w+)=\{(.*)\}$")


def krl_statements(folder, module="offline_prog"):
    """[(statement, declaration type, {field: value})] in execution order, sub-programs
    (``name_k( )``) followed."""
    decls = {
        m[2]: (m[1], {k: float(v) for k, v in (f.split() for f in m[3].split(","))})
        for line in (folder / f"{module}.dat").read_text().splitlines()
        if (m := KRL_DECL.match(line))
    }
    out = []
    for line in (folder / f"{module}.src").read_text().splitlines():
        words = line.split()
        if re.fullmatch(r"offline_prog_\d+\( \)", line.strip()):
            out += krl_statements(folder, line.strip().split("(")[0])
        elif words and words[0] in ("PTP", "LIN", "CIRC", "SPTP", "SLIN", "PTP_REL", "LIN_REL"):
            assert words[0] in ("PTP", "LIN"), f"unexpected motion {line}"
            out.append((line.strip(), *decls[words[1]]))
    return out


def krl_matches(folder, rows: Rows):
    matches = []
    for statement, kind, f in krl_statements(folder):
        if kind == "E6AXIS":
            q_c = np.deg2rad([f[f"A{i}"] for i in range(1, 7)])
            matches.append((statement, rows.joints(q_c)))
        else:  # E6POS: P in T (X_TP), KUKA's A, B, C = Z-Y'-X'' [deg], mm
            X_TP = np.eye(4)
            X_TP[:3, :3] = Rotation.from_euler("ZYX", [f["A"], f["B"], f["C"]], True).as_matrix()
            X_TP[:3, 3] = np.array([f["X"], f["Y"], f["Z"]]) * 1e-3
            matches.append((statement, rows.pose(np.linalg.inv(X_TP))))
    return matches


# --- RAPID ----------------------------------------------------------------------------------

ROBTARGET = re.compile(r"robtarget (\w+) := \[\[([^\]]*)\],\[([^\]]*)\]")
JOINTTARGET = re.compile(r"jointtarget (\w+) := \[\[([^\]]*)\]")
RAPID_MOVE = re.compile(r"^(MoveL|TriggL|MoveAbsJ|MoveJ|MoveC|TriggJ|TriggC) (\w+)")


def rapid_matches(folder, rows: Rows):
    text = (folder / "OfflineProg.mod").read_text()
    robtargets = {m[1]: (m[2], m[3]) for m in ROBTARGET.finditer(text)}
    jointtargets = {m[1]: m[2] for m in JOINTTARGET.finditer(text)}
    procs = {
        name: [line for line in lines if not line.startswith("!")]
        for name, lines in rapid_procs(text).items()
    }

    def run(proc):
        for line in procs[proc]:
            call = line.rstrip(";").strip()
            if call in procs:
                yield from run(call)
            else:
                yield line

    matches = []
    for line in run("main"):
        m = RAPID_MOVE.match(line)
        if m is None:
            continue
        assert m[1] in ("MoveL", "TriggL", "MoveAbsJ"), f"unexpected motion {line}"
        if m[1] == "MoveAbsJ":  # controller axes [deg] (the IRB 2400's axis 3 is q2 + q3)
            q_c = np.deg2rad(np.array(jointtargets[m[2]].split(","), float))
            matches.append((line, rows.joints(q_c)))
        else:  # the tool T in the work object (the part P): mm, quaternion w, x, y, z
            p, quat = (np.array(v.split(","), float) for v in robtargets[m[2]])
            X_PT = np.eye(4)
            X_PT[:3, :3] = Rotation.from_quat(quat[[1, 2, 3, 0]]).as_matrix()
            X_PT[:3, 3] = p * 1e-3
            matches.append((line, rows.pose(X_PT)))
    return matches


# --- URScript -------------------------------------------------------------------------------


def on_a_step(rows: Rows, q: np.ndarray) -> np.ndarray:
    """Rows i such that q lies on the joint step from row i to row i + 1 (or is row i)."""
    a, b = rows.q[:-1], rows.q[1:]
    d = b - a
    lam = np.clip(np.einsum("ij,ij->i", q - a, d) / np.maximum((d * d).sum(1), 1e-30), 0, 1)
    gap = np.abs(a + lam[:, None] * d - q).max(axis=1)
    return np.flatnonzero(gap <= ANGLE_TOL_RAD)


def urscript_matches(folder, rows: Rows):
    matches = []
    for raw in (folder / "offline_prog.script").read_text().splitlines():
        line = raw.strip()
        if not re.match(r"(movej|movel|movep|movec|servoj|speedj|speedl)\(", line):
            continue
        assert line.startswith(("movej(", "servoj(")), f"unexpected motion {line}"
        q = np.array(re.search(r"\(\[([^\]]*)\]", line)[1].split(","), float)
        if line.startswith("movej("):
            matches.append((line, rows.joints(q)))
        else:
            matches.append((line, on_a_step(rows, q)))
    return matches


@pytest.fixture(scope="module", params=CASES)
def planned(request, planned_job):
    job, folder = planned_job(request.param)
    assert job.feasible, job.failure
    return request.param, folder, Rows(folder, CELLS / f"{request.param}.yaml")


def test_every_motion_statement_is_a_planned_checked_row(planned):
    name, folder, rows = planned
    programs = folder / "programs"
    language = load_robot(load_cell(CELLS / f"{name}.yaml").robot.model).language
    reader = {"krl": krl_matches, "rapid": rapid_matches, "urscript": urscript_matches}
    matches = reader[language](programs, rows)
    assert_in_order(matches, rows)
    # The whole job was collision-checked: collisions.json of the same folder says so.
    collisions = json.loads((folder / "collisions.json").read_text())
    assert collisions["collision_free"] and collisions["samples_in_collision"] == []


def test_a_path_cell_is_planned_home_to_home(planned):
    """The one-seam demos run home → link → approach → seam → retract → link → home."""
    name, folder, rows = planned
    if name == "seal_job_kr16":
        pytest.skip("several seams: tests/job/test_job_plan.py")
    kinds = [rows.segment[0]] + [
        b for a, b in zip(rows.segment[:-1], rows.segment[1:], strict=True) if a != b
    ]
    assert kinds == ["link", "approach:seam", "process:seam", "retract:seam", "link"]
    np.testing.assert_allclose(rows.q[0], rows.q[-1], atol=1e-12)
