"""``offline-prog calibrate CELL --from-controller FILE``: the controller's frames, mapped
through tool.controller_frame / part.controller_frame (KUKA) or the names derived from
tool.name / part.name (ABB), land in calibrated.yaml as X_IT and X_PE to 0.001 mm /
0.001°; what cannot be mapped is one line, exit 2."""

import json

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from scipy.spatial.transform import Rotation
from synthetic_touches import CELLS
from test_controller_abb import MODULE, matrix
from test_controller_kuka import CONFIG_DAT, WRITTEN

from offline_prog.cli import main
from offline_prog.config.cell import load_cell, transform

MM, DEG = 1e-3, 1e-3


def kuka_cell(folder, *, numbers="", base="[0, 0, 0]"):
    text = (CELLS / "seal_plate_kr16.yaml").read_text()
    text = text.replace("  name: sealant_nozzle\n", f"  name: sealant_nozzle\n{numbers}", 1)
    text = text.replace(
        "X_IB: {translation: [0.0, 0.0, 0.0], rotation: !Rpy {deg: [0, 0, 0]}}",
        f"X_IB: {{translation: {base}, rotation: !Rpy {{deg: [0, 0, 30]}}}}",
    )
    file = folder / "cell.yaml"
    file.write_text(text)
    (folder / "config.dat").write_text(CONFIG_DAT)
    return file


def run(capsys, *args):
    code = main(["calibrate", *map(str, args)])
    out, err = capsys.readouterr()
    return code, out, err


def assert_frame(X: RigidTransform, expected: np.ndarray) -> None:
    assert np.abs(X.translation() - expected[:3, 3]).max() * 1e3 < MM
    turn = Rotation.from_matrix(X.rotation().matrix().T @ expected[:3, :3]).magnitude()
    assert np.degrees(turn) < DEG


def kuka_matrix(x, y, z, a, b, c) -> np.ndarray:
    return RigidTransform(
        RollPitchYaw(np.radians([c, b, a])), np.array([x, y, z]) * 1e-3
    ).GetAsMatrix4()


def test_kuka_base_and_tool_data_become_x_it_and_x_pe(tmp_path, capsys):
    numbers = "  controller_frame: 3\n"
    cell = kuka_cell(tmp_path, numbers=numbers, base="[0.1, -0.2, 0.05]")
    text = cell.read_text().replace(
        "  name: plate_400x300\n", "  name: plate_400x300\n  controller_frame: 1\n"
    )
    cell.write_text(text)
    out = tmp_path / "calibrated.yaml"
    code, printed, err = run(
        capsys, cell, "--from-controller", tmp_path / "config.dat", "--out", out
    )
    assert code == 0, err
    calibrated = load_cell(out)
    X_IB = transform(calibrated.robot.X_IB).GetAsMatrix4()
    assert_frame(transform(calibrated.tool.X_IT), X_IB @ kuka_matrix(*WRITTEN[("BASE", 3)]))
    assert_frame(transform(calibrated.part.X_PE), np.linalg.inv(kuka_matrix(*WRITTEN[("TOOL", 1)])))
    lines = printed.strip().splitlines()
    assert (
        'from BASE_DATA[3] "NOZZLE"' in lines[0]
        and 'from TOOL_DATA[1] "PLATE; on the flange"' in lines[1]
    )
    data = json.loads((tmp_path / "calibration.json").read_text())
    assert data["controller"] == {
        "tool": 'BASE_DATA[3] "NOZZLE"',
        "part": 'TOOL_DATA[1] "PLATE; on the flange"',
        "notes": [],
    }
    assert data["path_shift"]["max_mm"] > 1.0  # the frames differ from the cell's


