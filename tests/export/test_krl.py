"""KUKA KRL export read back with an independent parser and independent maths: poses
(scipy's intrinsic "ZYX" Euler angles), joints (Drake forward kinematics of the URDF),
Status/Turn (URDF link geometry), point density, splitting, linting, forced header."""

import dataclasses
import re

import numpy as np
import pytest
from krl_lint import assert_krllint_clean
from scipy.spatial.transform import Rotation

from offline_prog.export.kuka.krl import write_krl
from offline_prog.export.kuka.kuka import kuka_abc_deg, status_turn
from offline_prog.export.program import ProgramData
from offline_prog.robot.model import load_robot
from offline_prog.robot.record import robot_record

POSITION_TOL_M = 0.01e-3  # round trip of every written pose
ANGLE_TOL_DEG = 0.01
JOINT_TOL_DEG = 0.001
# Writing rounds to 1e-4 mm and 1e-5 deg; over lever arms below 1 m that is < 1e-6 m.
ROUNDING_SLACK_M, ROUNDING_SLACK_RAD = 1e-6, np.deg2rad(2e-5)
# The URDF tool0 in KUKA's $FLANGE: the same frame, z out of the flange (kuka_experimental,
# e.g. kuka_kr6_support/urdf/kr6r900_2_macro.xacro: tool0 "corresponds to the $FLANGE
# coordinate system in KUKA KRC controllers").
X_FLANGE_TOOL0 = np.eye(4)
DECL = re.compile(r"^DECL (E6POS|E6AXIS|FRAME) (\w+)=\{(.*)\}$")


@pytest.fixture(scope="module")
def data(planned_folder):
    return ProgramData.load(planned_folder("seal_plate_kr16")[1])


@pytest.fixture(scope="module")
def slowed(tmp_path_factory):
    """The seal demo with its nozzle's turn fixed (no tool.turn_smoothing_mm): the
    wrist's jerk slows the plate at each corner."""
    from offline_prog.plan import plan_cell
    from offline_prog.results.plan_folder import write_outputs

    from conftest import CELLS

    folder = tmp_path_factory.mktemp("seal_fixed_turn")
    text = (CELLS / "seal_plate_kr16.yaml").read_text()
    cell = folder / "seal_fixed_turn.yaml"
    cell.write_text(re.sub(r"\n  turn_smoothing_mm: .*", "", text))
    write_outputs(plan_cell(cell), folder / "plan")
    return ProgramData.load(folder / "plan")


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


def read_program(folder, name):
    """Motions in execution order, following sub-program calls.

    Returns:
        (motions, frames): motions is a list of dicts (kind, point, blended, vel_cp,
        type, fields, module); frames the main program's $BASE / $TOOL / $IPO_MODE values
        (FRAME names resolved to their fields).
    """
    motions, settings = [], {}

    def run(module, vel):
        decls = {}
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


def flange_poses(motions, settings, style, convention):
    """X_BE (n, 4, 4) of every LIN target, composed as the convention says."""
    tool_inv = np.linalg.inv(pose(settings["TOOL"]))
    base = np.eye(4) if settings["BASE"] == "$NULLFRAME" else pose(settings["BASE"])
    out = []
    for motion in motions:
        X = pose(motion["fields"])
        if style == "external_tcp" and convention == "X_PF":
            X = np.linalg.inv(X)  # the point is T in P: $BASE : inv(POS) : inv($TOOL)
        out.append(base @ X @ tool_inv @ X_FLANGE_TOOL0)  # $BASE : POS : inv($TOOL)
    return np.array(out)


def pose_errors(X_a, X_b):
    """Largest position [m] and angle [deg] between two (n, 4, 4) pose stacks."""
    dp = np.linalg.norm(X_a[:, :3, 3] - X_b[:, :3, 3], axis=1).max()
    R = np.swapaxes(X_a[:, :3, :3], 1, 2) @ X_b[:, :3, :3]
    return dp, np.rad2deg(Rotation.from_matrix(R).magnitude().max())


