"""A whole job on the imported M-20iA as FANUC LS programs, read back: the links go
through the planned joints (FANUC axes), the positions reconstruct the planned flange
poses, and the process output switches (DB distance-before) within ±1 mm of the asked
positions along the path, as the KRL and RAPID job tests check."""

import re

import numpy as np
import pytest
from fanuc_reader import joints_from_config, pose, read_ls
from test_import_fanuc import FANUC, REPO, pytestmark  # noqa: F401  (skip without ../shared)

from offline_prog.export.job_program import JobProgramData
from offline_prog.plan import plan_job
from offline_prog.results.job_folder import write_job_outputs
from offline_prog.robot_import.run import import_robot

IO_TOL_M = 1e-3
JOINT_TOL_DEG = 1e-3
IO = (
    "tool:\n  process_io:\n    on:  {digital_output: 2, lead_mm: 3}\n"
    "    off: {digital_output: 2, lead_mm: 4}\n"
    "    flow: {analog_output: 1, per_mps: 30.0, offset: 1.0, min: 0.0, max: 10.0}\n"
)


@pytest.fixture(scope="module")
def fanuc_job(tmp_path_factory):
    work = tmp_path_factory.mktemp("fanuc_job")
    import_robot(
        FANUC / "fanuc_m20ia_support/urdf/m20ia.xacro", name="fanuc_m20ia", out=work / "robots",
        package_paths=[FANUC], vendor="fanuc", samples=500,
    )  # fmt: skip
    text = (REPO / "cells" / "seal_plate_kr16.yaml").read_text()
    text = text.replace("model: kuka_kr16_2\n", "model: fanuc_m20ia\n  robots_dir: robots\n")
    text = text.replace("motion:", "job: {order: given}\nmotion:", 1).replace("tool:\n", IO, 1)
    cell = work / "seal_job_m20ia.yaml"
    cell.write_text(text)
    job = plan_job(cell)
    assert job.feasible, job.failure
    write_job_outputs(job, work / "out")
    return JobProgramData.load(work / "out"), work / "out" / "programs", job.robot


def _run(folder, name="OFFLINE_PROG"):
    """Motion statements in execution order: (statement, position entry)."""
    out = []

    def read(program):
        ls = read_ls(folder / f"{program}.ls")
        for statement in ls["mn"]:
            if statement.startswith("CALL "):
                read(statement.split()[1])
            elif m := re.match(r"([JL]) P\[(\d+)\]", statement):
                out.append((statement, ls["pos"][int(m[2])]))
            elif statement.startswith("AO["):
                out.append((statement, None))

    read(name)
    return out


def test_fanuc_job_links_poses_and_io(fanuc_job, tmp_path):
    data, folder, robot = fanuc_job
    _check_job(data, folder, robot)
    # With a line limit each seam runs as called parts that switch at the same places.
    from offline_prog.export.formats import export

    files = export(data, "fanuc", tmp_path, line_limit=100)
    assert len(files) > 2 and all(len(read_ls(f)["mn"]) <= 100 for f in files)
    _check_job(data, tmp_path, robot)


def _check_job(data, folder, robot):
    run = _run(folder)
    joints = [np.radians(e["joints"]) for s, e in run if s.startswith("J ")]
    planned = [data.link_waypoints[0][0]] + [q for w in data.link_waypoints for q in w[1:]]
    np.testing.assert_allclose(
        np.degrees(joints), np.degrees(robot.controller_joints(np.array(planned))),
        atol=JOINT_TOL_DEG,
    )  # fmt: skip
    X_PE, p_BT = np.linalg.inv(data.job.X_EP), data.job.X_BT[:3, 3]
    here, position, switched, flows, approach = None, 0.0, {}, [], None
    for statement, entry in run:
        if entry is None:
            flows.append(float(statement.split("=")[1]))
            continue
        if statement.startswith("J "):
            q = robot.urdf_joints(np.radians(entry["joints"])[None])[0]
            X_BE = robot.forward(q[None])[0]
        else:
            X_BE = pose(entry["xyzwpr"]) @ X_PE
            q = joints_from_config(robot, X_BE, entry["config"], entry["turns"])
            np.testing.assert_allclose(robot.forward(q[None])[0], X_BE, atol=1e-9)
        X_BP = X_BE @ data.job.X_EP
        p_PT = X_BP[:3, :3].T @ (p_BT - X_BP[:3, 3])  # the fixed tool's point on the part
        if statement.startswith("J "):  # a link ends where the approach starts
            position, approach = 0.0, None
        else:  # along the tool's path on the part, from the approach's start
            step = np.linalg.norm(p_PT - here)
            approach = step if approach is None else approach
            if "DB" in statement:
                d = float(re.search(r"DB ([\d.]+)mm", statement)[1]) * 1e-3
                state = re.search(r"DO\[\d+\]=(ON|OFF)", statement)[1] == "ON"
                switched[state] = position + step - d - approach  # from the seam's start
            position += step
        here = p_PT
    on, off = data.switch_positions(0)
    assert switched[True] == pytest.approx(on, abs=IO_TOL_M)
    assert switched[False] == pytest.approx(off, abs=IO_TOL_M)
    io = data.process_io
    assert flows[-1] == 0 and all(io.min <= v <= io.max for v in flows)
    assert max(flows) == pytest.approx(
        io.offset + io.per_mps * data.job.process_speed_m_s, abs=0.05
    )