def test_a_frame_the_cell_does_not_number_keeps_the_cell_s(tmp_path, capsys):
    cell = kuka_cell(tmp_path, numbers="  controller_frame: 3\n")
    out = tmp_path / "calibrated.yaml"
    assert run(capsys, cell, "--from-controller", tmp_path / "config.dat", "--out", out)[0] == 0
    calibrated, nominal = load_cell(out), load_cell(cell)
    assert transform(calibrated.part.X_PE).IsExactlyEqualTo(transform(nominal.part.X_PE))
    assert out.read_text().count("X_PE: {translation: [0.0, 0.0, 0.100]") == 1


def test_a_type_that_is_not_external_tcp_is_noted(tmp_path, capsys):
    cell = kuka_cell(tmp_path, numbers="  controller_frame: 3\n")
    (tmp_path / "config.dat").write_text(
        CONFIG_DAT.replace("BASE_TYPE[3]=#TCP", "BASE_TYPE[3]=#BASE")
    )
    code, printed, _ = run(
        capsys, cell, "--from-controller", tmp_path / "config.dat", "--out", tmp_path / "c.yaml"
    )
    assert code == 0 and "note: BASE_TYPE[3] is #BASE, not #TCP" in printed


@pytest.mark.parametrize(
    ("numbers", "reason"),
    [
        ("", "the cell numbers no controller frame: set tool.controller_frame"),
        (
            "  controller_frame: 5\n",
            "no BASE_DATA[5] (the cell's tool.controller_frame); the file has BASE_DATA [1, 3]",
        ),
        ("  controller_frame: 40\n", "tool.controller_frame: 40 is not a BASE_DATA number"),
    ],
)
def test_what_cannot_be_mapped_is_one_line(tmp_path, capsys, numbers, reason):
    cell = kuka_cell(tmp_path, numbers=numbers)
    out = tmp_path / "c.yaml"
    code, _, err = run(capsys, cell, "--from-controller", tmp_path / "config.dat", "--out", out)
    assert code == 2 and reason in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def test_abb_tooldata_and_wobjdata_become_x_it_and_x_pe(tmp_path, capsys):
    text = (CELLS / "weld_seam_irb2400.yaml").read_text().replace(": data/", f": {CELLS}/data/")
    cell = tmp_path / "weld.yaml"
    cell.write_text(text)
    (tmp_path / "CalibData.mod").write_text(MODULE)
    out = tmp_path / "calibrated.yaml"
    code, printed, err = run(
        capsys, cell, "--from-controller", tmp_path / "CalibData.mod", "--out", out
    )
    assert code == 0, err
    calibrated = load_cell(out)
    tframe = matrix([1100.512, -0.412, 899.733], [0.7072068, -0.7070068, 0.0012, -0.0004])
    object_in_E = matrix([-30.25, 0.4, 300.118], [0.7071068, 0.0, -0.7071068, 0.0]) @ matrix(
        [1.5, 0, 0], [0.9998477, 0, 0, 0.0174524]
    )
    assert_frame(transform(calibrated.tool.X_IT), tframe)
    assert_frame(transform(calibrated.part.X_PE), np.linalg.inv(object_in_E))
    assert "from tooldata tool_welding_torch" in printed and "from wobjdata wobj_bracket" in printed
    (tmp_path / "Other.mod").write_text(MODULE.replace("tool_welding_torch", "tool_gun"))
    code, _, err = run(capsys, cell, "--from-controller", tmp_path / "Other.mod", "--out", out)
    named = "no PERS tooldata tool_welding_torch (named after the cell's tool.name)"
    assert code == 2 and f"{named}; the file has tool0_copy, tool_gun" in err


def test_a_robot_without_a_reader_is_refused(tmp_path, capsys):
    text = (CELLS / "tape_cylinder_ur10e.yaml").read_text().replace(": data/", f": {CELLS}/data/")
    cell = tmp_path / "tape.yaml"
    cell.write_text(text)
    (tmp_path / "x.txt").write_text("anything")
    code, _, err = run(
        capsys, cell, "--from-controller", tmp_path / "x.txt", "--out", tmp_path / "c.yaml"
    )
    assert (
        code == 2
        and "the robot's controller (urscript) has no frame file this command reads" in err
    )
