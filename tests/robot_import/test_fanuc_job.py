"""A whole job on the imported M-20iA as FANUC LS programs, read back: the links go
through the planned joints (FANUC axes), the positions reconstruct the planned flange
poses, and the process output switches (DB distance-before) within ±1 mm of the
positions computed here from the cell's ``lead_mm`` and the seam's length, as the KRL
and RAPID job tests check. The stripe of issue 24 (``on.lead_mm: -100`` on a 240 mm
straight seam: on and off on the same motion) keeps both switches, and the program's
``AO`` values replayed along the path agree with the plan's ``ao`` column."""

import csv
import dataclasses
import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from calibrated import moved
from fanuc_reader import nominal_frames, pose, read_ls, run_statements, walk
from hypothesis import given, settings
from hypothesis import strategies as st
from program_replay import fanuc_flow, fanuc_switch_errors, replayed
from replay_jobs import exported, import_m20ia, on_m20ia, stripe_flying, stripe_job
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation, Slerp
from test_import_fanuc import FANUC, REPO, pytestmark  # noqa: F401  (skip without ../shared)

from offline_prog.config.cell import load_cell
from offline_prog.constants import FLOW_PRIME_LAGS
from offline_prog.export.formats import controller_post
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.post import write_program
from offline_prog.io_events import IoEvent, Signal
from offline_prog.plan import plan_job
from offline_prog.results.job_folder import write_job_outputs

from conftest import with_own_io

IO_TOL_M = 1e-3
SWITCH_TOL_M = 0.5e-3  # a DB switch lands this close to the cell's position on the part
JOINT_TOL_DEG = 1e-3
REPLAY_STEPS = 16  # the bead replay's time steps per planned row
FLOW_TOL_V = 0.05  # a motion's AO value against the plan's column on its rows
IO = (
    "tool:\n  process_io:\n    on:  {digital_output: 2, lead_mm: 3}\n"
    "    off: {digital_output: 2, lead_mm: 4}\n"
    "    flow: {analog_output: 1, per_mps: 30.0, offset: 1.0, min: 0.0, max: 10.0}\n"
)
# The stripe of cells/seal_job_kr16.yaml, alone (issue 24's case), on the M-20iA.
START_P, END_P = np.array([-0.120, 0.080, 0.0]), np.array([0.120, 0.080, 0.0])
LENGTH_M = float(np.linalg.norm(END_P - START_P))  # 240 mm
ON_LEAD_MM, OFF_LEAD_MM, PER_MPS, OFFSET_V, LAG_S = -100.0, 2.0, 40.0, 0.5, 0.1
SPEED_M_S = 0.15


def write_fanuc_job(data: JobProgramData, folder: Path) -> list[Path]:
    """The FANUC writer's files of the job in folder."""
    return write_program(controller_post(data, "fanuc"), folder)


def _m20ia(work: Path) -> None:
    import_m20ia(work, FANUC)


@pytest.fixture(scope="module")
def fanuc_job(tmp_path_factory):
    work = tmp_path_factory.mktemp("fanuc_job")
    _m20ia(work)
    text = on_m20ia((REPO / "cells" / "seal_plate_kr16.yaml").read_text())
    text = text.replace("motion:", "job: {order: given}\nmotion:", 1)
    text = with_own_io(text, IO)
    cell = work / "seal_job_m20ia.yaml"
    cell.write_text(text)
    job = plan_job(cell)
    assert job.feasible, job.failure
    write_job_outputs(job, work / "out")
    return JobProgramData.load(work / "out"), work / "out" / "programs", job.robot, cell


def _stripe_job() -> tuple[str, str]:
    """The seal job on the M-20iA cut to its stripe, run forward in the given order:
    (the text before ``seams:``, to edit; the rest from ``seams:`` on)."""
    return stripe_job(on_m20ia((REPO / "cells" / "seal_job_kr16.yaml").read_text()))


