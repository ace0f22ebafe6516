"""KUKA KRL export read back with an independent parser and independent maths: poses
(scipy's intrinsic "ZYX" Euler angles), joints (Drake forward kinematics of the URDF),
Status/Turn (URDF link geometry), point density against the plan, speeds, linting,
the forced header and the options a KRL program takes."""

import dataclasses
import re

import numpy as np
import pytest
from calibrated import moved
from krl_lint import assert_krllint_clean
from scipy.spatial.transform import Rotation

from offline_prog.export.formats import export
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.kuka.kuka import krl_frame, kuka_abc_deg, status_turn
from offline_prog.export.points import PointRule
from offline_prog.export.record import program_record
from offline_prog.robot.model import load_robot
from offline_prog.robot.record import robot_record

POSITION_TOL_M = 0.01e-3  # round trip of every written pose
ANGLE_TOL_DEG = 0.01
# Writing rounds to 1e-4 mm and 1e-5 deg; over lever arms below 1 m that is < 1e-6 m.
ROUNDING_SLACK_M, ROUNDING_SLACK_RAD = 1e-6, np.deg2rad(2e-5)
# The URDF tool0 in KUKA's $FLANGE: the same frame, z out of the flange (kuka_experimental,
# e.g. kuka_kr6_support/urdf/kr6r900_2_macro.xacro: tool0 "corresponds to the $FLANGE
# coordinate system in KUKA KRC controllers").
X_FLANGE_TOOL0 = np.eye(4)
DECL = re.compile(r"^DECL (E6POS|E6AXIS|FRAME) (\w+)=\{(.*)\}$")


@pytest.fixture(scope="module")
def data(planned_job):
    """The seal demo (a one-seam job with its flow output)."""
    return JobProgramData.load(planned_job("seal_plate_kr16")[1])


@pytest.fixture(scope="module")
def slowed(tmp_path_factory):
    """The seal demo with its nozzle's turn fixed (no tool.turn_smoothing_mm): the
    wrist's jerk slows the plate at each corner."""
    from offline_prog.plan import plan_job
    from offline_prog.results.job_folder import write_job_outputs

    from conftest import CELLS

    folder = tmp_path_factory.mktemp("seal_fixed_turn")
    text = (CELLS / "seal_plate_kr16.yaml").read_text()
    cell = folder / "seal_fixed_turn.yaml"
    cell.write_text(re.sub(r"\n  turn_smoothing_mm: .*", "", text))
    write_job_outputs(plan_job(cell), folder / "plan")
    return JobProgramData.load(folder / "plan")


@pytest.fixture(scope="module")
def plant():
    """The KR 16-2 URDF in Drake, base_link welded to the world."""
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    model = MultibodyPlant(0.0)
    Parser(model).AddModels(str(load_robot("kuka_kr16_2").urdf_path))
    model.WeldFrames(model.world_frame(), model.GetFrameByName("base_link"))
    model.Finalize()
    return model


def link_poses(plant, q_rad, names):
    """{name: (4, 4) pose of the URDF link frame in base_link} at joint vector q."""
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, q_rad)
    base = plant.GetFrameByName("base_link")
    return {n: plant.GetFrameByName(n).CalcPose(context, base).GetAsMatrix4() for n in names}


def pose(fields):
    """(4, 4) [m] from KRL X, Y, Z [mm] and A, B, C [deg]: R = Rz(A) Ry(B) Rx(C), which is
    scipy's intrinsic (upper-case) "ZYX" sequence."""
    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler(
        "ZYX", [fields["A"], fields["B"], fields["C"]], degrees=True
    ).as_matrix()
    X[:3, 3] = np.array([fields["X"], fields["Y"], fields["Z"]]) * 1e-3
    return X


FRAME_DATA = re.compile(r"^((?:BASE|TOOL)_DATA\[\d+\])=\{(.*)\}$")


