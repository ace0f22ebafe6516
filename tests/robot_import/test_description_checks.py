"""Ordinary and mistaken URDFs (issue 36), each from the shared M-20iA expanded once and
edited: what crashed or hung is a robot folder or one line naming the file and key,
exit 2, and a description in the wrong units or with names that would break
joint_trajectory.csv is refused before anything is written."""

import re
import shutil
import signal
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from test_import_fanuc import FANUC, pytestmark  # noqa: F401  (skip without ../shared)

from offline_prog.cli import main
from offline_prog.robot.model import load_robot
from offline_prog.robot_import.chain import chain_forward, parse_chain
from offline_prog.robot_import.sources import packages_for
from offline_prog.robot_import.xacro_sandbox import description_text

YELLOW = '<material name=""><color rgba="0.96 0.76 0.13 1.0"/></material>'


@pytest.fixture(scope="module")
def m20ia(tmp_path_factory) -> tuple[Path, str]:
    """(a writable copy of the FANUC packages, the M-20iA's URDF text)."""
    folder = tmp_path_factory.mktemp("pkgs") / "fanuc"
    shutil.copytree(FANUC, folder)
    top = folder / "fanuc_m20ia_support/urdf/m20ia.xacro"
    return folder, description_text(top, packages_for(top, [folder]))


def _import(capsys, packages: Path, text: str, out: Path, name: str, *flags) -> tuple:
    """Exit code and stderr lines of `robots import` of ``text`` placed in the package."""
    file = packages / "fanuc_m20ia_support" / "urdf" / f"{name}.urdf"
    file.write_text(text)
    argv = ["robots", "import", file, "--name", name, "--package-path", packages, "--out", out]
    code = main([str(a) for a in [*argv, "--samples", "10", *flags]])
    return code, capsys.readouterr().err.strip().splitlines()


def _scaled_origins(text: str, factor: float) -> str:
    def scaled(match):
        return 'xyz="' + " ".join(f"{float(v) * factor:g}" for v in match.group(1).split()) + '"'

    return re.sub(r'xyz="([^"]*)"', scaled, text)