@pytest.fixture(scope="module")
def stripe(tmp_path_factory):
    """(JobProgramData, plan folder, robot) of the stripe with on.lead_mm −100."""
    work = tmp_path_factory.mktemp("fanuc_stripe")
    _m20ia(work)
    head, seams = _stripe_job()
    head = head.replace("lead_mm: 5}", f"lead_mm: {ON_LEAD_MM}}}")
    head = head.replace("lead_mm: 2}", f"lead_mm: {OFF_LEAD_MM}}}")
    head = head.replace("min: 0.0, max: 10.0}", f"min: 0.0, max: 10.0, lag_s: {LAG_S}}}")
    cell = work / "stripe.yaml"
    cell.write_text(head + seams)
    io = load_cell(cell).tool.process_io
    assert (io.on.lead_mm, io.off.lead_mm, io.flow.lag_s) == (ON_LEAD_MM, OFF_LEAD_MM, LAG_S)
    assert (io.flow.per_mps, io.flow.offset) == (PER_MPS, OFFSET_V)
    job = plan_job(cell)
    assert job.feasible, job.failure
    write_job_outputs(job, work / "plan")
    return JobProgramData.load(work / "plan"), work / "plan", job.robot


def test_fanuc_job_links_poses_and_io(fanuc_job, tmp_path):
    data, folder, robot, cell = fanuc_job
    _check_job(data, folder, robot, cell)
    # With a line limit each seam runs as called parts that switch at the same places.
    from offline_prog.export.formats import export

    files = export(data, "fanuc", tmp_path, line_limit=100)
    assert len(files) > 2 and all(len(read_ls(f)["mn"]) <= 100 for f in files)
    _check_job(data, tmp_path, robot, cell)
    # ... and run the unsplit programs' statements and positions, in order (the
    # position registers are numbered per program).

    def statements(folder):
        return [(re.sub(r"P\[\d+\]", "P[]", s), p) for s, p in run_statements(folder)]

    assert max(len(read_ls(f)["mn"]) for f in folder.glob("*.ls")) > 100
    assert len(files) > len(list(folder.glob("*.ls")))
    assert statements(tmp_path) == statements(folder)


def _check_job(data, folder, robot, cell):
    run = run_statements(folder)
    joints = [np.radians(e["joints"]) for s, e in run if s.startswith("J ")]
    planned = [data.link_waypoints[0][0]] + [q for w in data.link_waypoints for q in w[1:]]
    np.testing.assert_allclose(
        np.degrees(joints),
        np.degrees(robot.controller_joints(np.array(planned))),
        atol=JOINT_TOL_DEG,
    )
    io = load_cell(cell).tool.process_io
    seams = walk(data, folder, robot)
    assert len(seams) == len(data.seam_names)
    for k, seam in enumerate(seams):
        on, off = -io.on.lead_mm * 1e-3, data.seam_lengths_m[k] - io.off.lead_mm * 1e-3
        assert [(n, s) for n, s, _ in seam["db"]] == [(2, True), (2, False)]
        assert seam["db"][0][2] == pytest.approx(on, abs=SWITCH_TOL_M)
        assert seam["db"][1][2] == pytest.approx(off, abs=SWITCH_TOL_M)
        # The flow (lag 0): live from the on switch to the off switch, idle outside.
        flow = io.flow
        for a, b, v in seam["moves"]:
            if b <= on - IO_TOL_M or a >= off + IO_TOL_M:
                assert v == pytest.approx(flow.offset), (a, b, v)
            elif on + IO_TOL_M <= a and b <= off - IO_TOL_M:
                assert flow.offset < v <= flow.max
    live = [v for seam in seams for _, _, v in seam["moves"] if v > io.flow.offset]
    assert max(live) == pytest.approx(
        io.flow.offset + io.flow.per_mps * data.job.process_speed_m_s, abs=0.05
    )


