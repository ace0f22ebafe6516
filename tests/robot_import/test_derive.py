"""Kinematic parameters derived from the bundled robots' URDFs equal their robot.yaml
records (OPW for the KR 16-2 and IRB 2400, UR for the UR10e), a chain with neither form
falls back to Drake IK, and Drake's FK check measures a wrong model."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from offline_prog.errors import InputError
from offline_prog.robot.model import ROBOTS_DIR, load_robot
from offline_prog.robot_import.chain import parse_chain
from offline_prog.robot_import.derive import derive_opw
from offline_prog.robot_import.derive_ur import derive_ur
from offline_prog.robot_import.verify import check_fk


def _chain(name: str):
    file = ROBOTS_DIR / name / f"{name}.urdf"
    return parse_chain(file.read_text(), file)


@pytest.mark.parametrize("name", ["kuka_kr16_2", "abb_irb2400", "ur10e"])
def test_derived_parameters_equal_the_records(name):
    chain, robot = _chain(name), load_robot(name)
    params = derive_opw(chain) or derive_ur(chain)
    expected = dataclasses.asdict(robot.params)
    for key, value in dataclasses.asdict(params).items():
        assert np.allclose(value, expected[key], atol=1e-12), key
    check = check_fk(chain, params)
    assert check.ok and check.samples == 1000


def test_wrong_parameters_fail_the_fk_check():
    chain = _chain("kuka_kr16_2")
    params = dataclasses.replace(derive_opw(chain), a2=-0.035)  # the sign the README warns of
    check = check_fk(chain, params, samples=50)
    assert not check.ok and check.max_position_m > 0.01


def test_a_wrist_that_is_neither_opw_nor_ur_has_no_closed_form():
    """Axis 5 moved 20 mm sideways: axes 4, 5, 6 no longer meet, and the arm is not a
    UR-type arm either, so the robot gets Drake's IK (family drake)."""
    file = ROBOTS_DIR / "kuka_kr16_2" / "kuka_kr16_2.urdf"
    text = file.read_text()
    origin = text.index("<origin", text.index('<joint name="joint_5"'))
    moved = text[:origin] + '<origin xyz="0 0.02 0" rpy="0 0 0"' + text[text.index("/>", origin) :]
    chain = parse_chain(moved, file)
    assert derive_opw(chain) is None and derive_ur(chain) is None
    assert derive_opw(parse_chain(text, file)) is not None


def test_a_prismatic_joint_is_not_6r():
    file = ROBOTS_DIR / "ur10e" / "ur10e.urdf"
    text = file.read_text().replace(
        'name="joint_3" type="revolute"', 'name="joint_3" type="prismatic"'
    )
    with pytest.raises(InputError, match="not six revolute joints .*joint_3 \\(prismatic\\)"):
        parse_chain(text, Path(file))
