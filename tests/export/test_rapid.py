"""ABB RAPID export read back by an independent parser and compared with the plan:
targets, the controller's stationary-tool composition, joint values, confdata, the
chordal rule, speeds, the failed-plan warning, the options a RAPID module takes and an
external syntax checker."""

import ast
import dataclasses
import functools
import re

import numpy as np
import pytest
from calibrated import moved
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant
from scipy.spatial.transform import Rotation, Slerp

from offline_prog.export.abb.abb import confdata
from offline_prog.export.formats import export
from offline_prog.export.points import PointRule
from offline_prog.export.record import program_record
from offline_prog.robot.model import ROBOTS_DIR, load_robot

POSITION_TOL_MM, ANGLE_TOL_DEG, JOINT_TOL_DEG = 0.01, 0.01, 0.001
ROUNDING_M = 1e-6  # written positions are rounded to 0.5 µm
DECL = re.compile(r"^\s*(?:LOCAL\s+)?(CONST|PERS)\s+(\w+)\s+(\w+)\s*:=\s*(.+);\s*$")
MOVE = re.compile(
    r"^(MoveL|MoveAbsJ)\s+(\w+)(?:\\NoEOffs)?,\s*(\w+),\s*(\w+),\s*(\w+)\\WObj:=(\w+);$"
)


@dataclasses.dataclass
class Program:
    """What the parser read: data by name (type, value), the moves main executes with
    calls expanded (instruction, target, speed, zone, tool, wobj), the module texts."""

    data: dict
    moves: list
    texts: list


def parse_rapid(files) -> Program:
    data, procs, texts = {}, {}, []
    for file in (f for f in files if f.suffix == ".mod"):
        texts.append(file.read_text())
        proc = None
        for line in texts[-1].splitlines():
            stripped = line.strip()
            if stripped.startswith("!") or not stripped:
                continue
            if m := DECL.match(line):
                value = m.group(4).replace("TRUE", "True").replace("FALSE", "False")
                data[m.group(3)] = (m.group(2), ast.literal_eval(value))
            elif m := re.match(r"PROC (\w+)\(\)$", stripped):
                proc = procs.setdefault(m.group(1), [])
            elif stripped == "ENDPROC":
                proc = None
            elif proc is not None:
                proc.append(stripped)

    def run(name):
        for statement in procs[name]:
            if (call := statement.split(";")[0]) in procs:
                yield from run(call)
            elif m := MOVE.match(statement):
                yield m.groups()

    return Program(data, list(run("main")), texts)


def pose_matrix(pose) -> np.ndarray:
    """4×4 [m] from a RAPID pose [[x, y, z] mm, [q1..q4]], by scipy (scalar first)."""
    X = np.eye(4)
    X[:3, :3] = Rotation.from_quat(pose[1], scalar_first=True).as_matrix()
    X[:3, 3] = np.asarray(pose[0]) * 1e-3
    return X


def pose_errors(X_a, X_b):
    """Distance [mm] and angle [deg] between (N, 4, 4) poses."""
    distance = np.linalg.norm(X_a[:, :3, 3] - X_b[:, :3, 3], axis=1) * 1e3
    R_ab = Rotation.from_matrix(np.swapaxes(X_a[:, :3, :3], 1, 2) @ X_b[:, :3, :3])
    return distance, np.rad2deg(R_ab.magnitude())


def urdf_q(axes_deg) -> np.ndarray:
    """URDF joints [rad] from IRB 2400 controller axes [deg]: joint 3 = axis 3 - axis 2."""
    q = np.deg2rad(np.asarray(axes_deg, dtype=float))
    q[..., 2] -= q[..., 1]
    return q


@functools.cache
def drake_plant() -> MultibodyPlant:
    plant = MultibodyPlant(time_step=0.0)
    parser = Parser(plant)
    parser.package_map().AddPackageXml(str(ROBOTS_DIR / "package.xml"))
    parser.AddModels(url="package://offline_prog_robots/abb_irb2400/abb_irb2400.urdf")
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("base_link"))
    plant.Finalize()
    return plant


def drake_frames(q: np.ndarray, pairs) -> list[np.ndarray]:
    """X_AB (4×4) for each (A, B) frame-name pair, by Drake FK of the URDF at q (6,)."""
    plant = drake_plant()
    context, positions = plant.CreateDefaultContext(), np.zeros(plant.num_positions())
    positions[[plant.GetJointByName(f"joint_{i}").position_start() for i in range(1, 7)]] = q
    plant.SetPositions(context, positions)
    return [
        plant.CalcRelativeTransform(
            context, plant.GetFrameByName(a), plant.GetFrameByName(b)
        ).GetAsMatrix4()
        for a, b in pairs
    ]


