"""A whole job planned end to end (cells/seal_job_kr16.yaml): segments in order and
continuous, approach and retract distances as asked, process I/O where asked, the
trajectory.csv contract, and the report's cycle-time split."""

import csv

import numpy as np
import pytest
from gripper_clearance import GRIPPER_CLEARANCE_TOL_M, gripper_clearance

from offline_prog.config.cell import load_cell
from offline_prog.job.approach import MIN_MOVE_M
from offline_prog.robot.model import load_robot
from offline_prog.robot.record import folder_sha256
from offline_prog.scene.drake_cell import build_cell_model

from conftest import CELLS

JOB = "seal_job_kr16"
IO_TOL_M = 1e-3  # the issue: I/O within ±1 mm of the requested position
DISTANCE_TOL_M = 1e-8


@pytest.fixture(scope="module")
def job(planned_job):
    return planned_job(JOB)


def test_segments_run_home_to_home_in_order(job):
    plan, _ = job
    labels = [s.label for s in plan.samples.segments]
    names = [o.name for o in plan.chosen]
    expected = []
    for name in names:
        expected += ["link", f"approach:{name}", f"process:{name}", f"retract:{name}"]
    assert labels == [*expected, "link"]
    assert sorted(names) == sorted(s.name for s in load_cell(CELLS / f"{JOB}.yaml").seams)
    q = plan.samples.q
    np.testing.assert_allclose(q[0], plan.q_home, atol=1e-12)
    np.testing.assert_allclose(q[-1], plan.q_home, atol=1e-12)
    # Continuous: no joint moves farther between two rows than its speed limit allows,
    # at the joins of segments included.
    dt = np.diff(plan.samples.t)
    assert np.all(dt > 0)
    step = np.abs(np.diff(plan.robot.controller_joints(q), axis=0))
    assert np.all(step <= plan.robot.qd_max * dt[:, None] * 1.01)


def test_joints_within_limits_everywhere(job):
    plan, _ = job
    robot = plan.robot
    q_c = robot.controller_joints(plan.samples.q)
    assert np.all(q_c >= robot.q_lower - 1e-9) and np.all(q_c <= robot.q_upper + 1e-9)
    qd = np.abs(np.gradient(q_c, plan.samples.t, axis=0))
    assert np.all(qd <= robot.qd_max * 1.01)


def test_approach_and_retract_distances_as_asked(job):
    """The tool's point on the part (forward kinematics of the planned joints) comes onto
    each seam's first point from the asked distance and leaves its last point by it: a
    "normal" move starts (ends) that far off the surface along −n, a "tangent" one runs
    that far along the seam's tangent, in a straight line. On a flying seam (the
    default) a lead joins the straight move to the seam's end, where the tool is at
    speed; a lead that takes a normal move over lifts by (part of) its distance, and the
    straight move along −n is what is left."""
    plan, _ = job
    cell = plan.cell
    robot = plan.robot
    specs = {s.name: s for s in cell.seams}
    from offline_prog.config.cell import transform

    X_BT = (
        np.linalg.inv(transform(cell.robot.X_IB).GetAsMatrix4())
        @ transform(cell.tool.X_IT).GetAsMatrix4()
    )
    X_PE = transform(cell.part.X_PE).GetAsMatrix4()
    rows_of = {s.label: (s.start, s.stop) for s in plan.samples.segments}
    flying = 0
    for option in plan.chosen:
        seam = option.plan
        lead_in, lead_out = (
            lead.length_m if lead else 0.0 for lead in (seam.lead_in, seam.lead_out)
        )
        flying += lead_in > 0.0
        for end in ("approach", "retract"):
            spec = getattr(specs[option.name], end)
            d = spec.distance_mm * 1e-3
            start, stop = rows_of[f"{end}:{option.name}"]
            rows = slice(start, stop + 1)  # up to the next segment's first row
            p_PT = (X_PE @ np.linalg.inv(robot.forward(plan.samples.q[rows])) @ X_BT)[:, :3, 3]
            path = plan.samples.path_m[rows]
            if end == "approach":  # the straight move: σ ≤ −lead-in; then the lead
                on_seam, straight = p_PT[-1], path <= -lead_in + 1e-8
            else:  # the last row is the next link's (path_m NaN): the move's far end
                on_seam, straight = p_PT[0], path >= seam.path.length + lead_out - 1e-8
                straight[-1] = True
            assert abs(on_seam[2]) < 1e-6, (option.name, end)  # on the underside
            line = p_PT[straight]
            chord = line[-1] - line[0]
            length = np.linalg.norm(chord)
            if length > 0.0:  # straight: every point within 1 µm of the chord
                axis = chord / length
                off = (line - line[0]) - np.outer((line - line[0]) @ axis, axis)
                assert np.linalg.norm(off, axis=1).max() < 1e-6, (option.name, end)
            if spec.kind == "normal":  # off the surface along −n (the demo's n is +z of P)
                leaving = p_PT[0] if end == "approach" else p_PT[-1]
                assert leaving[2] == pytest.approx(-d, abs=1e-6), (option.name, end)
                assert length == 0.0 or abs(abs(chord[2]) - length) < 1e-6
                if lead_in == 0.0:  # at rest: the straight move alone
                    assert length == pytest.approx(d, abs=1e-6), (option.name, end)
            elif lead_in == 0.0:  # tangent at rest: the straight move runs the asked distance
                assert length == pytest.approx(d, abs=1e-6), (option.name, end)
            else:  # tangent, flying: the lead runs it along the tangent (the move the rest)
                leaving = p_PT[0] if end == "approach" else p_PT[-1]
                along = np.linalg.norm((leaving - on_seam)[:2])  # in the plate's plane
                assert along == pytest.approx(d, abs=MIN_MOVE_M), (option.name, end)
    assert flying == len(plan.chosen)  # the default: every seam runs flying