def offset_pose(data, k, approach_m=0.02):
    """X_BE with the tool frame backed off approach_m against the normal (y of F)."""
    X_PF = data.X_PF[k].copy()
    X_PF[:3, 3] -= approach_m * X_PF[:3, 1]
    return data.X_BT @ np.linalg.inv(X_PF) @ np.linalg.inv(data.X_EP)


CASES = [("external_tcp", "X_TP"), ("external_tcp", "X_PF"), ("flange", "X_TP")]


@pytest.mark.parametrize(("style", "convention"), CASES)
def test_round_trip_reproduces_the_flange_poses(data, tmp_path, style, convention):
    result = write_krl(data, tmp_path, style=style, tcp_pose_convention=convention)
    motions, settings = read_program(tmp_path, "offline_prog")
    assert settings["IPO_MODE"] == ("#TCP" if style == "external_tcp" else "#BASE")
    # No approach or retract of the writer's own: PTP to the plan's start, its points.
    assert [m["kind"] for m in motions] == ["PTP"] + ["LIN"] * result.n_points
    assert motions[0]["type"] == "E6AXIS" and motions[0]["point"] == "XSTART"
    lin = [m for m in motions if m["kind"] == "LIN"]
    assert [m["point"] for m in lin] == [f"XP{k + 1}" for k in range(result.n_points)]
    indices = np.asarray(result.indices)
    assert indices[0] == 0 and indices[-1] == len(data.t) - 1 and np.all(np.diff(indices) > 0)
    X_BE = flange_poses(lin, settings, style, convention)
    dp, da = pose_errors(X_BE, data.X_BE[indices])
    assert dp <= POSITION_TOL_M and da <= ANGLE_TOL_DEG
    # Exact stops at the process start and end; blending in between.
    assert [m["blended"] for m in lin] == [False] + [True] * (result.n_points - 2) + [False]
    if style == "external_tcp":  # the other convention would put the flange elsewhere
        other = {"X_TP": "X_PF", "X_PF": "X_TP"}[convention]
        assert pose_errors(flange_poses(lin, settings, style, other), X_BE)[0] > 0.01


def test_ptp_start_is_the_planned_start(data, tmp_path):
    write_krl(data, tmp_path)
    motions, _ = read_program(tmp_path, "offline_prog")
    fields = motions[0]["fields"]
    axes_deg = np.array([fields[f"A{i}"] for i in range(1, 7)])
    np.testing.assert_allclose(axes_deg, np.rad2deg(data.q[0]), atol=1e-5)


def test_ptp_to_an_asked_approach(data, tmp_path, plant):
    write_krl(data, tmp_path, approach_m=0.02)
    motions, _ = read_program(tmp_path, "offline_prog")
    assert motions[0]["point"] == "XAPPROACH" and motions[-1]["point"] == "XRETRACT"
    fields = motions[0]["fields"]
    axes_deg = np.array([fields[f"A{i}"] for i in range(1, 7)])
    assert all(fields[f"E{i}"] == 0.0 for i in range(1, 7))
    # A_i = URDF q_i in degrees: Drake's forward kinematics puts the flange on the approach.
    X_BE = link_poses(plant, np.deg2rad(axes_deg), ["tool0"])["tool0"]
    dp, da = pose_errors(X_BE[None], offset_pose(data, 0)[None])
    assert dp <= POSITION_TOL_M and da <= ANGLE_TOL_DEG
    # ... with the analytic IK solution nearest the plan's start, to 0.001 deg.
    robot = load_robot(data.robot)
    q = robot.inverse(offset_pose(data, 0)[None])[0]
    q = data.q[0] + (q - data.q[0] + np.pi) % (2 * np.pi) - np.pi
    nearest = q[np.nanargmin(np.abs(q - data.q[0]).max(axis=1))]
    assert np.abs(axes_deg - np.rad2deg(nearest)).max() <= JOINT_TOL_DEG
    assert np.abs(axes_deg - np.rad2deg(data.q[0])).max() < 10.0  # same branch as the path