def drake_cfx(q: np.ndarray) -> int:
    """cfx by the RAPID table from URDF geometry: wrist centre (link_5 origin) behind
    axis 1 (x < 0 in link_1), behind the lower arm (x < 0 in link_2, whose z runs from
    axis 2 to axis 3), axis 5 negative."""
    X_1W, X_2W = drake_frames(q, [("link_1", "link_5"), ("link_2", "link_5")])
    return 4 * (X_1W[0, 3] < 0) + 2 * (X_2W[0, 3] < 0) + (q[4] < 0)


@pytest.fixture(scope="module")
def data(planned_with_moves):
    """The weld demo (a one-seam job) with its approach and retract at 50 mm/s (the
    issue's setting: straight MoveL moves; at 8 mm/s its leads take them over)."""
    return planned_with_moves("weld_seam_irb2400")[1]


@pytest.fixture(scope="module")
def written(data, tmp_path_factory):
    files = export(data, "rapid", tmp_path_factory.mktemp("rapid"))
    return files, parse_rapid(files)


def record_points(data):
    """The seam's points as the program record holds them: (densified data, indices)."""
    (run,) = program_record(data, PointRule("external_tcp", "X_PF")).runs()
    return run.process.data, run.process.indices


def seam_moves(program: Program) -> list:
    """The moves to the seam's points in execution order: the approach's end (its first
    point), then the seam's own."""
    names = [m[1] for m in program.moves]
    first = names.index("pA1")
    return [program.moves[first]] + [
        m for m in program.moves[first + 1 :] if re.fullmatch(r"seam_1_\d+", m[1])
    ]


def test_targets_round_trip_to_the_plan(data, written):
    _, program = written
    moves = seam_moves(program)
    seam, indices = record_points(data)
    assert [m[1] for m in moves] == ["pA1"] + [f"seam_1_{k}" for k in range(1, len(indices))]
    targets = [program.data[m[1]] for m in moves]
    assert all(kind == "robtarget" for kind, _ in targets)
    X_PT = np.array([pose_matrix(value[:2]) for _, value in targets])
    distance, angle = pose_errors(X_PT, seam.X_PT[indices])
    assert distance.max() <= POSITION_TOL_MM and angle.max() <= ANGLE_TOL_DEG
    quaternions = np.array([value[1] for _, value in targets])
    np.testing.assert_allclose(np.linalg.norm(quaternions, axis=1), 1.0, atol=1e-6)
    assert np.all(quaternions[:, 0] >= 0.0)
    assert all(value[3] == [9e9] * 6 for _, value in targets)
    # Stationary tool and robot-held work object on every move.
    tool, wobj = {m[4] for m in program.moves}, {m[5] for m in program.moves}
    assert tool == {"tool_welding_torch"} and wobj == {"wobj_bracket"}
    # Exact stops where the approach ends and at the seam's end, the zone between.
    assert [m[3] for m in moves][0 :: len(moves) - 1] == ["fine", "fine"]
    assert {m[3] for m in moves[1:-1]} == {"zPath"}


def test_controller_composition_gives_the_planned_flange(data, written):
    """X_BE = tframe · robtarget⁻¹ · oframe⁻¹ · uframe⁻¹ (stationary tool, world = B)."""
    _, program = written
    kind, tool = program.data["tool_welding_torch"]
    assert kind == "tooldata" and tool[0] is False and tool[2][0] > 0  # robhold, mass
    kind, wobj = program.data["wobj_bracket"]
    assert kind == "wobjdata" and wobj[:3] == [True, True, ""]
    X_WT, X_EU, X_UO = pose_matrix(tool[1]), pose_matrix(wobj[3]), pose_matrix(wobj[4])
    X_OT = np.array([pose_matrix(program.data[m[1]][1][:2]) for m in seam_moves(program)])
    X_WE = X_WT @ np.linalg.inv(X_OT) @ np.linalg.inv(X_UO) @ np.linalg.inv(X_EU)
    seam, indices = record_points(data)
    distance, angle = pose_errors(X_WE, seam.X_BE[indices])
    assert distance.max() <= POSITION_TOL_MM and angle.max() <= ANGLE_TOL_DEG