def nominal_frames(folder, name="offline_prog"):
    """{"BASE_DATA[n]": ("FRAME", fields), ...}: the frames ``<name>_frm.src`` loads
    into the controller (the nominal values, the only file that holds them)."""
    frames = {}
    for line in (folder / f"{name}_frm.src").read_text().splitlines():
        if m := FRAME_DATA.match(line):
            items = (item.split(" ") for item in m.group(2).split(","))
            frames[m.group(1)] = ("FRAME", {k: float(v) for k, v in items})
    return frames


def read_program(folder, name="offline_prog"):
    """Motions in execution order, following the calls of the seams' modules.

    Returns:
        (motions, frames): motions is a list of dicts (kind, point, blended, vel_cp,
        type, fields, module); frames the main program's $BASE / $TOOL / $IPO_MODE values
        (FRAME names resolved to their fields).
    """
    motions, settings = [], {}
    frames = nominal_frames(folder, name)

    def run(module, vel):
        decls = dict(frames)
        for line in (folder / f"{module}.dat").read_text().splitlines():
            if m := DECL.match(line):
                items = (item.split(" ") for item in m.group(3).split(","))
                decls[m.group(2)] = (m.group(1), {k: float(v) for k, v in items})
        for line in (folder / f"{module}.src").read_text().splitlines():
            if m := re.match(r"^\$VEL\.CP=(\S+)$", line):
                vel = float(m.group(1))
            elif m := re.match(r"^\$(BASE|TOOL|IPO_MODE)=(\S+)$", line):
                settings[m.group(1)] = decls.get(m.group(2), (None, m.group(2)))[1]
            elif m := re.match(r"^(PTP|LIN) (\w+)( C_DIS)?$", line):
                kind, point, blended = m.groups()
                motions.append(
                    dict(
                        kind=kind,
                        point=point,
                        blended=bool(blended),
                        vel_cp=vel,
                        type=decls[point][0],
                        fields=decls[point][1],
                        module=module,
                    )
                )
            elif (m := re.match(r"^(\w+)\( \)$", line)) and m.group(1) != "DEF":
                vel = run(m.group(1), vel)
        return vel

    run(name, None)
    return motions, settings


def flange_poses(motions, settings, convention="X_TP"):
    """X_BE (n, 4, 4) of LIN targets, composed as the convention says."""
    tool_inv, base = np.linalg.inv(pose(settings["TOOL"])), pose(settings["BASE"])
    out = []
    for motion in motions:
        X = pose(motion["fields"])
        if convention == "X_PF":
            X = np.linalg.inv(X)  # the point is T in P: $BASE : inv(POS) : inv($TOOL)
        out.append(base @ X @ tool_inv @ X_FLANGE_TOOL0)  # $BASE : POS : inv($TOOL)
    return np.array(out)


def pose_errors(X_a, X_b):
    """Largest position [m] and angle [deg] between two (n, 4, 4) pose stacks."""
    dp = np.linalg.norm(X_a[:, :3, 3] - X_b[:, :3, 3], axis=1).max()
    R = np.swapaxes(X_a[:, :3, :3], 1, 2) @ X_b[:, :3, :3]
    return dp, np.rad2deg(Rotation.from_matrix(R).magnitude().max())


def seam_lins(motions):
    """The seam's LIN targets after its first point (its module's), and the motion that
    reaches its first point: the approach's LIN ``XA1``, or the link's last PTP where
    a flying seam's lead took the straight approach over (no ``XA1`` is written)."""
    first = next(k for k, m in enumerate(motions) if m["module"] != "offline_prog")
    start = motions[first - 1]
    lins = []
    for m in motions[first:]:
        if m["module"] == "offline_prog":
            break
        lins.append(m)
    return start, lins


def first_point_pose(start, settings, plant, convention="X_TP"):
    """X_BE (4, 4) at the seam's first point, from the motion that reaches it: the
    approach LIN's pose, or Drake's forward kinematics of the link's last PTP target."""
    if start["kind"] == "LIN":
        return flange_poses([start], settings, convention)[0]
    q = np.deg2rad([start["fields"][f"A{i}"] for i in range(1, 7)])
    return link_poses(plant, q, ["tool0"])["tool0"]