def geometric_status(plant, q_rad):
    """KUKA Status from the URDF's link frames (not from the OPW formulas)."""
    X = link_poses(plant, q_rad, ["link_1", "link_2", "link_3", "link_5"])
    R_B1 = X["link_1"][:3, :3]  # turns with A1: KUKA's A1 coordinate system
    p2, p3, w = (X[n][:3, 3] - X["link_1"][:3, 3] for n in ("link_2", "link_3", "link_5"))
    overhead = (R_B1.T @ w)[0] < 0  # wrist centre (link_5 origin) behind the A1 axis
    elbow_up = np.cross(p3 - p2, w - p2) @ R_B1[:, 1] > 0  # wrist above the A2-A3 line
    return int(overhead) + 2 * int(elbow_up) + 4 * int(q_rad[4] < 0)


def test_status_and_turn_on_the_plan(data, tmp_path, plant):
    result = write_krl(data, tmp_path)
    motions, _ = read_program(tmp_path, "offline_prog")
    lin = [m for m in motions if m["kind"] == "LIN"]
    q = data.q[result.indices]
    turn = np.array([m["fields"]["T"] for m in lin])
    expected = sum((q[:, i] < 0).astype(int) << i for i in range(6))  # bit i: A(i+1) < 0
    np.testing.assert_array_equal(turn, expected)
    status = np.array([m["fields"]["S"] for m in lin])
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


def nozzle_curve(X_BP_a, X_BP_b, p_BT, n=200):
    """(n, 3) tool origin in P while the controller interpolates X_BP from a to b
    (position linear, orientation by slerp, one parameter)."""
    lam = np.linspace(0, 1, n)
    rotvec = Rotation.from_matrix(X_BP_a[:3, :3].T @ X_BP_b[:3, :3]).as_rotvec()
    R = X_BP_a[:3, :3] @ Rotation.from_rotvec(lam[:, None] * rotvec).as_matrix()
    p = X_BP_a[:3, 3] + lam[:, None] * (X_BP_b[:3, 3] - X_BP_a[:3, 3])
    return np.einsum("nji,nj->ni", R, p_BT - p)


def distance_to_polyline(points, line):
    a, d = line[:-1], np.diff(line, axis=0)
    u = np.clip(np.einsum("kgc,gc->kg", points[:, None] - a, d) / (d * d).sum(1), 0, 1)
    return np.linalg.norm(points[:, None] - a - u[..., None] * d, axis=2).min(axis=1)


@pytest.mark.parametrize("style", ["external_tcp", "flange"])
def test_exported_points_follow_the_dense_plan(data, tmp_path, style):
    chord, angle = 0.05e-3, np.deg2rad(0.1)
    result = write_krl(data, tmp_path, style=style, chord_tol_m=chord, angle_tol_rad=angle)
    motions, settings = read_program(tmp_path, "offline_prog")
    X_BE = flange_poses([m for m in motions if m["kind"] == "LIN"], settings, style, "X_TP")
    X_BP = X_BE @ data.X_EP
    X_PT = np.linalg.inv(X_BP) @ data.X_BT  # the exported process frames, from the file
    p_PF, R_PF = data.X_PF[:, :3, 3], data.X_PF[:, :3, :3]
    worst = 0.0
    for k, (i, j) in enumerate(zip(result.indices[:-1], result.indices[1:], strict=True)):
        if style == "external_tcp":  # the controller moves T straight across P
            line = X_PT[k : k + 2, :3, 3]
        else:  # the controller moves P straight in B
            line = nozzle_curve(X_BP[k], X_BP[k + 1], data.X_BT[:3, 3])
        gap = distance_to_polyline(p_PF[i : j + 1], line)
        worst = max(worst, gap.max())
        if style == "external_tcp" and j > i + 1:
            chord_vec = line[1] - line[0]
            lam = np.clip((p_PF[i + 1 : j] - line[0]) @ chord_vec / (chord_vec @ chord_vec), 0, 1)
            rel = Rotation.from_matrix(X_PT[k, :3, :3].T @ X_PT[k + 1, :3, :3]).as_rotvec()
            R_lin = X_PT[k, :3, :3] @ Rotation.from_rotvec(lam[:, None] * rel).as_matrix()
            err = Rotation.from_matrix(np.swapaxes(R_lin, 1, 2) @ R_PF[i + 1 : j]).magnitude()
            assert err.max() <= angle + ROUNDING_SLACK_RAD
    assert worst <= chord + ROUNDING_SLACK_M
    assert result.max_chord_m <= chord and result.max_angle_rad <= angle