def test_joint_targets_are_the_planned_joints(data, written):
    """MoveAbsJ home first (axis 3 = q2 + q3: the J2/J3 linkage), then the links'
    waypoints; Drake's forward kinematics of the last one before the approach is the
    flange where the approach starts."""
    _, program = written
    joint_moves = [m for m in program.moves if m[0] == "MoveAbsJ"]
    assert joint_moves[0][1] == "jHome"
    axes = [program.data[m[1]][1][0] for m in joint_moves]
    assert all(program.data[m[1]][1][1] == [9e9] * 6 for m in joint_moves)
    planned = [data.link_waypoints[0][0]] + [q for w in data.link_waypoints for q in w[1:]]
    np.testing.assert_allclose(urdf_q(axes), planned, atol=np.deg2rad(JOINT_TOL_DEG))
    assert axes[0][2] == pytest.approx(np.rad2deg(planned[0][1] + planned[0][2]), abs=1e-3)
    names = [m[1] for m in program.moves]
    before = program.moves[names.index("pA1") - 1][1]
    (X_BE,) = drake_frames(urdf_q(program.data[before][1][0]), [("base_link", "tool0")])
    approach = next(s for s in data.segments if s.kind == "approach")
    distance, angle = pose_errors(X_BE[None], data.job.X_BE[approach.start][None])
    assert distance.max() <= POSITION_TOL_MM and angle.max() <= ANGLE_TOL_DEG


def test_confdata_quadrants_and_cfx(data, written):
    _, program = written
    conf = np.array([program.data[m[1]][1][2] for m in seam_moves(program)])
    seam, indices = record_points(data)
    axes = np.rad2deg(seam.q[indices][:, [0, 3, 5]])
    assert np.all((90.0 * conf[:, :3] <= axes) & (axes < 90.0 * (conf[:, :3] + 1)))
    assert [drake_cfx(q) for q in seam.q[indices]] == list(conf[:, 3])
    # Seeded property loop over the joint ranges: all eight cfx values occur.
    robot, rng = load_robot("abb_irb2400"), np.random.default_rng(0)
    q = rng.uniform(robot.q_lower, robot.q_upper, size=(400, 6))
    q[:, 2] = rng.uniform(-np.pi, np.pi, size=400)  # reach the elbow-behind branch too
    expected = [drake_cfx(q_i) for q_i in q]
    assert list(confdata(robot, q)[:, 3]) == expected and set(expected) == set(range(8))


def test_chordal_rule_holds_for_the_written_points(data, written):
    _, program = written
    X = np.array([pose_matrix(program.data[m[1]][1][:2]) for m in seam_moves(program)])
    seam, indices = record_points(data)
    chord_tol, angle_tol = 0.05e-3 + ROUNDING_M, np.deg2rad(0.1) + 1e-5
    for k, (a, b) in enumerate(zip(indices[:-1], indices[1:], strict=True)):
        p0, p1 = X[k, :3, 3], X[k + 1, :3, 3]
        dense = seam.X_PT[a : b + 1]
        lam = np.clip((dense[:, :3, 3] - p0) @ (p1 - p0) / np.sum((p1 - p0) ** 2), 0.0, 1.0)
        distance = np.linalg.norm(dense[:, :3, 3] - (p0 + lam[:, None] * (p1 - p0)), axis=1)
        slerp = Slerp([0.0, 1.0], Rotation.from_matrix(X[k : k + 2, :3, :3]))
        angle = (slerp(lam).inv() * Rotation.from_matrix(dense[:, :3, :3])).magnitude()
        assert distance.max() <= chord_tol and angle.max() <= angle_tol


def test_speeds_follow_the_planned_timing(data, written):
    _, program = written
    moves = seam_moves(program)
    seam, indices = record_points(data)
    speeds = np.array([program.data[m[2]][1][0] for m in moves[1:]])  # mm/s
    assert np.all(speeds > 0) and speeds.max() <= seam.process_speed_m_s * 1e3 + 0.05
    p = np.array([program.data[m[1]][1][0] for m in moves])
    duration = np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1) / speeds)
    span = seam.t[indices[-1]] - seam.t[indices[0]]
    assert duration == pytest.approx(span, rel=0.02)


def test_forced_export_of_a_failed_plan_warns_in_the_header(data, tmp_path):
    failure = "joint_5 at its limit at σ = 0.120 m (≥ 120°)"
    rows = dataclasses.replace(data.job, feasible=False, failure=failure, tool="Düse 1")
    files = export(dataclasses.replace(data, job=rows), "rapid", tmp_path, force=True)
    text = files[0].read_text()
    header = text.splitlines()[1:20]
    assert any("WARNING: EXPORTED WITH --force FROM A FAILED PLAN" in line for line in header)
    assert any("sigma = 0.120 m (>= 120 deg)" in line for line in header)
    assert text.isascii() and all(line.startswith("  !") for line in header[:5])
    assert "tool_Duse_1" in parse_rapid(files).data