def seam_flange_poses(motions, settings, plant, convention="X_TP"):
    """X_BE (K, 4, 4) at the seam's points as the program reaches them."""
    start, lins = seam_lins(motions)
    first = first_point_pose(start, settings, plant, convention)
    return np.concatenate([first[None], flange_poses(lins, settings, convention)])


def assert_start_is_the_records(data, start):
    """The seam's first point is reached by XA1 where the record has a straight
    approach, else by the link's last PTP (the lead-in starts where the link ends)."""
    (run,) = program_record(data, None).runs()
    if run.approach is None:
        assert start["kind"] == "PTP" and start["module"] == "offline_prog"
    else:
        assert start["point"] == "XA1" and start["kind"] == "LIN"


def record_points(data, convention="X_TP", **tolerances):
    """The seam's points as the program record holds them: (densified data, indices)."""
    rule = PointRule("external_tcp", convention, **tolerances)
    (run,) = program_record(data, rule, flow_where_set=True).runs()
    return run.process.data, run.process.indices


@pytest.mark.parametrize("convention", ["X_TP", "X_PF"])
def test_round_trip_reproduces_the_flange_poses(data, tmp_path, plant, convention):
    export(data, "krl", tmp_path, tcp_pose_convention=convention)
    motions, settings = read_program(tmp_path)
    assert settings["IPO_MODE"] == "#TCP"
    start, lins = seam_lins(motions)
    assert_start_is_the_records(data, start)
    seam, indices = record_points(data, convention)
    assert [m["point"] for m in lins] == [f"XP{k + 1}" for k in range(1, len(indices))]
    assert indices[0] == 0 and indices[-1] == len(seam.t) - 1 and np.all(np.diff(indices) > 0)
    X_BE = seam_flange_poses(motions, settings, plant, convention)
    dp, da = pose_errors(X_BE, seam.X_BE[indices])
    assert dp <= POSITION_TOL_M and da <= ANGLE_TOL_DEG
    # An exact stop where the seam's first point is reached and at the seam's end;
    # blending in between.
    assert [m["blended"] for m in [start, *lins]] == [False] + [True] * (len(lins) - 1) + [False]
    # The other convention would put the flange elsewhere.
    other = {"X_TP": "X_PF", "X_PF": "X_TP"}[convention]
    assert pose_errors(flange_poses(lins, settings, other), seam.X_BE[indices[1:]])[0] > 0.01


def test_ptp_targets_are_the_planned_joints_and_put_the_flange_there(data, tmp_path, plant):
    """E6AXIS A_i = URDF q_i in degrees: home first, then each link's waypoints; Drake's
    forward kinematics of the last one before the seam is the flange where its approach
    starts (on a flying seam whose lead took the straight move over: the lead-in's
    start)."""
    export(data, "krl", tmp_path)
    motions, _ = read_program(tmp_path)
    ptp = [m for m in motions if m["kind"] == "PTP"]
    axes = np.array([[m["fields"][f"A{i}"] for i in range(1, 7)] for m in ptp])
    planned = [data.link_waypoints[0][0]] + [q for w in data.link_waypoints for q in w[1:]]
    np.testing.assert_allclose(axes, np.rad2deg(planned), atol=1e-5)
    assert all(m["fields"][f"E{i}"] == 0.0 for m in ptp for i in range(1, 7))
    assert ptp[0]["point"] == "XHOME" and motions[-1]["kind"] == "PTP"
    start, _ = seam_lins(motions)
    before = [m for m in motions[: motions.index(start) + 1] if m["kind"] == "PTP"][-1]
    X_BE = link_poses(
        plant, np.deg2rad([before["fields"][f"A{i}"] for i in range(1, 7)]), ["tool0"]
    )
    approach = next(s for s in data.segments if s.kind == "approach")
    dp, da = pose_errors(X_BE["tool0"][None], data.job.X_BE[approach.start][None])
    assert dp <= POSITION_TOL_M and da <= ANGLE_TOL_DEG


