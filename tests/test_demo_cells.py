"""Every one-seam demo cell plans end to end as a one-seam job, written as `plan` writes it
(home → link → approach → seam → retract → link → home), and its trajectory.csv alone
shows the fixed-TCP properties on the seam's rows (segment ``process:seam``): the part
point under the tool is on the path, the tool axes are the process frame, the TCP speed
is the commanded speed; and on every row the joints drive the flange along the poses."""

import json
import re

import numpy as np
import pytest
from gripper_clearance import GRIPPER_CLEARANCE_TOL_M, gripper_clearance
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from offline_prog.config.cell import load_cell, transform
from offline_prog.path.inputs import load_points
from offline_prog.robot.model import load_robot
from offline_prog.scene.drake_cell import build_drake_cell
from offline_prog.timing.trajectory import CSV_COLUMNS

from conftest import ONE_SEAM_CELLS

DEMO_CELLS = ONE_SEAM_CELLS  # whole jobs (seams:) have their own tests in tests/job


@pytest.fixture(scope="module", params=DEMO_CELLS, ids=lambda p: p.stem)
def planned_job_csv(request, planned_job):
    """(cell, header without segment, (N, ·) every row, (N,) segment labels, report),
    from the folder ``plan`` writes (the session's plan of the cell, shared with the
    other tests that read it; the README's command 1 runs the command itself in CI)."""
    job, out = planned_job(request.param.stem)
    assert job.feasible, job.failure
    with open(out / "trajectory.csv") as stream:
        header = stream.readline().strip().split(",")
    segment = header.index("segment")
    rows = [line.strip().split(",") for line in (out / "trajectory.csv").open().readlines()[1:]]
    labels = np.array([row[segment] for row in rows])
    numbers = [
        [float(v) if v else np.nan for k, v in enumerate(row) if k != segment] for row in rows
    ]
    whole = np.array(numbers)
    report = json.loads((out / "report.json").read_text())
    return request.param, [h for h in header if h != "segment"], whole, labels, report


@pytest.fixture(scope="module")
def planned(planned_job_csv):
    """The seam's rows (segment process:seam, and the next row: the seam's last sample
    is where the retract starts), its clock from 0."""
    cell_file, header, whole, labels, report = planned_job_csv
    rows = np.flatnonzero(labels == "process:seam")
    table = whole[rows[0] : rows[-1] + 2].copy()
    table[:, 0] -= table[0, 0]
    return cell_file, header, table, report


def test_one_seam_job_segments_and_defaults(planned_job_csv):
    """A path: cell runs home → link → approach → seam → retract → link → home, starting
    and ending at the home pose, and its report says how home, approach and retract
    were chosen (robot.yaml / job.home; normal 50 mm by default)."""
    cell_file, header, whole, labels, report = planned_job_csv
    order = [labels[0]] + [b for a, b in zip(labels[:-1], labels[1:], strict=True) if a != b]
    assert order == ["link", "approach:seam", "process:seam", "retract:seam", "link"]
    cell, robot = load_cell(cell_file), load_robot(load_cell(cell_file).robot.model)
    col = {name: i for i, name in enumerate(header)}
    q = whole[:, [col[f"q{i}"] for i in range(1, 7)]]
    home = np.deg2rad(cell.job.home.joints_deg) if cell.job and cell.job.home else robot.home_c
    for row in (q[0], q[-1]):
        np.testing.assert_allclose(robot.controller_joints(row), home, atol=1e-9)
    job = report["job"]
    assert job["home_from"] == ("job.home" if cell.job and cell.job.home else "robot.yaml home_deg")
    (seam,) = job["order"]
    assert seam["approach"] == seam["retract"] == {"kind": "normal", "distance_mm": 50.0}
    # The seam's one-seam keys stay at the top of report.json; the cycle is the job's.
    assert report["trajectory"]["duration_s"] == report["seams"][0]["trajectory"]["duration_s"]
    assert job["cycle_time_s"] == pytest.approx(whole[-1, 0], abs=1e-6)
    assert job["cycle_time_s"] > report["trajectory"]["duration_s"]