def test_fanuc_keeps_both_switches_on_a_straight_seam(stripe, tmp_path):
    """Issue 24's case: on 100 mm into the stripe, off 2 mm before its end."""
    data, _, robot = stripe
    write_fanuc_job(data, tmp_path)
    (seam,) = walk(data, tmp_path, robot)
    on, off = -ON_LEAD_MM * 1e-3, LENGTH_M - OFF_LEAD_MM * 1e-3
    assert [(n, s) for n, s, _ in seam["db"]] == [(1, True), (1, False)]
    assert seam["db"][0][2] == pytest.approx(on, abs=SWITCH_TOL_M)
    assert seam["db"][1][2] == pytest.approx(off, abs=SWITCH_TOL_M)
    statements = [s for f in tmp_path.glob("*.ls") for s in read_ls(f)["mn"]]
    assert sum("DO[" in s for s in statements if not s.startswith("!")) == 2  # not the flow
    # The flow goes live FLOW_PRIME_LAGS lags ahead of the on switch (the stripe runs
    # flying, the default: at its speed there), and is cut as the gun closes (not led).
    first = next(a for a, _, v in seam["moves"] if v > OFFSET_V + 0.01)
    assert first == pytest.approx(on - SPEED_M_S * FLOW_PRIME_LAGS * LAG_S, abs=IO_TOL_M)
    last = max(b for _, b, v in seam["moves"] if v > OFFSET_V + 0.01)
    assert last == pytest.approx(off, abs=IO_TOL_M)  # live until the valve closes


def test_fanuc_flow_replays_the_plans_ao_column(stripe, tmp_path):
    """Each planned row's ``ao1`` (trajectory.csv) against the AO value the program
    holds where the tool is at that row (its position from the row's joints)."""
    data, folder, robot = stripe
    write_fanuc_job(data, tmp_path)
    (seam,) = walk(data, tmp_path, robot)
    with open(folder / "trajectory.csv") as f:
        rows = [r for r in csv.DictReader(f) if r["segment"] != "link"]  # the stripe's
    q = np.array([[float(r[f"q{j}"]) for j in range(1, 7)] for r in rows])  # [rad]
    X_BP = robot.forward(q) @ data.job.X_EP
    p_PT = np.einsum("nji,nj->ni", X_BP[:, :3, :3], data.job.X_BT[:3, 3] - X_BP[:, :3, 3])
    position = (p_PT - START_P) @ (END_P - START_P) / LENGTH_M
    planned = np.array([float(r["ao1"]) for r in rows])
    edges = [a for a, _, _ in seam["moves"]]
    checked = 0
    for x, ao in zip(position, planned, strict=True):
        held = [v for a, b, v in seam["moves"] if a < x <= b]
        if not held or min(abs(x - e) for e in edges) < IO_TOL_M:
            continue  # at the approach's start, or within 1 mm of an L point
        checked += 1
        assert held[0] == pytest.approx(ao, abs=FLOW_TOL_V), x
    assert checked > 0.5 * len(rows)  # the rest: at rest, or within 1 mm of a point
    assert planned.max() > OFFSET_V + 1 and min(v for _, _, v in seam["moves"]) == OFFSET_V


@settings(max_examples=8, deadline=None, derandomize=True)
@given(
    positions_mm=st.lists(st.floats(-25.0, 265.0), min_size=2, max_size=6, unique=True)
    .map(sorted)
    .filter(lambda p: len(p) % 2 == 0 and min(np.diff(p)) > 2.0)
)
def test_fanuc_switches_where_the_events_say(stripe, positions_mm):
    """On/off pairs anywhere on the stripe's approach, seam and retract, several on one
    motion: every one becomes a DB option at its position, in order."""
    data, _, robot = stripe
    events = tuple(
        IoEvent("stripe", Signal.DIGITAL, 1, k % 2 == 0, float(k % 2 == 0), p * 1e-3, 0.0, p * 1e-3)
        for k, p in enumerate(positions_mm)
    )
    data = dataclasses.replace(data, events=events)
    with tempfile.TemporaryDirectory() as folder:
        write_fanuc_job(data, Path(folder))
        (seam,) = walk(data, Path(folder), robot)
    assert [s for _, s, _ in seam["db"]] == [k % 2 == 0 for k in range(len(positions_mm))]
    assert [p for _, _, p in seam["db"]] == [
        pytest.approx(p * 1e-3, abs=SWITCH_TOL_M) for p in positions_mm
    ]