def geometric_status(plant, q_rad):
    """KUKA Status from the URDF's link frames (not from the OPW formulas)."""
    X = link_poses(plant, q_rad, ["link_1", "link_2", "link_3", "link_5"])
    R_B1 = X["link_1"][:3, :3]  # turns with A1: KUKA's A1 coordinate system
    p2, p3, w = (X[n][:3, 3] - X["link_1"][:3, 3] for n in ("link_2", "link_3", "link_5"))
    overhead = (R_B1.T @ w)[0] < 0  # wrist centre (link_5 origin) behind the A1 axis
    elbow_up = np.cross(p3 - p2, w - p2) @ R_B1[:, 1] > 0  # wrist above the A2-A3 line
    return int(overhead) + 2 * int(elbow_up) + 4 * int(q_rad[4] < 0)


def test_status_and_turn_on_the_plan(data, tmp_path, plant):
    export(data, "krl", tmp_path)
    motions, _ = read_program(tmp_path)
    start, lins = seam_lins(motions)
    if start["kind"] == "LIN":  # the approach's end: the seam's first point
        lins = [start, *lins]
    seam, indices = record_points(data)
    q = seam.q[indices[-len(lins) :]]
    turn = np.array([m["fields"]["T"] for m in lins])
    expected = sum((q[:, i] < 0).astype(int) << i for i in range(6))  # bit i: A(i+1) < 0
    np.testing.assert_array_equal(turn, expected)
    status = np.array([m["fields"]["S"] for m in lins])
    np.testing.assert_array_equal(status, [geometric_status(plant, row) for row in q])


def test_status_matches_the_urdf_geometry(plant):
    rng = np.random.default_rng(0)
    robot = load_robot("kuka_kr16_2")
    q = rng.uniform(robot.q_lower, robot.q_upper, size=(300, 6))
    status, turn = status_turn(robot.params, q)
    np.testing.assert_array_equal(status, [geometric_status(plant, row) for row in q])
    np.testing.assert_array_equal(turn, (q < 0) @ (1 << np.arange(6)))
    assert set(status) >= {0, 1, 2, 3, 4, 5, 6, 7}  # every bit pattern was exercised
    # KUKA's home {A1 0, A2 -90, A3 90, A4 0, A5 0, A6 0}: Status 2 ('B010'), Turn 2.
    home = np.deg2rad([[0.0, -90.0, 90.0, 0.0, 0.0, 0.0]])
    assert [int(v[0]) for v in status_turn(robot.params, home)] == [2, 2]