def test_header_and_sampling(planned):
    cell_file, header, table, report = planned
    assert header[: len(CSV_COLUMNS)] == CSV_COLUMNS
    joints = [f"q{i}" for i in range(1, 7)] + [f"qd{i}" for i in range(1, 7)]
    rest = header[len(CSV_COLUMNS) :]
    assert rest[:12] == joints
    # Then the process outputs (do<n>, ao<n>) and the process model's quality column.
    quality = [report["quality"]["column"]] if "quality" in report else []
    assert [h for h in rest[12:] if not re.fullmatch(r"[da]o\d+", h)] == quality
    t = table[:, 0]
    assert t[0] == 0.0 and np.all(np.diff(t) > 0)
    # 250 Hz inside; a flying seam's ends (σ = 0, L) are samples of their own, a grid
    # time within a quarter step of one dropped (at rest: the law's end is appended).
    step = np.diff(t) * 250.0
    np.testing.assert_allclose(step[1:-1], 1.0, atol=2.5e-6)  # CSV: 10 digits
    assert 0.25 - 1e-5 <= step[0] <= 1.25 + 1e-5 and step[-1] <= 1.25 + 1e-5
    assert t[-1] == pytest.approx(report["trajectory"]["duration_s"], abs=1e-6)
    assert report["fit"]["max_error_mm"] <= report["fit"]["tolerance_mm"]


def test_part_point_under_tcp_is_on_the_path(planned):
    cell_file, header, table, report = planned
    cell = load_cell(cell_file)
    col = {name: i for i, name in enumerate(header)}
    X_IT, X_PE = transform(cell.tool.X_IT), transform(cell.part.X_PE)
    R_IE = Rotation.from_euler("XYZ", table[:, [col["alpha"], col["beta"], col["gamma"]]])
    p_IE = table[:, [col["x"], col["y"], col["z"]]]
    # p_PQ = X_PE · X_EI · p_IT: the part point at the TCP, from the CSV pose alone.
    p_EQ = R_IE.inv().apply(X_IT.translation() - p_IE)
    p_PQ = p_EQ @ X_PE.rotation().matrix().T + X_PE.translation()
    given = load_points(cell_file, cell).p_PR
    if cell.path.closed:
        given = np.vstack([given, given[:1]])
    fit_tol = report["fit"]["max_error_mm"] * 1e-3
    # Distance to the given points' polyline, densified (spacing ≤ 1 mm, so the
    # polyline's own sagitta is far below the fit tolerance).
    dense = np.vstack(
        [np.linspace(a, b, 20, endpoint=False) for a, b in zip(given[:-1], given[1:], strict=True)]
    )
    dist, _ = cKDTree(dense).query(p_PQ)
    assert dist.max() <= fit_tol + 1e-4
    # The tool's axes are [t n b]: T's x axis is the direction the part point moves
    # along the path (opposite to the part's motion under the tool).
    R_IP = R_IE * Rotation.from_matrix(X_PE.rotation().matrix().T)
    tangent_I = R_IP.apply(np.gradient(p_PQ, axis=0))
    moving = np.linalg.norm(tangent_I, axis=1) > 1e-7
    tangent_I = tangent_I[moving] / np.linalg.norm(tangent_I[moving], axis=1, keepdims=True)
    # A symmetric tool may be turned about its axis, by tool_rotation_deg or, along the
    # path, within tool_turn_deg: the tangent stays square to the axis, at that turn.
    axis = np.eye(3)["xyz".index(cell.tool.symmetry_axis)]
    R_IT = Rotation.from_matrix(X_IT.rotation().matrix())
    x_T, axis_I = R_IT.apply([1.0, 0.0, 0.0]), R_IT.apply(axis)
    np.testing.assert_allclose(tangent_I @ axis_I, 0.0, atol=np.sin(np.deg2rad(1.0)))
    phi = np.rad2deg(np.arctan2(np.cross(x_T, tangent_I) @ axis_I, tangent_I @ x_T))
    low, high = report["robot_motion"]["tool_turn_deg"]
    fixed = report["robot_motion"]["tool_rotation_deg"]
    assert (low == high == fixed) or cell.tool.turn_smoothing_mm > 0
    assert phi.min() > low - 0.1 and phi.max() < high + 0.1