def test_bad_arguments_are_named(data, tmp_path):
    for kwargs, name in [
        ({"module": "1bad"}, "module"),
        ({"module": "x" * 40}, "module"),
        ({"zone_mm": -1.0}, "zone_mm"),
        ({"line_limit": 5}, "line_limit=5: need a whole number"),
        ({"chord_tol_m": -1.0}, "chord_tol_m"),
    ]:
        with pytest.raises(ValueError, match=name):
            export(data, "rapid", tmp_path, **kwargs)
    # A plan made before plans carried their robot record looks the robot up by name.
    rows = dataclasses.replace(data.job, robot="abb_unknown", robot_record=None)
    with pytest.raises(ValueError, match="no robot folder named 'abb_unknown'"):
        export(dataclasses.replace(data, job=rows), "rapid", tmp_path)


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # rapidchecker's pyparsing calls
@pytest.mark.slow
def test_output_passes_rapidchecker(written):
    rapidchecker = pytest.importorskip(
        "rapidchecker.cli", reason="rapidchecker (pip install rapidchecker) not installed"
    )
    for text in written[1].texts:
        assert [str(e) for e in rapidchecker.check_file(text)] == []
    broken = written[1].texts[0].replace("MoveL seam_1_1, ", "MoveL seam_1_1 ")
    assert rapidchecker.check_file(broken)  # the checker does catch errors


def test_the_program_names_the_controllers_frames_and_holds_no_frame_value(data, written):
    """The motion module uses the PERS tooldata / wobjdata named after the cell's tool
    and part and declares neither; their nominal values are in OfflineProgFrames.mod
    only, which the .pgf does not load."""
    files, program = written
    assert [f.name for f in files] == [
        "OfflineProg.mod",
        "OfflineProg.pgf",
        "OfflineProgFrames.mod",
    ]
    motion, frames = (f.read_text() for f in (files[0], files[2]))
    code = [line for line in motion.splitlines() if not line.strip().startswith("!")]
    assert not [line for line in code if "tooldata" in line or "wobjdata" in line]
    assert "OfflineProgFrames" not in files[1].read_text()
    assert "PERS tooldata tool_welding_torch :=" in frames
    assert "PERS wobjdata wobj_bracket :=" in frames
    assert "! Frames: tool T = PERS tooldata tool_welding_torch" in motion  # the header
    moves = program.moves
    assert {m[4] for m in moves} == {"tool_welding_torch"} and {m[5] for m in moves} == {
        "wobj_bracket"
    }


def test_a_calibration_of_the_pers_data_moves_the_whole_program(data, written, tmp_path):
    """Export → edit tframe and uframe in the frames module (as a calibration does) →
    parse → compose: X_WE' = tframe' · robtarget⁻¹ · uframe'⁻¹ is where the new frames
    put the unchanged tool-on-part pose, X_BT' · X_BT⁻¹ · X_BE · X_EP · X_EP'⁻¹."""
    files, _ = written
    rng, rows = np.random.default_rng(0), data.job
    X_BT, X_EP = (moved(X, rng) for X in (rows.X_BT, rows.X_EP))
    edited = []
    for file in files:
        text = file.read_text()
        if file.name == "OfflineProgFrames.mod":
            text = re.sub(
                r"(tool_welding_torch := \[FALSE,)\[\[[^\]]*\],\[[^\]]*\]\]",
                lambda m: m[1] + rapid_pose(X_BT),
                text,
            )
            text = re.sub(
                r'(wobj_bracket := \[TRUE,TRUE,"",)\[\[[^\]]*\],\[[^\]]*\]\]',
                lambda m: m[1] + rapid_pose(X_EP),
                text,
            )
        edited.append(tmp_path / file.name)
        edited[-1].write_text(text)
    program = parse_rapid(edited)
    X_WT = pose_matrix(program.data["tool_welding_torch"][1][1])
    X_EU = pose_matrix(program.data["wobj_bracket"][1][3])
    np.testing.assert_allclose(X_WT, X_BT, atol=1e-6)
    X_OT = np.array([pose_matrix(program.data[m[1]][1][:2]) for m in seam_moves(program)])
    X_WE = X_WT @ np.linalg.inv(X_OT) @ np.linalg.inv(X_EU)
    seam, indices = record_points(data)
    expected = (
        X_BT @ np.linalg.inv(rows.X_BT) @ seam.X_BE[indices] @ rows.X_EP @ np.linalg.inv(X_EP)
    )
    distance, angle = pose_errors(X_WE, expected)
    assert distance.max() <= POSITION_TOL_MM and angle.max() <= ANGLE_TOL_DEG
    assert pose_errors(X_WE, seam.X_BE[indices])[0].max() > 1.0  # [mm]: it did move


def rapid_pose(X: np.ndarray) -> str:
    """``[[x,y,z],[q1,q2,q3,q4]]`` [mm] of X (4, 4) [m], by scipy (scalar first)."""
    q = Rotation.from_matrix(X[:3, :3]).as_quat(scalar_first=True)
    return f"[[{','.join(f'{v:.4f}' for v in X[:3, 3] * 1e3)}],[{','.join(f'{v:.9f}' for v in q)}]]"
