"""ABB RAPID export read back by an independent parser and compared with the plan:
targets, the controller's stationary-tool composition, joint values, confdata, the
chordal rule, splitting, the failed-plan warning and an external syntax checker."""

import ast
import dataclasses
import functools
import re

import numpy as np
import pytest
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant
from scipy.spatial.transform import Rotation, Slerp

from offline_prog.export.abb.rapid import confdata, write_rapid
from offline_prog.export.program import ProgramData
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
            if (call := statement.rstrip(";")) in procs:
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
def data(planned_folder):
    return ProgramData.load(planned_folder("weld_seam_irb2400")[1])


@pytest.fixture(scope="module")
def written(data, tmp_path_factory):
    """With the legacy approach (``approach_m``): every process point is a MoveL; the
    points and speeds do not depend on it (the default: test_start_joint_target...)."""
    result = write_rapid(data, tmp_path_factory.mktemp("rapid"), approach_m=0.02)
    return result, parse_rapid(result.files)


def process_moves(program: Program) -> list:
    """The MoveL to each process point p0000.. in execution order."""
    return [m for m in program.moves if m[0] == "MoveL" and re.fullmatch(r"p\d+", m[1])]


def test_targets_round_trip_to_the_plan(data, written):
    result, program = written
    moves = process_moves(program)
    assert [m[1] for m in moves] == [f"p{i:04d}" for i in range(result.n_points)]
    targets = [program.data[m[1]] for m in moves]
    assert all(kind == "robtarget" for kind, _ in targets)
    X_PT = np.array([pose_matrix(value[:2]) for _, value in targets])
    distance, angle = pose_errors(X_PT, data.X_PF[result.indices])
    assert distance.max() <= POSITION_TOL_MM and angle.max() <= ANGLE_TOL_DEG
    quaternions = np.array([value[1] for _, value in targets])
    np.testing.assert_allclose(np.linalg.norm(quaternions, axis=1), 1.0, atol=1e-6)
    assert np.all(quaternions[:, 0] >= 0.0)
    assert all(value[3] == [9e9] * 6 for _, value in targets)
    # Stationary tool and robot-held work object on every move.
    tool, wobj = {m[4] for m in program.moves}, {m[5] for m in program.moves}
    assert tool == {"tool_welding_torch"} and wobj == {"wobj_bracket"}
    assert [m[3] for m in moves][0 :: len(moves) - 1] == ["fine", "fine"]
    assert {m[3] for m in moves[1:-1]} == {"zPath"}


def test_controller_composition_gives_the_planned_flange(data, written):
    """X_BE = tframe · robtarget⁻¹ · oframe⁻¹ · uframe⁻¹ (stationary tool, world = B)."""
    result, program = written
    kind, tool = program.data["tool_welding_torch"]
    assert kind == "tooldata" and tool[0] is False and tool[2][0] > 0  # robhold, mass
    kind, wobj = program.data["wobj_bracket"]
    assert kind == "wobjdata" and wobj[:3] == [True, True, ""]
    X_WT, X_EU, X_UO = pose_matrix(tool[1]), pose_matrix(wobj[3]), pose_matrix(wobj[4])
    X_OT = np.array([pose_matrix(program.data[m[1]][1][:2]) for m in process_moves(program)])
    X_WE = X_WT @ np.linalg.inv(X_OT) @ np.linalg.inv(X_UO) @ np.linalg.inv(X_EU)
    distance, angle = pose_errors(X_WE, data.X_BE[result.indices])
    assert distance.max() <= POSITION_TOL_MM and angle.max() <= ANGLE_TOL_DEG


def test_start_joint_target_is_the_planned_start(data, tmp_path):
    """By default no approach or retract of the writer's own: MoveAbsJ to the plan's
    first joints, the process points, and nothing after the last one."""
    program = parse_rapid(write_rapid(data, tmp_path).files)
    assert program.moves[-1][1] == f"p{len(process_moves(program)):04d}"
    assert program.moves[0][:2] == ("MoveAbsJ", "jStart")
    kind, (axes, extax) = program.data["jStart"]
    assert kind == "jointtarget" and extax == [9e9] * 6
    np.testing.assert_allclose(np.rad2deg(urdf_q(axes)), np.rad2deg(data.q[0]), atol=JOINT_TOL_DEG)
    assert axes[2] == pytest.approx(np.rad2deg(data.q[0, 1] + data.q[0, 2]), abs=JOINT_TOL_DEG)