def test_tcp_speed_is_the_commanded_speed(planned):
    cell_file, header, table, report = planned
    cell = load_cell(cell_file)
    col = {name: i for i, name in enumerate(header)}
    v = table[:, [col["vx"], col["vy"], col["vz"]]]
    w = table[:, [col["wx"], col["wy"], col["wz"]]]
    p_IE = table[:, [col["x"], col["y"], col["z"]]]
    p_IT = transform(cell.tool.X_IT).translation()
    # On the seam's own rows (the last row is the retract's first: off the seam, its v
    # and w are central differences, inexact where a flying seam's lead-out runs on).
    v_tcp = np.linalg.norm(v + np.cross(w, p_IT - p_IE), axis=1)[:-1]
    np.testing.assert_allclose(v_tcp, table[:-1, col["tcp_speed"]], atol=1e-8)
    speed = report["motion"]["top_speed_m_s"]
    # Recomputed from the CSV's rounded columns: within their 1e-8 m/s of tcp_speed
    # (above), which a law holding the speed exactly (sin²'s plateau) may reach.
    assert v_tcp.max() <= speed * (1 + 1e-8) + 1e-8
    assert table[:, col["tcp_speed"]].max() <= speed * (1 + 1e-9)
    # σ from positions alone (chord per time step) matches the TCP speed within 0.05 %.
    sigma_dot = np.diff(table[:, col["sigma"]]) / np.diff(table[:, col["t"]])
    mid_speed = 0.5 * (table[1:, col["tcp_speed"]] + table[:-1, col["tcp_speed"]])
    moving = mid_speed > 0.1 * speed
    dt = np.diff(table[:, col["t"]])[moving]
    midpoint_rule = dt**2 * cell.motion.max_jerk / 8  # chord vs endpoint-mean difference
    assert np.all(np.abs(sigma_dot[moving] - mid_speed[moving]) <= 5e-4 * speed + midpoint_rule)
    # The process speed is held over long stretches (lowered only where the joints
    # need it, see the report's speed reductions).
    at_speed = table[:, col["tcp_speed"]] >= speed * (1 - 1e-9)
    assert at_speed.mean() >= 0.4
    assert report["trajectory"]["chord_speed_max_error_rel"] <= 5e-4
    assert report["trajectory"]["tcp_speed_max_error_rel"] <= 1e-9


def test_joint_columns_drive_the_flange_along_the_planned_poses(planned_job_csv):
    """Drake's FK of the URDF at q1..q6 reproduces the planned flange pose on every row
    of the job (what the controller will do is what the preview shows), within the
    joint limits."""
    cell_file, header, table, _, report = planned_job_csv
    cell = load_cell(cell_file)
    col = {name: i for i, name in enumerate(header)}
    robot = load_robot(cell.robot.model)
    drake = build_drake_cell(
        robot,
        X_IB=transform(cell.robot.X_IB),
        X_IT=transform(cell.tool.X_IT),
        X_PE=transform(cell.part.X_PE),
    )
    q = table[:, [col[f"q{i}"] for i in range(1, 7)]]
    qd = table[:, [col[f"qd{i}"] for i in range(1, 7)]]
    q_c, qd_c = robot.controller_joints(q), robot.controller_joints(qd)  # limits apply there
    assert np.all(q_c >= robot.q_lower) and np.all(q_c <= robot.q_upper)
    assert np.all(np.abs(qd_c) <= robot.qd_max * (1 + 1e-6))
    rows = np.linspace(0, len(table) - 1, 60).astype(int)
    for i in rows:
        X_IE = drake.X_IE(q[i])
        p_csv = table[i, [col["x"], col["y"], col["z"]]]
        R_csv = Rotation.from_euler("XYZ", table[i, [col["alpha"], col["beta"], col["gamma"]]])
        assert np.linalg.norm(X_IE.translation() - p_csv) <= 1e-8
        R_err = Rotation.from_matrix(X_IE.rotation().matrix()) * R_csv.inv()
        assert R_err.magnitude() <= 1e-8
    # qd is the time derivative of q (central differences, interior samples).
    t = table[:, col["t"]]
    fd = (q[2:] - q[:-2]) / (t[2:] - t[:-2])[:, None]
    assert np.abs(fd - qd[1:-1]).max() <= 1e-3 * max(np.abs(qd).max(), 1e-3)
    assert report["robot_motion"]["min_joint_limit_margin_deg"] > 0


def test_demo_cells_plan_clear_at_the_default_clearances_with_vendor_meshes(planned):
    """Every demo cell keeps 5 mm to everything and 5 mm between the robot's links (the
    pairs its self-collision matrix marks "check"); the skipped pairs are listed."""
    file, _, _, report = planned
    assert "clearance" not in file.read_text().split("motion:")[1].split("obstacles:")[0]
    assert report["clearance_m"] == 0.005 and report["self_clearance_m"] == 0.005
    assert report["collision_free"] and report["min_distance_m"] >= 0.005
    skipped = report["self_collision_pairs_skipped"]
    assert skipped and all(p["class"] != "check" and p["reason"] for p in skipped)
    assert {p["class"] for p in skipped} <= {"adjacent", "always", "constant", "never"}


def test_the_gripper_is_clear_by_a_second_library(request, planned_job_csv, planned_job):
    """The demo's gripper keeps the clearance from the tool and the obstacles on every
    row of trajectory.csv, measured with python-fcl on shapes built from the cell file
    (tests/gripper_clearance.py), not the planner's SceneGraph."""
    cell_file = planned_job_csv[0]
    _, folder = planned_job(cell_file.stem)
    distance, pair, row = gripper_clearance(cell_file, folder / "trajectory.csv")
    clearance = load_cell(cell_file).motion.clearance
    assert distance >= clearance - GRIPPER_CLEARANCE_TOL_M, (distance, pair, row)
