"""robot_model: the robots/ folders, their URDFs and the loader's errors."""

from __future__ import annotations

import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import yaml
from pydrake.geometry import SceneGraph
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

from offline_prog.robot.kinematics_opw import OpwParameters
from offline_prog.robot.kinematics_ur import UrParameters
from offline_prog.robot.model import PARAMS_FILE, ROBOTS_DIR, list_robots, load_robot
from offline_prog.scene.self_collision import read_matrix

ROBOTS = ("ur10e", "kuka_kr16_2", "abb_irb2400")
LINKS = ["base_link"] + [f"link_{i}" for i in range(1, 7)]
JOINTS = [f"joint_{i}" for i in range(1, 7)]
TOL_LIMIT = 1e-12  # [rad], [rad/s]: URDF and robot.yaml state the same numbers


def test_robots_dir_holds_the_three_robots():
    assert Path(__file__).resolve().parents[2] / "offline_prog" / "robots" == ROBOTS_DIR
    assert list_robots() == sorted(ROBOTS)
    package = ET.parse(ROBOTS_DIR / "package.xml").getroot()
    assert package.findtext("name") == "offline_prog_robots"


@pytest.mark.parametrize("name", ROBOTS)
def test_load_robot_in_si_units(name):
    robot = load_robot(name)
    assert robot.name == name
    assert robot.family == ("ur" if name == "ur10e" else "opw")
    assert isinstance(robot.params, UrParameters if name == "ur10e" else OpwParameters)
    assert robot.joint_names == tuple(JOINTS)
    for limit in (robot.q_lower, robot.q_upper, robot.qd_max, robot.qdd_max):
        assert limit.shape == (6,) and limit.dtype == float and not limit.flags.writeable
    assert np.all(robot.q_lower < robot.q_upper)
    assert np.all(robot.qd_max > 0) and np.all(robot.qdd_max > 0)
    limits = yaml.safe_load((ROBOTS_DIR / name / PARAMS_FILE).read_text())["limits"]
    np.testing.assert_allclose(np.degrees(robot.q_lower), np.array(limits["position_deg"])[:, 0])
    np.testing.assert_allclose(np.degrees(robot.q_upper), np.array(limits["position_deg"])[:, 1])
    np.testing.assert_allclose(np.degrees(robot.qd_max), limits["velocity_deg_s"])
    np.testing.assert_allclose(np.degrees(robot.qdd_max), limits["acceleration_deg_s2"])
    assert robot.urdf_path == ROBOTS_DIR / name / f"{name}.urdf"
    assert (ROBOTS_DIR / name / "README.md").is_file()


@pytest.mark.parametrize("name", ROBOTS)
def test_urdf_structure_and_limits_match_record(name):
    robot = load_robot(name)
    root = ET.parse(robot.urdf_path).getroot()
    links = {link.get("name"): link for link in root.findall("link")}
    assert sorted(links) == sorted(LINKS + ["tool0"])
    for link_name in LINKS:
        link = links[link_name]
        assert float(link.find("inertial/mass").get("value")) > 0
        # One vendor collision mesh per link, shipped beside the URDF (tests/robot/test_meshes).
        shapes = link.findall("collision/geometry/mesh")
        assert len(shapes) == 1, link_name
        assert (robot.urdf_path.parent / shapes[0].get("filename")).is_file(), link_name
    joints = {joint.get("name"): joint for joint in root.findall("joint")}
    for i, joint_name in enumerate(robot.joint_names):
        joint = joints[joint_name]
        assert joint.get("type") == "revolute"
        assert joint.find("parent").get("link") == LINKS[i]
        assert joint.find("child").get("link") == LINKS[i + 1]
        limit = joint.find("limit")
        assert float(limit.get("lower")) == pytest.approx(robot.q_lower[i], abs=TOL_LIMIT)
        assert float(limit.get("upper")) == pytest.approx(robot.q_upper[i], abs=TOL_LIMIT)
        assert float(limit.get("velocity")) == pytest.approx(robot.qd_max[i], abs=TOL_LIMIT)
        assert float(limit.get("effort")) > 0
    (flange,) = [j for j in joints.values() if j.find("child").get("link") == "tool0"]
    assert flange.get("type") == "fixed" and flange.find("parent").get("link") == "link_6"


@pytest.mark.parametrize("name", ROBOTS)
def test_urdf_loads_in_drake_by_package_uri_without_self_collision(name):
    robot = load_robot(name)
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    parser = Parser(plant)
    parser.package_map().AddPackageXml(str(ROBOTS_DIR / "package.xml"))
    parser.AddModels(url=f"package://offline_prog_robots/{name}/{name}.urdf")
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("base_link"))
    plant.Finalize()
    assert plant.num_positions() == 6
    starts = [plant.GetJointByName(n).position_start() for n in robot.joint_names]
    np.testing.assert_allclose(
        plant.GetPositionLowerLimits()[starts], robot.q_lower, atol=TOL_LIMIT
    )
    np.testing.assert_allclose(
        plant.GetPositionUpperLimits()[starts], robot.q_upper, atol=TOL_LIMIT
    )
    np.testing.assert_allclose(plant.GetVelocityUpperLimits()[starts], robot.qd_max, atol=TOL_LIMIT)
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()  # q = 0
    query = scene_graph.get_query_output_port().Eval(
        SceneGraph.GetMyContextFromRoot(scene_graph, context)
    )
    # Drake filters parent-child pairs; any other overlap at q = 0 is a modelling error,
    # unless the robot's self-collision matrix marks the pair "always" (vendor meshes that
    # overlap by design, e.g. the IRB 2400's link_4 and link_6).
    inspector = scene_graph.model_inspector()
    always = {frozenset((p.a, p.b)) for p in read_matrix(ROBOTS_DIR / name) if p.kind == "always"}
    for contact in query.ComputePointPairPenetration():
        bodies = frozenset(
            plant.GetBodyFromFrameId(inspector.GetFrameId(g)).name()
            for g in (contact.id_A, contact.id_B)
        )
        assert bodies in always, sorted(bodies)