def test_approach_and_retract_back_off_along_the_tool_axis(data, tmp_path):
    """Only when asked (approach_m): by default the program moves only as planned."""
    program = parse_rapid(write_rapid(data, tmp_path, approach_m=0.02).files)
    names = [m[1] for m in program.moves]
    assert names[:2] == ["jApproach", "p0000"] and names[-1] == "pRetract"
    X_EP_inv, approach_m = np.linalg.inv(data.X_EP), 0.02
    # Approach: Drake FK of the jointtarget = flange with the tool 20 mm off the surface.
    q_app = urdf_q(program.data["jApproach"][1][0])
    X_PT = data.X_PF[0].copy()
    X_PT[:3, 3] -= approach_m * X_PT[:3, 1]
    (X_BE,) = drake_frames(q_app, [("base_link", "tool0")])
    distance, angle = pose_errors(X_BE[None], (data.X_BT @ np.linalg.inv(X_PT) @ X_EP_inv)[None])
    assert distance.max() <= POSITION_TOL_MM and angle.max() <= ANGLE_TOL_DEG
    assert np.abs(q_app - data.q[0]).max() < np.deg2rad(10.0)  # same branch as the start
    # Retract: a robtarget 20 mm off the last process point, along -y of F.
    p_ret = np.asarray(program.data["pRetract"][1][0]) * 1e-3
    expected = data.X_PF[-1, :3, 3] - approach_m * data.X_PF[-1, :3, 1]
    assert np.linalg.norm(p_ret - expected) * 1e3 <= POSITION_TOL_MM


def test_confdata_quadrants_and_cfx(data, written):
    result, program = written
    conf = np.array([program.data[m[1]][1][2] for m in process_moves(program)])
    axes = np.rad2deg(data.q[result.indices][:, [0, 3, 5]])
    assert np.all((90.0 * conf[:, :3] <= axes) & (axes < 90.0 * (conf[:, :3] + 1)))
    assert [drake_cfx(q) for q in data.q[result.indices]] == list(conf[:, 3])
    # Seeded property loop over the joint ranges: all eight cfx values occur.
    robot, rng = load_robot("abb_irb2400"), np.random.default_rng(0)
    q = rng.uniform(robot.q_lower, robot.q_upper, size=(400, 6))
    q[:, 2] = rng.uniform(-np.pi, np.pi, size=400)  # reach the elbow-behind branch too
    expected = [drake_cfx(q_i) for q_i in q]
    assert list(confdata(robot, q)[:, 3]) == expected and set(expected) == set(range(8))


def test_chordal_rule_holds_for_the_written_points(data, written):
    result, program = written
    X = np.array([pose_matrix(program.data[m[1]][1][:2]) for m in process_moves(program)])
    chord_tol, angle_tol = 0.05e-3 + ROUNDING_M, np.deg2rad(0.1) + 1e-5
    for k, (a, b) in enumerate(zip(result.indices[:-1], result.indices[1:], strict=True)):
        p0, p1 = X[k, :3, 3], X[k + 1, :3, 3]
        dense = data.X_PF[a : b + 1]
        lam = np.clip((dense[:, :3, 3] - p0) @ (p1 - p0) / np.sum((p1 - p0) ** 2), 0.0, 1.0)
        distance = np.linalg.norm(dense[:, :3, 3] - (p0 + lam[:, None] * (p1 - p0)), axis=1)
        slerp = Slerp([0.0, 1.0], Rotation.from_matrix(X[k : k + 2, :3, :3]))
        angle = (slerp(lam).inv() * Rotation.from_matrix(dense[:, :3, :3])).magnitude()
        assert distance.max() <= chord_tol and angle.max() <= angle_tol