def test_process_io_switches_at_the_requested_positions(job):
    """do1 turns on 5 mm before each seam's start (on the approach) and off 2 mm before
    its end, measured along the tool's path on the part from the planned samples."""
    plan, folder = job
    io = plan.cell.tool.process_io
    with open(folder / "trajectory.csv") as f:
        rows = list(csv.DictReader(f))
    do = np.array([int(r["do1"]) for r in rows])
    path = np.array([float(r["sigma"]) if r["sigma"] else np.nan for r in rows])
    segment = np.array([r["segment"] for r in rows])
    step = np.nanmax(np.abs(np.diff(path)))  # path travelled between two samples
    assert step < IO_TOL_M
    for option in plan.chosen:
        mine = np.flatnonzero(np.char.endswith(segment.astype(str), f":{option.name}"))
        rises = mine[np.flatnonzero(np.diff(do[mine]) == 1) + 1]
        falls = mine[np.flatnonzero(np.diff(do[mine]) == -1) + 1]
        assert len(rises) == 1 and len(falls) == 1, option.name
        on_at, off_at = path[rises[0]], path[falls[0]]
        assert on_at == pytest.approx(-io.on.lead_mm * 1e-3, abs=IO_TOL_M)
        length = option.plan.path.length
        assert off_at == pytest.approx(length - io.off.lead_mm * 1e-3, abs=IO_TOL_M)
    events = {(e.seam, e.state): e.path_m for e in plan.io.switches}
    assert len(events) == 2 * len(plan.chosen)


def test_flow_follows_the_tcp_speed_while_on(job):
    plan, _ = job
    flow = plan.cell.tool.process_io.flow
    on = plan.io.digital.astype(bool)
    expected = np.clip(flow.offset + flow.per_mps * plan.tcp_speed, flow.min, flow.max)
    np.testing.assert_allclose(plan.io.analog[on], expected[on], atol=1e-12)
    # Off: the idle value, the flow at zero speed (README, Process I/O).
    assert np.all(plan.io.analog[~on] == np.clip(flow.offset, flow.min, flow.max))


def test_report_splits_cycle_time(job):
    import json

    plan, folder = job
    report = json.loads((folder / "report.json").read_text())
    j = report["job"]
    assert j["cycle_time_s"] == pytest.approx(plan.samples.t[-1])
    assert j["process_time_s"] + j["air_time_s"] == pytest.approx(j["cycle_time_s"])
    assert j["process_time_s"] == pytest.approx(
        sum(o.plan.trajectory.duration for o in plan.chosen), rel=1e-9
    )
    assert [s["seam"] for s in report["seams"]] == [o.name for o in plan.chosen]
    assert len(report["links"]) == len(plan.chosen) + 1
    assert report["collision_free"] == plan.collisions.collision_free
    # Which robot folder, in which state (issue 36): the bundled one here.
    assert report["robot_folder"] == str(plan.robot.urdf_path.parent)
    assert report["robot_files_sha256"] == folder_sha256(plan.robot.urdf_path.parent)


def test_home_pose_is_collision_free_in_the_cell():
    cell = load_cell(CELLS / f"{JOB}.yaml")
    robot = load_robot(cell.robot.model)
    scene = build_cell_model(cell, CELLS / f"{JOB}.yaml", robot)
    from offline_prog.collision.check import check_trajectory

    q = robot.urdf_joints(robot.home_c)
    result = check_trajectory(scene, q[None], np.zeros(1), np.zeros(1), clearance=0.005)
    assert result.collision_free