@pytest.fixture
def robots_copy(tmp_path: Path) -> Path:
    """A writable copy of robots/ to break."""
    shutil.copytree(ROBOTS_DIR, tmp_path / "robots")
    return tmp_path / "robots"


def edit_record(robots_dir: Path, name: str, edit) -> Path:
    """Applies edit(record) to robots_dir/name/robot.yaml; returns the file."""
    path = robots_dir / name / PARAMS_FILE
    record = yaml.safe_load(path.read_text())
    edit(record)
    path.write_text(yaml.safe_dump(record))
    return path


def assert_one_line_error(call, *fragments: str) -> None:
    with pytest.raises(ValueError) as error:
        call()
    message = str(error.value)
    assert "\n" not in message
    for fragment in fragments:
        assert fragment in message, message


def test_missing_folder(robots_copy):
    assert_one_line_error(
        lambda: load_robot("kuka_kr16", robots_copy),
        str(robots_copy / "kuka_kr16"),
        "no robot folder named 'kuka_kr16'",
        "kuka_kr16_2",
    )
    assert_one_line_error(lambda: load_robot("../robots", robots_copy), "no robot folder")


def test_missing_record(robots_copy):
    path = robots_copy / "ur10e" / PARAMS_FILE
    path.unlink()
    assert_one_line_error(lambda: load_robot("ur10e", robots_copy), str(path), "file not found")


def test_invalid_yaml(robots_copy):
    path = robots_copy / "ur10e" / PARAMS_FILE
    path.write_text("family: ur\nlimits: [unclosed\n")
    assert_one_line_error(lambda: load_robot("ur10e", robots_copy), str(path), "not valid YAML")


@pytest.mark.parametrize(
    ("name", "edit", "fragments"),
    [
        ("ur10e", lambda r: r.pop("family"), ["key 'family': missing"]),
        ("ur10e", lambda r: r.update(familly="ur"), ["key 'familly': unknown"]),
        ("ur10e", lambda r: r.update(family="scara"), ["key 'family'", "'scara'"]),
        ("ur10e", lambda r: r["kinematics"].pop("d4"), ["key 'kinematics.d4': missing"]),
        ("ur10e", lambda r: r["kinematics"].update(d4="0.17"), ["key 'kinematics.d4'"]),
        ("ur10e", lambda r: r.update(urdf="ur10.urdf"), ["key 'urdf'", "'ur10.urdf'"]),
        ("ur10e", lambda r: r.update(joint_names=["a"] * 6), ["key 'joint_names'"]),
        (
            "ur10e",  # a comma, a space, a newline break joint_trajectory.csv's header
            lambda r: r.update(joint_names=["j,1", "j 2", "j\n3", "j4", "j5", "j6"]),
            ["key 'joint_names'", "'j,1' is not a name"],
        ),
        ("ur10e", lambda r: r.update(urdf="../kuka_kr16_2/kuka_kr16_2.urdf"), ["key 'urdf'"]),
        (
            "kuka_kr16_2",
            lambda r: r["kinematics"].update(a2_mm=35),
            ["key 'kinematics.a2_mm': unknown"],
        ),
        (
            "kuka_kr16_2",
            lambda r: r["kinematics"].update(sign_corrections=[-1, 1, 1, -1, 1]),
            ["key 'kinematics.sign_corrections'", "1 or -1"],
        ),
        (
            "abb_irb2400",
            lambda r: r["limits"]["position_deg"].__setitem__(1, [110, -100]),
            ["key 'limits.position_deg'", "lower < upper"],
        ),
        (
            "abb_irb2400",
            lambda r: r["limits"]["velocity_deg_s"].pop(),
            ["key 'limits.velocity_deg_s'", "shape [6]"],
        ),
        (
            "abb_irb2400",
            lambda r: r["limits"]["acceleration_deg_s2"].__setitem__(0, 0),
            ["key 'limits.acceleration_deg_s2'", "positive"],
        ),
    ],
)
def test_bad_record_names_file_and_key(robots_copy, name, edit, fragments):
    path = edit_record(robots_copy, name, edit)
    assert_one_line_error(lambda: load_robot(name, robots_copy), str(path), *fragments)


@pytest.mark.parametrize("name", ["my robot", "kr16,2", "x-y"])
def test_a_robot_folder_name_follows_the_seam_name_rule(robots_copy, name):
    """The folder name heads programs and CSV files: checked when the folder loads."""
    shutil.copytree(robots_copy / "ur10e", robots_copy / name)
    assert_one_line_error(lambda: load_robot(name, robots_copy), f"{name!r} is not a name")


def test_urdf_joints_inverts_controller_joints(rng):
    """The ABB J2/J3 coupling both ways: controller axis 3 = q2 + q3, and back."""
    for name in ("abb_irb2400", "kuka_kr16_2"):
        robot = load_robot(name)
        q = rng.uniform(-3.0, 3.0, size=(100, 6))
        np.testing.assert_allclose(robot.urdf_joints(robot.controller_joints(q)), q, atol=1e-12)
    abb = load_robot("abb_irb2400")
    assert abb.urdf_joints(np.array([0.0, 0.3, 0.5, 0, 0, 0]))[2] == pytest.approx(0.2)