def test_vel_cp_follows_the_planned_speed(slowed, tmp_path):
    data = slowed
    result = write_krl(data, tmp_path)
    motions, _ = read_program(tmp_path, "offline_prog")
    lin = [m for m in motions if m["kind"] == "LIN"]
    assert lin[0]["vel_cp"] == pytest.approx(data.process_speed_m_s)
    for k, (i, j) in enumerate(zip(result.indices[:-1], result.indices[1:], strict=True)):
        planned = data.tcp_speed[i : j + 1].max()
        assert planned - 1e-4 - 1e-9 <= lin[k + 1]["vel_cp"] <= max(planned, 1e-3) + 1e-9
    assert min(m["vel_cp"] for m in lin) < data.process_speed_m_s  # the slowed corners


def test_split_programs_are_called_in_order(data, tmp_path):
    whole, parts = tmp_path / "whole", tmp_path / "parts"
    write_krl(data, whole)
    result = write_krl(data, parts, line_limit=25)
    subs = [f.stem for f in result.files if f.suffix == ".src"][1:]
    assert subs == [f"offline_prog_{k + 1}" for k in range(len(subs))] and len(subs) > 2
    main = (parts / "offline_prog.src").read_text().splitlines()
    assert [line[:-3] for line in main if re.match(r"^offline_prog_\d+\( \)$", line)] == subs
    for sub in subs:
        body = (parts / f"{sub}.src").read_text().splitlines()
        body = body[body.index(f"DEF {sub}( )") + 1 : body.index("END")]
        assert 0 < len(body) <= 25 and body[0].startswith("$VEL.CP=")
    split_motions, _ = read_program(parts, "offline_prog")
    whole_motions, _ = read_program(whole, "offline_prog")
    key = ("kind", "point", "blended", "vel_cp", "fields")
    assert [[m[k] for k in key] for m in split_motions] == [
        [m[k] for k in key] for m in whole_motions
    ]


def test_files_are_plain_krl(data, tmp_path):
    result = write_krl(data, tmp_path, style="flange", line_limit=100)
    for file in result.files:
        raw = file.read_bytes()
        raw.decode("ascii")
        assert raw.count(b"\r\n") == raw.count(b"\n")  # CRLF, as KSS writes
        lines = raw.decode().splitlines()
        assert lines[0].startswith("; Generated by offline_prog")
        assert max(len(line) for line in lines) <= 255
        code = [line for line in lines if not line.startswith(";")]
        kind = "DEF" if file.suffix == ".src" else "DEFDAT"
        assert code[0] == (f"{kind} {file.stem}( )" if kind == "DEF" else f"DEFDAT {file.stem}")
        assert code[-1] == ("END" if kind == "DEF" else "ENDDAT")
        for line in code:
            if m := DECL.match(line):
                assert len(m.group(2)) <= 24


def test_krllint_finds_nothing(data, tmp_path):
    write_krl(data, tmp_path / "krl", line_limit=60)
    assert_krllint_clean(tmp_path / "krl", tmp_path)