def test_fanuc_switches_land_where_the_part_turns(fanuc_job):
    """Issue 37: FANUC's DB measures the programmed TCP (P's origin, UTOOL), not the
    tool's point on the part. On/off pairs every few millimetres around the plate's
    seam, corners included: each switch, replayed from the program text (the TCP on its
    chord, the orientation slerped, the output set where the TCP comes within the DB
    distance of the motion's end), lands within ±0.5 mm of its position on the part."""
    data, _, robot, _ = fanuc_job
    name, length = data.seam_names[0], data.seam_lengths_m[0]
    positions = np.linspace(0.002, length - 0.002, 60)
    events = tuple(
        IoEvent(name, Signal.DIGITAL, 2, k % 2 == 0, float(k % 2 == 0), p, 0.0, p)
        for k, p in enumerate(positions)
    )
    analog = tuple(e for e in data.events if e.signal is Signal.ANALOG)
    seam_data = data.seams[0]
    dense = seam_data.X_PT_dense
    # The part turns near the switches: the tool's heading on the part changes by more
    # than 10° within 5 mm of several of them (the corners).
    heading = np.gradient(dense[:, :3, 3], seam_data.path_dense_m, axis=0)
    heading /= np.linalg.norm(heading, axis=1, keepdims=True)
    turns = 0
    for p in positions:
        near = np.abs(seam_data.path_dense_m - p) < 5e-3
        turns += np.degrees(np.arccos(np.clip(heading[near] @ heading[near][0], -1, 1))).max() > 10
    assert turns >= 4
    with tempfile.TemporaryDirectory() as folder:
        write_fanuc_job(dataclasses.replace(data, events=events + analog), Path(folder))
        seam = walk(data, Path(folder), robot)[0]
    assert [s for _, s, _ in seam["db"]] == [k % 2 == 0 for k in range(len(positions))]
    landed = np.array([p for _, _, p in seam["db"]])
    assert np.abs(landed - positions).max() <= SWITCH_TOL_M


def test_fanuc_refuses_switches_no_sample_separates(stripe, tmp_path):
    data, _, _ = stripe
    events = tuple(
        IoEvent("stripe", Signal.DIGITAL, 1, state, float(state), x, 0.0, x)
        for state, x in ((True, 0.1), (False, 0.1 + 1e-5))
    )
    with pytest.raises(ValueError, match=r"seam stripe: .* 100\.000 mm and at 100\.010 mm"):
        write_fanuc_job(dataclasses.replace(data, events=events), tmp_path)