def test_trajectory_csv_has_the_one_seam_columns_then_segment(job):
    """The one-seam columns on every row (the seams' exact values on their rows, forward
    kinematics elsewhere), then the segment label: the contract."""
    from offline_prog.timing.trajectory import CSV_COLUMNS

    plan, folder = job
    with open(folder / "trajectory.csv") as f:
        header = f.readline().strip().split(",")
    assert header[: len(CSV_COLUMNS) + 1] == [*CSV_COLUMNS, "segment"]
    table = np.genfromtxt(folder / "trajectory.csv", delimiter=",", skip_header=1)
    X_IE = plan.robot.forward(plan.samples.q)  # the demo's base is at I
    np.testing.assert_allclose(table[:, 2:5], X_IE[:, :3, 3], atol=1e-6)
    for segment, option in zip(
        [g for g in plan.samples.segments if g.kind == "process"], plan.chosen, strict=True
    ):
        rows = slice(segment.start, segment.stop)
        exact = option.plan.trajectory.table()[: segment.stop - segment.start]
        np.testing.assert_allclose(table[rows, 1:18], exact[:, 1:18], rtol=1e-8, atol=1e-9)


def test_the_demo_needs_the_sampling_planner_and_its_links_are_clear(job):
    """The nozzle and its stand block the direct joint move of at least one link: OMPL
    plans it; every link is certified clear at the cell's clearance."""
    plan, _ = job
    from offline_prog.collision.motion import MotionChecker
    from offline_prog.robot.model import ROBOTS_DIR
    from offline_prog.stages import build_scene, load_inputs

    scene = build_scene(load_inputs(CELLS / f"{JOB}.yaml", ROBOTS_DIR))
    checker = MotionChecker(scene, clearance=0.005, self_clearance=0.005)
    planned = [link for link in plan.links if link.method == "planned"]
    assert planned
    for link in planned:
        assert not checker.move_clear(link.waypoints[0], link.waypoints[-1])
    for link in plan.links:
        assert all(
            checker.move_clear(a, b)
            for a, b in zip(link.waypoints[:-1], link.waypoints[1:], strict=True)
        )
    assert plan.collisions.collision_free and plan.feasible


@pytest.mark.slow  # a whole job planned through the CLI
def test_a_link_not_found_in_time_ends_with_exit_1_naming_it_reports_written(tmp_path, capsys):
    import json

    from offline_prog.cli import main

    text = (
        (CELLS / f"{JOB}.yaml")
        .read_text()
        .replace("job:\n  order: auto\n", "job:\n  order: auto\n  link_time_s: 0.0001\n")
    )
    cell = tmp_path / "job.yaml"
    cell.write_text(text)
    out = tmp_path / "out"
    code = main(["plan", str(cell), "--out", str(out)])
    stderr = capsys.readouterr().err
    assert code == 1, stderr
    line = stderr.strip().splitlines()[-1]
    assert "link" in line and "no collision-free path found within" in line
    report = json.loads((out / "report.json").read_text())
    failed = [k for k in report["links"] if k["failure"]]
    assert failed and failed[0]["name"] in line
    assert (out / "trajectory.csv").is_file() and (out / "collisions.json").is_file()
    assert not (out / "programs").exists()


def test_each_seam_runs_at_its_process_speed_record(job):
    """Each seam's plan holds the speed the cell gives it (config.process_speed: the
    stripe's own 0.15 m/s, the others' motion.speed); its time law caps and reaches it,
    and the program record the writers read carries it (issue 41: decided once)."""
    from offline_prog.config.process_speed import process_speed
    from offline_prog.export.job_program import JobProgramData

    plan, folder = job
    data = JobProgramData.load(folder)
    for option in plan.chosen:
        speed = process_speed(plan.cell, option.seam)
        assert option.plan.process_speed == speed
        law = option.plan.joints.retiming.law
        assert law.v_max == speed.v_m_s and law.v_peak <= speed.v_m_s
        seam = data.seams[data.seam_names.index(option.name)]
        assert seam.process_speed_m_s == speed.v_m_s
    assert {o.plan.process_speed.v_m_s for o in plan.chosen} == {0.1, 0.15}


def test_the_gripper_is_clear_by_a_second_library(planned_job):
    """The job's gripper keeps the clearance from the tool and the obstacles on every row
    (python-fcl on shapes built from the cell file, tests/gripper_clearance.py)."""
    _, folder = planned_job(JOB)
    distance, pair, row = gripper_clearance(CELLS / f"{JOB}.yaml", folder / "trajectory.csv")
    clearance = load_cell(CELLS / f"{JOB}.yaml").motion.clearance
    assert distance >= clearance - GRIPPER_CLEARANCE_TOL_M, (distance, pair, row)