def test_forced_export_says_so_in_every_file(data, tmp_path):
    failed = dataclasses.replace(data, feasible=False, failure="collision at t = 3.2 s")
    result = write_krl(failed, tmp_path, forced=True, line_limit=100)
    for file in result.files:
        head = [line for line in file.read_text().splitlines() if line.startswith(";")]
        assert any("WARNING: EXPORTED WITH --force FROM A FAILED PLAN" in h for h in head)
        assert any("collision at t = 3.2 s" in h for h in head)


@pytest.mark.parametrize(
    "options",
    [
        {"style": "tcp"},
        {"tcp_pose_convention": "X_PT"},
        {"name": "1abc"},
        {"name": "a_name_that_is_far_too_long"},
        {"line_limit": 1},
        {"chord_tol_m": 0.0},
    ],
)
def test_bad_arguments_are_refused(data, tmp_path, options):
    with pytest.raises(ValueError, match="write_krl"):
        write_krl(data, tmp_path, **options)


def test_a_non_opw_robot_is_refused(data, tmp_path):
    with pytest.raises(ValueError, match="not an OPW arm"):
        ur = robot_record(load_robot("ur10e"))
        write_krl(dataclasses.replace(data, robot="ur10e", robot_record=ur), tmp_path)


@pytest.mark.parametrize("convention", ["X_TP", "X_PF"])
def test_export_command_sets_the_tcp_pose_convention(planned_folder, tmp_path, convention):
    """README: ``offline-prog export --tcp-pose-convention X_PF`` writes the inverse
    points; either reads back to the planned flange poses."""
    from offline_prog.cli import main

    plan_dir = planned_folder("seal_plate_kr16")[1]
    flags = [] if convention == "X_TP" else ["--tcp-pose-convention", convention]
    argv = ["export", str(plan_dir), "--format", "krl", "--out", str(tmp_path), *flags]
    assert main(argv) == 0
    motions, settings = read_program(tmp_path, "offline_prog")
    lin = [m for m in motions if m["kind"] == "LIN"]  # the seam's (no unplanned retract)
    X_BE = flange_poses(lin, settings, "external_tcp", convention)
    data = ProgramData.load(plan_dir)
    dp, da = pose_errors(X_BE[[0, -1]], data.X_BE[[0, -1]])
    assert dp <= POSITION_TOL_M and da <= ANGLE_TOL_DEG
    assert f"({convention})" in (tmp_path / "offline_prog.src").read_text()


@pytest.mark.parametrize("convention", ["X_TP", "X_PF"])
def test_a_job_exports_with_either_tcp_pose_convention(planned_job, tmp_path, convention):
    """A job's KRL (every plan's, a path: cell being a one-seam job) takes
    ``--tcp-pose-convention`` too: the approach ends on each seam's first point and the
    seam's last LIN on its last, read back under the convention the header names."""
    from offline_prog.cli import main
    from offline_prog.export.job_program import JobProgramData

    plan_dir = planned_job("seal_job_kr16")[1]
    argv = ["export", str(plan_dir), "--format", "krl", "--out", str(tmp_path)]
    assert main([*argv, "--tcp-pose-convention", convention]) == 0
    motions, settings = read_program(tmp_path, "offline_prog")
    job = JobProgramData.load(plan_dir)
    lin = [m for m in motions if m["kind"] == "LIN"]
    for seam in job.seams:
        first = lin.pop(0)  # the approach's end: the seam's first point
        while lin[0]["module"] != "offline_prog":  # the seam's LINs in its module
            last = lin.pop(0)
        lin.pop(0)  # the retract
        X_BE = flange_poses([first, last], settings, "external_tcp", convention)
        dp, da = pose_errors(X_BE, seam.X_BE[[0, -1]])
        assert dp <= POSITION_TOL_M and da <= ANGLE_TOL_DEG
    assert not lin
    assert f"({convention})" in (tmp_path / "offline_prog.src").read_text()