def test_speeds_follow_the_planned_timing(data, written):
    result, program = written
    moves = process_moves(program)
    speeds = np.array([program.data[m[2]][1][0] for m in moves[1:]])  # mm/s
    assert np.all(speeds > 0) and speeds.max() <= data.process_speed_m_s * 1e3 + 0.05
    p = np.array([program.data[m[1]][1][0] for m in moves])
    duration = np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1) / speeds)
    span = data.t[result.indices[-1]] - data.t[result.indices[0]]
    assert duration == pytest.approx(span, rel=0.02)


def test_split_at_a_small_line_limit_keeps_every_point_in_order(data, tmp_path, written):
    options = dict(chord_tol_m=0.01e-3, angle_tol_rad=np.deg2rad(0.02))
    whole = parse_rapid(write_rapid(data, tmp_path / "whole", **options).files)
    result = write_rapid(data, tmp_path / "split", line_limit=60, **options)
    modules = [f for f in result.files if f.suffix == ".mod"]
    assert len(modules) >= 4 and all(f.read_text().count("\n") <= 60 for f in modules)
    pgf = result.files[-1].read_text()
    assert re.findall(r"<Module>(.+?)</Module>", pgf) == [f.name for f in modules]
    split = parse_rapid(result.files)
    # MoveAbsJ to the first point (no approach of the writer's own), MoveL to the rest.
    assert split.moves == whole.moves and len(process_moves(split)) == result.n_points - 1
    for m in process_moves(split):
        assert split.data[m[1]] == whole.data[m[1]]
    with pytest.raises(ValueError, match="line_limit"):
        write_rapid(data, tmp_path / "tiny", line_limit=8, **options)


def test_forced_export_of_a_failed_plan_warns_in_the_header(data, tmp_path):
    failure = "joint_5 at its limit at σ = 0.120 m (≥ 120°)"
    failed = dataclasses.replace(data, feasible=False, failure=failure, tool="Düse 1")
    result = write_rapid(failed, tmp_path, forced=True)
    text = result.files[0].read_text()
    header = text.splitlines()[1:20]
    assert any("WARNING: EXPORTED WITH --force FROM A FAILED PLAN" in line for line in header)
    assert any("sigma = 0.120 m (>= 120 deg)" in line for line in header)
    assert text.isascii() and all(line.startswith("  !") for line in header[:5])
    assert "tool_Duse_1" in parse_rapid(result.files).data


def test_unreachable_approach_starts_at_the_first_point(data, tmp_path):
    result = write_rapid(data, tmp_path, approach_m=3.0)  # 3 m off the part: out of reach
    program = parse_rapid(result.files)
    assert [m[1] for m in program.moves[:2]] == ["jStart", "p0001"]
    assert "pRetract" not in program.data and "OUT OF REACH" in program.texts[0]


def test_bad_arguments_are_named(data, tmp_path):
    for kwargs, name in [
        ({"module": "1bad"}, "module"),
        ({"module": "x" * 40}, "module"),
        ({"zone_mm": -1.0}, "zone_mm"),
        ({"line_limit": 8}, "line_limit"),
    ]:
        with pytest.raises(ValueError, match=name):
            write_rapid(data, tmp_path, **kwargs)
    # A plan made before plans carried their robot record looks the robot up by name.
    old_plan = dataclasses.replace(data, robot="abb_unknown", robot_record=None)
    with pytest.raises(ValueError, match="no robot folder named 'abb_unknown'"):
        write_rapid(old_plan, tmp_path)


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # rapidchecker's pyparsing calls
@pytest.mark.slow
def test_output_passes_rapidchecker(written, tmp_path, data):
    rapidchecker = pytest.importorskip(
        "rapidchecker.cli", reason="rapidchecker (pip install rapidchecker) not installed"
    )
    split = write_rapid(data, tmp_path, line_limit=40)
    for text in written[1].texts + parse_rapid(split.files).texts:
        assert [str(e) for e in rapidchecker.check_file(text)] == []
    broken = written[1].texts[0].replace("MoveL p0001, ", "MoveL p0001 ")
    assert rapidchecker.check_file(broken)  # the checker does catch errors