REFUSED = {
    "duplicate_joint": (
        lambda t: t.replace('<joint name="joint_3"', '<joint name="joint_2"'),
        "joint joint_2: the name is used twice",
    ),
    "duplicate_link": (
        lambda t: t.replace('<link name="base"/>', '<link name="link_1"/>'),
        "link link_1: the name is used twice",
    ),
    "two_parents": (
        lambda t: t.replace('<child link="base"/>', '<child link="link_1"/>'),
        "link 'link_1' is already the child of joint",
    ),
    "mimic": (
        lambda t: t.replace(
            '<joint name="joint_3" type="revolute">',
            '<joint name="joint_3" type="revolute"><mimic joint="joint_2" multiplier="-1"/>',
        ),
        "joint joint_3 mimic: follows joint 'joint_2'",
    ),
    "limits_in_degrees": (
        lambda t: t.replace('lower="-2.967060" upper="2.967060"', 'lower="-170" upper="170"'),
        "joint joint_1 limit: ±9740°",
    ),
    "speed": (
        lambda t: t.replace('velocity="3.403392"', 'velocity="1e9"'),
        "joint joint_1 limit velocity: 1e+09 rad/s",
    ),
    "millimetres": (lambda t: _scaled_origins(t, 1000.0), "2650 m long"),
    "comma_in_joint_name": (
        lambda t: t.replace('"joint_4"', '"joint,4"'),
        "joint 'joint,4': 'joint,4' is not a name",
    ),
    "space_in_joint_name": (
        lambda t: t.replace('"joint_4"', '"joint 4"'),
        "joint 'joint 4': 'joint 4' is not a name",
    ),
    "colour_of_three": (
        lambda t: t.replace(YELLOW, YELLOW.replace(" 1.0", ""), 1),
        "color rgba: expected four numbers in [0, 1]",
    ),
    "world_as_base": (
        lambda t: (
            t.replace('<link name="base_link">', '<link name="world">')
            .replace('"base_link"', '"world"')
            .replace("base_link", "world")
        ),
        "--base",
    ),
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_a_bad_description_is_one_line_exit_2(m20ia, tmp_path, capsys, case):
    packages, text = m20ia
    edit, words = REFUSED[case]
    flags = ["--base", "world"] if case == "world_as_base" else []
    code, err = _import(capsys, packages, edit(text), tmp_path / "out", case, *flags)
    assert code == 2 and len(err) == 1 and words in err[0], err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_a_cycle_in_the_joint_tree_ends_at_once(m20ia, tmp_path, capsys):
    """joint_1's parent made link_2: walking up from tool0 meets link_2 twice (this
    hung, growing ~17 MB/s; an alarm ends the test should it hang again)."""
    packages, text = m20ia
    cycle = text.replace(
        '<parent link="base_link"/><child link="link_1"/>',
        '<parent link="link_2"/><child link="link_1"/>',
    )

    def hung(*_):
        raise TimeoutError("the import hangs")

    previous = signal.signal(signal.SIGALRM, hung)
    signal.alarm(60)
    try:
        code, err = _import(capsys, packages, cycle, tmp_path / "out", "cycle")
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    file = packages / "fanuc_m20ia_support" / "urdf" / "cycle.urdf"
    assert code == 2
    assert err == [f"error: {file}: joint joint_1: the joints form a cycle through 'link_2'"]


def test_world_link_and_primitives_without_colour_import(m20ia, tmp_path, capsys):
    """Ordinary URDFs that crashed (exit 3): a `world` link fixed to base_link (Drake's
    world welded twice), a primitive with a material named but never coloured (Drake
    refuses it; the folder was left half written), a top-level material without colour.
    They import, and the robot moves as the unedited one does."""
    packages, text = m20ia
    box = (
        '<visual><geometry><box size="0.1 0.1 0.1"/></geometry><material name="nocolour"/></visual>'
    )
    edited = (
        text.replace(
            '<link name="base_link">',
            '<link name="world"/><joint name="world_joint" type="fixed">'
            '<parent link="world"/><child link="base_link"/></joint><link name="base_link">',
        )
        .replace('<link name="link_1">', '<link name="link_1">' + box)
        .replace('<robot name="fanuc_m20ia">', '<robot name="fanuc_m20ia"><material name="grey"/>')
    )
    out = tmp_path / "out"
    code, err = _import(capsys, packages, edited, out, "plain", "--vendor", "fanuc")
    assert code == 0, err
    robot, unedited = load_robot("plain", out), parse_chain(text, Path("m20ia.urdf"))
    q = np.random.default_rng(0).uniform(robot.q_lower, robot.q_upper, size=(20, 6))
    for k in range(len(q)):
        X_BE = chain_forward(unedited, q[k])[-1].GetAsMatrix4()
        assert np.abs(robot.forward(q[k : k + 1])[0] - X_BE).max() < 1e-12
    urdf = ET.parse(out / "plain" / "plain.urdf").getroot()
    box = urdf.find("link[@name='link_1']/visual/geometry/box/../..")
    assert box.find("material/color").get("rgba") == "0.7 0.7 0.7 1"  # DEFAULT_RGBA
    assert "world" not in ET.tostring(urdf, encoding="unicode")


def test_abb_needs_its_coupling_and_gets_it(tmp_path, capsys):
    """--vendor abb without --j23-coupled/--no-j23-coupled is refused (ABB models
    differ); with it, the bundled IRB 2400's own URDF imports with the bundled record's
    controller axes (axis 3 = q2 + q3) and the RAPID language."""
    from offline_prog.robot.model import ROBOTS_DIR

    urdf = ROBOTS_DIR / "abb_irb2400" / "abb_irb2400.urdf"
    argv = ["robots", "import", str(urdf), "--name", "irb", "--vendor", "abb"]
    argv += ["--out", str(tmp_path), "--samples", "10"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--vendor abb: ABB models differ" in err[0], err
    assert main([*argv, "--j23-coupled"]) == 0, capsys.readouterr().err
    imported, bundled = load_robot("irb", tmp_path), load_robot("abb_irb2400")
    assert imported.j23_coupled and imported.j23_factor == bundled.j23_factor == 1.0
    assert imported.language == "rapid"
    q = np.random.default_rng(1).uniform(bundled.q_lower, bundled.q_upper, size=(20, 6))
    assert np.allclose(imported.controller_joints(q), bundled.controller_joints(q))
    kuka = ["robots", "import", str(urdf), "--name", "k", "--vendor", "kuka", "--j23-coupled"]
    assert main([*kuka, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].endswith("--j23-coupled: a kuka controller counts the URDF's axes"), err


@pytest.mark.parametrize("name", ["my robot", "a,b", "line\nbreak", "x-y", "é"])
def test_a_robot_name_follows_the_seam_name_rule(tmp_path, capsys, name):
    """The folder name heads programs and names the robot in CSV files: letters,
    digits and _, as a seam's name."""
    from offline_prog.robot.model import ROBOTS_DIR

    urdf = ROBOTS_DIR / "kuka_kr16_2" / "kuka_kr16_2.urdf"
    code = main(["robots", "import", str(urdf), "--name", name, "--out", str(tmp_path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--name" in err[0] and "is not a name" in err[0], err
    assert not any(tmp_path.iterdir())