def test_plan_refuses_switches_no_sample_separates_in_one_line(tmp_path, capsys):
    """A cell whose on and off switches lie 0.01 mm apart: no FANUC motion can carry
    both DB options, so planning stops with one line naming the seam, exit 2."""
    from offline_prog.cli import main

    _m20ia(tmp_path)
    text = on_m20ia((REPO / "cells" / "seal_job_kr16.yaml").read_text())
    head, rest = text.split("seams:", 1)
    seam = rest[rest.index("  - name: stripe") : rest.index("job:")]
    head = head.replace("lead_mm: 5}", "lead_mm: -100}").replace("lead_mm: 2}", "lead_mm: 139.99}")
    cell = tmp_path / "crowded.yaml"
    cell.write_text(head + "seams:\n" + seam + rest[rest.index("job:") :])
    capsys.readouterr()
    code = main(["plan", str(cell), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "crowded.yaml: tool.process_io: seam stripe:" in err[0]
    assert "100.000 mm and at 100.010 mm" in err[0]


@pytest.fixture(scope="module")
def bead_stripe(tmp_path_factory):
    """(JobProgramData, plan folder, robot, job) of the stripe on the M-20iA laying the
    sealing demo's bead (issue 28): the flow's gain and lead are the bead model's."""
    work = tmp_path_factory.mktemp("fanuc_bead")
    _m20ia(work)
    head, seams = _stripe_job()
    head = head.replace("per_mps: 40.0, offset: 0.5, ", "")
    bead = (
        "process:\n  model: bead\n"
        "  bead: {area_mm2: 12.0, flow_mm3_s_per_unit: 250.0, lag_s: 0.08}\n"
    )
    cell = work / "bead.yaml"
    cell.write_text(bead + head + seams)
    job = plan_job(cell)
    assert job.feasible, job.failure
    write_job_outputs(job, work / "plan")
    return JobProgramData.load(work / "plan"), work / "plan", job.robot, job


def test_fanuc_flow_replayed_through_the_bead_gives_the_reported_bead(bead_stripe, tmp_path):
    """Issue 28: the AO values the LS program holds along the path (each L motion's,
    placed by the program's own poses), replayed through the bead model (the
    dispenser's lag) at the plan's speed, give the report's cross-section within 1 %."""
    import json

    from offline_prog.process.registry import process_model

    data, folder, robot, job = bead_stripe
    write_fanuc_job(data, tmp_path)
    for _, motions in _seam_motions(tmp_path):  # coarser flow steps near rest, no short one
        _assert_no_short_motion(motions)
    s = job.samples
    # The controller holds each motion's AO from the motion's start (a step), replayed
    # on a grid REPLAY_STEPS times finer than the plan's rows (a motion here is two or
    # three rows long).
    t_fine, held = fanuc_flow(job, data, tmp_path, robot, steps=REPLAY_STEPS)
    model = process_model(job.cell.process)
    bead = replayed(job, t_fine, held)[::REPLAY_STEPS]
    process = next(g for g in s.segments if g.kind == "process")
    rows = np.arange(process.start, process.stop)
    plan = job.quality.column[rows]
    top = job.tcp_speed[rows].max()
    check = np.isfinite(plan) & (job.tcp_speed[rows] > 0.05 * top)
    # The ramps from and to rest (longer under the dispenser's jerk cap) are the rest.
    assert check.sum() > 0.8 * len(rows)
    # Within the band (and 5 % around it) the replay agrees within 1 %; on the ramps
    # from and to rest, far outside the band, a motion's one AO value is coarser than
    # the plan's continuous schedule (up to 6 % there): the same rows are outside.
    low, high = model.band[0] * model.unit_scale, model.band[1] * model.unit_scale
    near = check & (plan >= 0.95 * low) & (plan <= 1.05 * high)
    # After the flow's idle edge the bead is the lag's decay from where the AO stopped:
    # the program stops it at the planned sample nearest the plan's position (0.08 mm
    # off here), a sample's shift of that decay; the share below still counts it.
    (stop,) = [e for e in job.io.events if e.signal.value == "analog" and not e.state]
    near &= s.t[rows] < stop.t_s
    assert near.sum() > 0.7 * len(rows)  # a 240 mm stripe: its ramps are a fifth of it
    np.testing.assert_allclose(bead[rows][near], plan[near], rtol=0.01)
    inside_plan = (plan >= low) & (plan <= high)
    inside_replay = (bead[rows] >= low) & (bead[rows] <= high)
    # The report's share counts wherever the gun is open: approach, seam and retract.
    moves = [g for g in s.segments if g.kind != "link"]
    every = np.arange(moves[0].start, moves[-1].stop)
    plan_every = job.quality.column[every]
    replay_every = (bead[every] >= low) & (bead[every] <= high)
    w = np.gradient(s.path_m[every])
    open_every = np.isfinite(plan_every)  # the gun open (the flow is primed before it)
    share = (w * (replay_every & open_every)).sum() / (w * open_every).sum()
    report = json.loads((folder / "report.json").read_text())["quality"]
    assert report["model"] == "bead"
    assert share == pytest.approx(report["share_within_band"], abs=0.01)
    assert np.mean(inside_plan[check] == inside_replay[check]) > 0.99


@pytest.mark.slow
def test_a_flying_stripe_in_fanuc_lays_the_bead_from_its_first_millimetre(tmp_path):
    """Issue 37: the stripe on the M-20iA run flying with the gun on at its start and
    off at its end, laying the bead (lag 0.08 s): the AO values and DB switches the LS
    program holds along the part (its own poses), replayed at the plan's speed, give
    the plan's bead within 1 %, ≥ 99 % of the gun-on length within ±5 %, no row beyond
    ±20 %, no gun-on standstill; the DB switches within ±0.5 mm of the plan's."""
    from process.test_replay import assert_holds_the_bead

    _m20ia(tmp_path)
    cell = tmp_path / "flying.yaml"
    cell.write_text(stripe_flying(on_m20ia((REPO / "cells" / "seal_job_kr16.yaml").read_text())))
    job, folder, data, ls = exported(cell, "fanuc", flying=True)
    t, held = fanuc_flow(job, data, ls, job.robot, steps=REPLAY_STEPS)
    assert_holds_the_bead(job, folder, t, replayed(job, t, held))
    errors = fanuc_switch_errors(data, ls, job.robot)
    assert len(errors) == 2 and np.abs(errors).max() <= SWITCH_TOL_M


def _seam_motions(folder, name="OFFLINE_PROG"):
    """Per seam program: its L motions in order as (statement, X_TP (4, 4): the part in
    the tool's user frame, the lines before and after it), read back from the LS text."""
    seams = []
    for file in sorted(folder.glob(f"{name}_S*.ls")):
        ls = read_ls(file)
        motions = []
        for k, statement in enumerate(ls["mn"]):
            if m := re.match(r"L P\[(\d+)\]", statement):
                around = (ls["mn"][k - 1], ls["mn"][k + 1] if k + 1 < len(ls["mn"]) else "")
                motions.append((statement, pose(ls["pos"][int(m[1])]["xyzwpr"]), around))
        seams.append((ls["mn"], motions))
    return seams


def test_fanuc_merged_motions_hold_the_path_tolerance_and_are_long(fanuc_job, tmp_path):
    """Issue 42: the seam programs read back, the tool's curve on the part while the
    controller moves P linearly (slerp) between their points reconstructed, and the
    plan's continuous path (its dense grid) compared with it: within the chord
    tolerance. No motion is shorter than 0.5 mm: not a flow step, a switch (DB) or a
    FINE end either."""
    from offline_prog.export.density import DEFAULT_CHORD_TOL_M

    data, _, robot, _ = fanuc_job
    write_fanuc_job(data, tmp_path)
    for k, (mn, motions) in enumerate(_seam_motions(tmp_path)):
        stated = re.search(r"deviation <= ([\d.]+)", " ".join(s.lstrip("! ") for s in mn))
        assert stated and float(stated[1]) * 1e-3 <= DEFAULT_CHORD_TOL_M
        # The chain starts where the link before it ends (its last joint target: on a
        # flying seam whose lead took the approach over, the lead-in's start).
        X_BE = robot.forward(data.link_waypoints[k][-1][None])[0]
        X_TP_start = np.linalg.inv(data.job.X_BT) @ X_BE @ data.job.X_EP
        X_TP = np.array([X_TP_start] + [X for _, X, _ in motions])
        curve = []
        for a, b in zip(X_TP, X_TP[1:], strict=False):
            length = np.linalg.norm(b[:3, 3] - a[:3, 3])
            lam = np.linspace(0.0, 1.0, max(2, int(length / 1e-5) + 2))
            R = Slerp([0, 1], Rotation.from_matrix([a[:3, :3], b[:3, :3]]))(lam).as_matrix()
            p = a[:3, 3] + lam[:, None] * (b[:3, 3] - a[:3, 3])
            curve.append(np.einsum("gji,gj->gi", R, -p))  # the tool's point (T's origin) on P
        planned = data.seams[k].X_PT_dense[:, :3, 3]
        gap, _ = cKDTree(np.concatenate(curve)).query(planned)
        assert gap.max() <= DEFAULT_CHORD_TOL_M + 1e-5, gap.max()  # + the curve's spacing
        _assert_no_short_motion(motions)


def _assert_no_short_motion(motions) -> None:
    """No L motion of a seam program (``_seam_motions``) moves the TCP less than 0.5 mm."""
    from offline_prog.export.merge import MIN_MOTION_M

    for (statement, X, _), (_, X_prev, _) in zip(motions[1:], motions, strict=False):
        assert np.linalg.norm(X[:3, 3] - X_prev[:3, 3]) >= MIN_MOTION_M, statement


def test_fanuc_approach_and_retract_run_at_the_planned_speed(fanuc_job, tmp_path):
    """Issue 37: each approach and retract ``L`` motion, read back, is written at the
    plan's mean speed of P's origin between its two points (the planned rows its
    positions are), whole mm/sec in FANUC's [1, 2000]: at most the approach speed,
    slower on its ramps from and to rest; never the cruise speed on a ramp."""
    data, _, robot, _ = fanuc_job
    write_fanuc_job(data, tmp_path)
    rows, segments = data.job, {g.kind: g for g in data.segments}
    p_BP = (rows.X_BE @ rows.X_EP)[:, :3, 3]
    frames = nominal_frames(tmp_path, robot)
    X_BT = frames["UFRAME"][1]
    checked = []
    for kind in ("approach", "retract"):
        g = segments[kind]
        own = np.arange(g.start - 1, g.stop + 1)  # the link's last row, the next's first
        written = []
        for statement, entry in run_statements(tmp_path):
            if not statement.startswith("L "):
                continue
            p = (X_BT @ pose(entry["xyzwpr"]))[:3, 3]
            gap = np.linalg.norm(p_BP[own] - p, axis=1)
            if gap.min() < 2e-6:
                speed = int(re.search(r"(\d+)mm/sec", statement)[1])
                written.append((int(own[np.argmin(gap)]), speed))
        assert len(written) >= 2, kind
        for (a, _), (b, speed) in zip(written, written[1:], strict=False):
            if b <= a:
                continue  # a seam sample that is also a retract row
            planned = np.linalg.norm(p_BP[b] - p_BP[a]) / (rows.t[b] - rows.t[a]) * 1e3
            assert speed == np.clip(round(planned), 1, 2000), (kind, a, b, planned)
            checked.append(speed)
    cruise = round(data.job.off_seam_speed_m_s * 1e3)
    assert max(checked) <= cruise + 1  # the approach speed, where a motion cruises
    assert min(checked) < 0.5 * cruise  # the ramps are written as planned


def test_fanuc_ao_in_counts_is_the_volts_times_the_cells_counts_per_volt(stripe, tmp_path):
    """Issue 42: with ``flow.ao_unit: counts`` every motion holds AO[n] = its value in
    volts × counts_per_volt, a whole number, and the header says so."""
    data, _, robot = stripe
    per_volt = 3276.7  # a ±10 V, 16-bit module's counts
    io = dataclasses.replace(data.process_io, ao_unit="counts", counts_per_volt=per_volt)
    write_fanuc_job(data, tmp_path / "volts")
    write_fanuc_job(dataclasses.replace(data, process_io=io), tmp_path / "counts")
    (volts,) = walk(data, tmp_path / "volts", robot)
    (counts,) = walk(data, tmp_path / "counts", robot)
    assert len(volts["moves"]) == len(counts["moves"])
    for (a, b, v), (_, _, c) in zip(volts["moves"], counts["moves"], strict=True):
        assert c == round(c) and abs(c / per_volt - v) <= 0.0005 + 1 / per_volt, (a, b)
    assert any(abs(c) > 1000 for _, _, c in counts["moves"])
    mn = read_ls(tmp_path / "counts" / "OFFLINE_PROG.ls")["mn"]
    head = " ".join(s.removeprefix("! ") for s in mn if s.startswith("!"))
    assert "in counts: 3276.7 counts per V" in head, head


def _with_frame(text: str, index: int, X: np.ndarray) -> str:
    """The LS text with /POS entry P[index]'s X..R replaced by X (4, 4) [m]."""
    from pydrake.math import RollPitchYaw, RotationMatrix

    w, p, r = np.degrees(RollPitchYaw(RotationMatrix(X[:3, :3])).vector())
    x, y, z = X[:3, 3] * 1e3
    values = (
        f"X = {x:.4f}  mm,\tY = {y:.4f}  mm,\tZ = {z:.4f}  mm,\n"
        f"\tW = {w:.5f} deg,\tP = {p:.5f} deg,\tR = {r:.5f} deg"
    )
    return re.sub(
        rf"(P\[{index}\]\{{.*?CONFIG : '[^']*',\n\t)X = .*? deg,\tP = .*? deg,\tR = \S+ deg",
        lambda m: m[1] + values,
        text,
        flags=re.S,
    )


def _l_flange_poses(folder, robot) -> np.ndarray:
    """(n, 4, 4) the faceplate at each L position: UFRAME · position · UTOOL⁻¹."""
    frames = nominal_frames(folder, robot)
    X_BT, X_EP = frames["UFRAME"][1], frames["UTOOL"][1]
    entries = [e for s, e in run_statements(folder) if s.startswith("L ")]
    return np.array([X_BT @ pose(e["xyzwpr"]) @ np.linalg.inv(X_EP) for e in entries])


def test_fanuc_programs_select_the_cells_frames_and_follow_their_calibration(stripe, tmp_path):
    """The stripe's cell numbers its frames (tool 3, part 2): every program selects
    UFRAME_NUM=3 and UTOOL_NUM=2, its positions name them, no program but
    OFFLINE_PROG_FRAMES sets a frame; editing the frames program (as a calibration
    changes the frames) moves every L position with the frames and leaves the switch
    positions along the part's path where they were."""
    data, plan, robot = stripe
    cell = load_cell(next(plan.parent.glob("*.yaml")))
    uf, ut = cell.tool.controller_frame, cell.part.controller_frame
    assert (uf, ut) == (3, 2)
    files = write_fanuc_job(data, tmp_path)
    assert files[-1].name == "OFFLINE_PROG_FRAMES.ls"
    for file in files[:-1]:
        ls = read_ls(file)
        assert ls["mn"][:2] == [f"UFRAME_NUM={uf}", f"UTOOL_NUM={ut}"]
        assert not any(re.match(r"(UFRAME|UTOOL|PR)\[", s) for s in ls["mn"])
        assert all((e["uf"], e["ut"]) == (uf, ut) for e in ls["pos"].values())
    frames = nominal_frames(tmp_path, robot)
    assert (frames["UFRAME"][0], frames["UTOOL"][0]) == (uf, ut)
    np.testing.assert_allclose(frames["UFRAME"][1], data.job.X_BT, atol=1e-5)
    np.testing.assert_allclose(frames["UTOOL"][1], data.job.X_EP, atol=1e-5)
    before, (seam,) = _l_flange_poses(tmp_path, robot), walk(data, tmp_path, robot)
    rng = np.random.default_rng(0)
    X_WT_new = moved(frames["UFRAME"][1], rng)
    X_WT_new[2, 3] -= robot.params.c1  # into FANUC's world
    X_EP_new = moved(data.job.X_EP, rng)
    file = tmp_path / "OFFLINE_PROG_FRAMES.ls"
    file.write_text(_with_frame(_with_frame(file.read_text(), 1, X_WT_new), 2, X_EP_new))
    edited = nominal_frames(tmp_path, robot)
    np.testing.assert_allclose(edited["UTOOL"][1], X_EP_new, atol=1e-6)
    X_BT_new = edited["UFRAME"][1]
    after = _l_flange_poses(tmp_path, robot)
    X_BT, X_EP = frames["UFRAME"][1], frames["UTOOL"][1]
    expected = X_BT_new @ np.linalg.inv(X_BT) @ before @ X_EP @ np.linalg.inv(X_EP_new)
    np.testing.assert_allclose(after, expected, atol=1e-6)
    assert np.abs(after[:, :3, 3] - before[:, :3, 3]).max() > 1e-3  # it did move
    (moved_seam,) = walk(data, tmp_path, robot)
    for (n, s, p), (n2, s2, p2) in zip(seam["db"], moved_seam["db"], strict=True):
        assert (n, s) == (n2, s2) and p2 == pytest.approx(p, abs=1e-6)