def test_kuka_home_pose_of_the_flange(plant):
    """At KUKA's HOME {A1 0, A2 -90, A3 90, A4 0, A5 0, A6 0} with $TOOL = $BASE =
    $NULLFRAME the pendant shows the flange at A 0, B 90, C 0 (z forward, x down)."""
    X_BE = link_poses(plant, np.deg2rad([0.0, -90.0, 90.0, 0.0, 0.0, 0.0]), ["tool0"])["tool0"]
    X_BK = X_BE @ np.linalg.inv(X_FLANGE_TOOL0)
    np.testing.assert_allclose(kuka_abc_deg(X_BK[None, :3, :3])[0], [0.0, 90.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(X_BK[:3, 3], [0.26 + 0.67 + 0.158, 0.0, 0.675 + 0.68 - 0.035])


def test_euler_angles_round_trip():
    rng = np.random.default_rng(0)
    R = Rotation.random(500, random_state=rng).as_matrix()
    locked = Rotation.from_euler("ZYX", [[30, 90, 0], [-120, -90, 0], [10, 90, 40]], degrees=True)
    R = np.concatenate([R, locked.as_matrix()])
    abc = kuka_abc_deg(R)
    back = Rotation.from_euler("ZYX", abc, degrees=True).as_matrix()
    assert np.abs(back - R).max() < 1e-9
    assert np.all(np.abs(abc[:, 1]) <= 90.0) and np.all(np.abs(abc) <= 180.0)


def distance_to_polyline(points, line):
    a, d = line[:-1], np.diff(line, axis=0)
    u = np.clip(np.einsum("kgc,gc->kg", points[:, None] - a, d) / (d * d).sum(1), 0, 1)
    return np.linalg.norm(points[:, None] - a - u[..., None] * d, axis=2).min(axis=1)


@pytest.mark.parametrize("chord_mm", [0.05, 0.2])
def test_exported_points_follow_the_dense_plan(data, tmp_path, plant, chord_mm):
    """The controller moves the fixed TCP in straight lines across the part between the
    written points: every densified sample of the seam lies within the chord tolerance
    of that line, orientation by slerp within the angle tolerance."""
    chord, angle = chord_mm * 1e-3, np.deg2rad(0.1)
    export(data, "krl", tmp_path, chord_tol_m=chord, angle_tol_rad=angle)
    motions, settings = read_program(tmp_path)
    X_BE = seam_flange_poses(motions, settings, plant)
    X_PT = np.linalg.inv(data.job.X_BT) @ X_BE @ data.job.X_EP
    X_PT = np.linalg.inv(X_PT)  # the written tool frames in P, from the file
    seam, indices = record_points(data, chord_tol_m=chord, angle_tol_rad=angle)
    p, R = seam.X_PT[:, :3, 3], seam.X_PT[:, :3, :3]
    worst = 0.0
    for k, (i, j) in enumerate(zip(indices[:-1], indices[1:], strict=True)):
        line = X_PT[k : k + 2, :3, 3]
        worst = max(worst, distance_to_polyline(p[i : j + 1], line).max())
        if j > i + 1:
            chord_vec = line[1] - line[0]
            lam = np.clip((p[i + 1 : j] - line[0]) @ chord_vec / (chord_vec @ chord_vec), 0, 1)
            rel = Rotation.from_matrix(X_PT[k, :3, :3].T @ X_PT[k + 1, :3, :3]).as_rotvec()
            R_lin = X_PT[k, :3, :3] @ Rotation.from_rotvec(lam[:, None] * rel).as_matrix()
            err = Rotation.from_matrix(np.swapaxes(R_lin, 1, 2) @ R[i + 1 : j]).magnitude()
            assert err.max() <= angle + ROUNDING_SLACK_RAD
    assert worst <= chord + ROUNDING_SLACK_M
    if chord_mm > 0.05:  # a larger tolerance: fewer points
        assert len(indices) < len(record_points(data)[1])


def test_vel_cp_follows_the_planned_speed(slowed, tmp_path):
    export(slowed, "krl", tmp_path)
    motions, _ = read_program(tmp_path)
    start, lins = seam_lins(motions)
    assert_start_is_the_records(slowed, start)
    seam, indices = record_points(slowed)
    speed = slowed.seams[0].process_speed_m_s
    if start["kind"] == "LIN":
        assert start["vel_cp"] == pytest.approx(speed, abs=1e-4)  # the approach
    for k, (i, j) in enumerate(zip(indices[:-1], indices[1:], strict=True)):
        planned = seam.tcp_speed[i : j + 1].max()
        assert planned - 1e-4 - 1e-9 <= lins[k]["vel_cp"] <= max(planned, 1e-3) + 1e-9
    assert min(m["vel_cp"] for m in lins) < speed  # the slowed corners


def test_files_are_plain_krl(data, tmp_path):
    files = export(data, "krl", tmp_path)
    assert [f.name for f in files] == [
        "offline_prog.src",
        "offline_prog.dat",
        "offline_prog_1.src",
        "offline_prog_1.dat",
        "offline_prog_frm.src",
        "offline_prog_frm.dat",
    ]
    for file in files:
        raw = file.read_bytes()
        raw.decode("ascii")
        assert raw.count(b"\r\n") == raw.count(b"\n")  # CRLF, as KSS writes
        lines = raw.decode().splitlines()
        assert lines[0].startswith("; Generated by offline_prog")
        assert max(len(line) for line in lines) <= 255
        code = [line for line in lines if not line.startswith(";")]
        kind = "DEF" if file.suffix == ".src" else "DEFDAT"
        head = f"{kind} {file.stem}( )" if kind == "DEF" else f"DEFDAT {file.stem}"
        assert code[0].split(" PUBLIC")[0] == head
        assert code[-1] == ("END" if kind == "DEF" else "ENDDAT")
        for line in code:
            if m := DECL.match(line):
                assert len(m.group(2)) <= 24


def test_krllint_finds_nothing(data, tmp_path):
    export(data, "krl", tmp_path / "krl")
    assert_krllint_clean(tmp_path / "krl", tmp_path)


def test_forced_export_says_so_in_every_file(data, tmp_path):
    rows = dataclasses.replace(data.job, feasible=False, failure="collision at t = 3.2 s")
    failed = dataclasses.replace(data, job=rows)
    for file in export(failed, "krl", tmp_path, force=True):
        head = [line for line in file.read_text().splitlines() if line.startswith(";")]
        assert any("WARNING: EXPORTED WITH --force FROM A FAILED PLAN" in h for h in head)
        assert any("collision at t = 3.2 s" in h for h in head)


@pytest.mark.parametrize(
    ("options", "words"),
    [
        ({"style": "flange"}, "no option style"),
        ({"line_limit": 5}, "line_limit=5: need a whole number"),
        ({"tcp_pose_convention": "X_PT"}, "tcp_pose_convention"),
        ({"name": "1abc"}, "name="),
        ({"name": "a_name_that_is_far_too_long"}, "name="),
        ({"chord_tol_m": 0.0}, "chord_tol_m > 0"),
    ],
)
def test_bad_arguments_are_refused(data, tmp_path, options, words):
    with pytest.raises(ValueError, match=words):
        export(data, "krl", tmp_path / "out", **options)
    assert not (tmp_path / "out").exists()


def test_a_non_opw_robot_is_refused(data, tmp_path):
    ur = robot_record(load_robot("ur10e"))
    rows = dataclasses.replace(data.job, robot="ur10e", robot_record=ur)
    with pytest.raises(ValueError, match="not an OPW arm"):
        export(dataclasses.replace(data, job=rows), "krl", tmp_path)


@pytest.mark.parametrize("convention", ["X_TP", "X_PF"])
def test_a_job_exports_with_either_tcp_pose_convention(planned_job, tmp_path, plant, convention):
    """``offline-prog export --tcp-pose-convention``: each seam's first point is reached
    (by its approach's LIN, or the link's last PTP where a flying seam's lead took the
    approach over) and the seam's last LIN ends on its last, read back under the
    convention the header names; a retract LIN only where the record has one."""
    from offline_prog.cli import main

    plan_dir = planned_job("seal_job_kr16")[1]
    argv = ["export", str(plan_dir), "--format", "krl", "--out", str(tmp_path)]
    assert main([*argv, "--tcp-pose-convention", convention]) == 0
    motions, settings = read_program(tmp_path)
    job = JobProgramData.load(plan_dir)
    runs = program_record(job, None).runs()
    assert len(runs) == len(job.seams)
    for run, seam in zip(runs, job.seams, strict=True):
        first = next(k for k, m in enumerate(motions) if m["module"] != "offline_prog")
        start = motions[first - 1]
        assert start["kind"] == ("PTP" if run.approach is None else "LIN")
        motions = motions[first:]
        module = motions[0]["module"]
        while motions[0]["module"] != "offline_prog":  # the seam's LINs in its module
            last = motions.pop(0)
        assert last["module"] == module
        if run.retract is not None:
            retract = motions.pop(0)
            assert retract["kind"] == "LIN" and retract["point"] == f"XR{run.number}"
        assert motions[0]["kind"] == "PTP"  # the next link (or home's return)
        X_BE = np.array(
            [
                first_point_pose(start, settings, plant, convention),
                flange_poses([last], settings, convention)[0],
            ]
        )
        dp, da = pose_errors(X_BE, seam.X_BE[[0, -1]])
        assert dp <= POSITION_TOL_M and da <= ANGLE_TOL_DEG
    assert all(m["kind"] == "PTP" for m in motions)
    assert f"({convention})" in (tmp_path / "offline_prog.src").read_text()


def test_programs_run_the_controllers_numbered_frames(data, tmp_path):
    """The cell gives no numbers: BASE_DATA[1] and TOOL_DATA[1], and the header says
    so; the nominal values are in offline_prog_frm.src only."""
    files = export(data, "krl", tmp_path)
    main = (tmp_path / "offline_prog.src").read_text()
    assert {"$BASE=BASE_DATA[1]", "$TOOL=TOOL_DATA[1]"} <= set(main.splitlines())
    assert "part.controller_frame not given in the cell: frame 1 by default" in main
    frames = nominal_frames(tmp_path)
    assert sorted(frames) == ["BASE_DATA[1]", "TOOL_DATA[1]"]
    rows = data.job
    np.testing.assert_allclose(pose(frames["BASE_DATA[1]"][1]), rows.X_BT, atol=1e-6)
    np.testing.assert_allclose(pose(frames["TOOL_DATA[1]"][1]), rows.X_EP, atol=1e-6)
    frm = (tmp_path / "offline_prog_frm.src").read_text()
    assert "BASE_TYPE[1]=#TCP" in frm and "TOOL_TYPE[1]=#BASE" in frm
    # No frame value in any motion program: no FRAME, no *_DATA assignment.
    for file in files:
        if not file.stem.endswith("_frm"):
            text = file.read_text()
            assert "FRAME" not in text and not re.search(r"(BASE|TOOL)_DATA\[\d+\]=\{", text)


def test_a_calibration_of_the_frames_moves_the_whole_program(data, tmp_path):
    """Export → edit the nominal frames (as a calibration changes BASE_DATA and
    TOOL_DATA) → parse → reconstruct: every LIN target is where the new frames put
    the unchanged tool-on-part pose, X_BE' = X_BT' · X_BT⁻¹ · X_BE · X_EP · X_EP'⁻¹."""
    export(data, "krl", tmp_path)
    seam, indices = record_points(data)
    rng, rows = np.random.default_rng(0), data.job
    X_BT, X_EP = moved(rows.X_BT, rng), moved(rows.X_EP, rng)
    frm = tmp_path / "offline_prog_frm.src"
    text = re.sub(
        r"BASE_DATA\[1\]=\{[^}]*\}", f"BASE_DATA[1]={{{krl_frame(X_BT)}}}", frm.read_text()
    )
    text = re.sub(r"TOOL_DATA\[1\]=\{[^}]*\}", f"TOOL_DATA[1]={{{krl_frame(X_EP)}}}", text)
    frm.write_text(text)
    motions, settings = read_program(tmp_path)
    start, lins = seam_lins(motions)
    if start["kind"] == "LIN":  # the approach's end moves too (a PTP target does not)
        lins = [start, *lins]
    X_BE = flange_poses(lins, settings)
    indices = indices[-len(lins) :]
    expected = (
        X_BT @ np.linalg.inv(rows.X_BT) @ seam.X_BE[indices] @ rows.X_EP @ np.linalg.inv(X_EP)
    )
    dp, da = pose_errors(X_BE, expected)
    assert dp <= POSITION_TOL_M and da <= ANGLE_TOL_DEG
    assert pose_errors(X_BE, seam.X_BE[indices])[0] > 1e-3  # the program did move
