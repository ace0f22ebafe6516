"""Payload statements: KRL $LOAD, RAPID tload + GripLoad, URScript set_payload; a
prominent warning in every header and report.json when the cell gives none (the demo
cells give both masses)."""

import dataclasses
import json
import re

import numpy as np
import pytest
from config.test_cell_errors import BASE, write_cell  # tests/config
from scipy.spatial.transform import Rotation

from offline_prog.config.cell import load_cell
from offline_prog.config.checks import check_cell
from offline_prog.errors import InputError
from offline_prog.export.formats import export
from offline_prog.export.job_program import JobProgramData
from offline_prog.results.report import payload_summary
from offline_prog.robot.model import ROBOTS_DIR

RECORD = {  # gripper 4 kg 80 mm down the flange axis; part 2 kg at (10, 0, 5) mm in P
    "gripper_mass_kg": 4.0,
    "gripper_com_E_m": [0.0, 0.0, 0.08],
    "part_mass_kg": 2.0,
    "part_com_P_m": [0.01, 0.0, 0.005],
}


def expected_total(data):
    X_EP = data.job.X_EP
    p_EC = X_EP[:3, :3] @ np.array(RECORD["part_com_P_m"]) + X_EP[:3, 3]
    return 6.0, (4.0 * np.array(RECORD["gripper_com_E_m"]) + 2.0 * p_EC) / 6.0


def with_payload(data: JobProgramData) -> JobProgramData:
    return dataclasses.replace(data, job=dataclasses.replace(data.job, payload=RECORD))


@pytest.fixture(scope="module")
def plans(planned_job):
    names = ("seal_plate_kr16", "weld_seam_irb2400", "tape_cylinder_ur10e")
    return [JobProgramData.load(planned_job(name)[1]) for name in names]


def program(data, fmt, folder, **options) -> str:
    """The main program's text (force: a test cell's plan may fail its link budget)."""
    return export(data, fmt, folder, force=True, **options)[0].read_text()


def unwrapped(text: str) -> str:
    """A program's text with its comment lines joined (KRL wraps its header at 100)."""
    return re.sub(r"\s*\n\s*[;!#]\s*", " ", text)


def test_cell_keys(tmp_path):
    text = BASE.replace("part:\n", "gripper: {mass_kg: 4, center_of_mass_mm: [0, 0, 80]}\npart:\n")
    text = text.replace("part:\n", "part:\n  mass_kg: 2.0\n  center_of_mass_mm: [10, 0, 5]\n", 1)
    cell = load_cell(write_cell(tmp_path, text))
    check_cell(tmp_path / "cell.yaml", cell, ROBOTS_DIR)
    assert cell.gripper.mass_kg == 4 and cell.part.center_of_mass_mm == [10, 0, 5]
    for bad, key in [("mass_kg: 2.0", "part.mass_kg"), ("[10, 0, 5]", "part.center_of_mass_mm")]:
        wrong = text.replace(bad, {"mass_kg: 2.0": "mass_kg: -1"}.get(bad, "[1, 2]"))
        with pytest.raises(InputError, match=key):
            check_cell(tmp_path / "cell.yaml", load_cell(write_cell(tmp_path, wrong)), ROBOTS_DIR)


def test_krl_load(plans, tmp_path):
    data = with_payload(plans[0])
    text = program(data, "krl", tmp_path)
    m = re.search(
        r"^\$LOAD=\{M ([\d.]+),CM \{X (\S+),Y (\S+),Z (\S+),A 0\.0+,B 0\.0+,C 0\.0+\}", text, re.M
    )
    mass, p_EC = expected_total(data)
    assert float(m.group(1)) == pytest.approx(mass)
    np.testing.assert_allclose([float(m.group(i)) for i in (2, 3, 4)], p_EC * 1e3, atol=0.06)
    assert text.index("$LOAD=") < text.index("PTP XHOME")


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # rapidchecker's pyparsing calls
def test_rapid_loads(plans, tmp_path):
    data = with_payload(plans[1])
    text = program(data, "rapid", tmp_path)
    frames = (tmp_path / "OfflineProgFrames.mod").read_text()  # the tool's tload: the gripper
    assert re.search(
        r"PERS tooldata \w+ := \[FALSE,.*,\[4,\[0,0,80\],\[1,0,0,0\],0,0,0\]\];", frames
    )
    assert "PERS loaddata partLoad := [2,[10,0,5],[1,0,0,0],0,0,0];" in text
    assert text.index("GripLoad partLoad;") < text.index("MoveAbsJ jHome")
    rapidchecker = pytest.importorskip("rapidchecker.cli")
    assert [str(e) for e in rapidchecker.check_file(text)] == []
    assert [str(e) for e in rapidchecker.check_file(frames)] == []


def test_urscript_payload(plans, tmp_path):
    data = with_payload(plans[2])
    text = program(data, "urscript", tmp_path)
    m = re.search(r"^  set_payload\(([\d.]+), \[(.*)\]\)$", text, re.M)
    mass, p_EC = expected_total(data)
    assert float(m.group(1)) == pytest.approx(mass)
    np.testing.assert_allclose([float(v) for v in m.group(2).split(",")], p_EC, atol=1e-4)
    assert text.index("set_payload(") < text.index("  movej(")


def test_without_payload_every_header_and_the_report_warn(plans, planned_job, tmp_path):
    kuka, abb, ur = (  # no masses
        dataclasses.replace(data, job=dataclasses.replace(data.job, payload={})) for data in plans
    )
    for data, fmt in ((kuka, "krl"), (abb, "rapid"), (ur, "urscript")):
        # export refuses to invent a load: one line naming the keys and the way out
        with pytest.raises(ValueError) as refused:
            export(data, fmt, tmp_path / "refused", force=True)
        assert "\n" not in str(refused.value) and "--no-payload" in str(refused.value)
        assert "gripper.mass_kg / part.mass_kg" in str(refused.value)
        assert not (tmp_path / "refused").exists() or not any((tmp_path / "refused").iterdir())
    texts = [
        program(kuka, "krl", tmp_path / "k", no_payload=True),
        program(abb, "rapid", tmp_path / "r", no_payload=True),
        program(ur, "urscript", tmp_path / "u", no_payload=True),
    ]
    for text in texts:
        assert "WARNING: PAYLOAD NOT SET" in text
        assert "the controller's active load is used" in unwrapped(text)
        assert "$LOAD" not in text and "GripLoad" not in text and "loaddata" not in text
        assert "set_payload(" not in text
    # No RAPID load anywhere but the frames module's tooldata, which says none is given.
    frames = (tmp_path / "r" / "OfflineProgFrames.mod").read_text()
    assert "[0.001,[0,0,0],[1,0,0,0],0,0,0]" in frames and "gives no gripper load" in frames
    without = payload_summary(load_cell(write_cell(tmp_path)), tmp_path / "cell.yaml")
    assert without["set"] is False and "PAYLOAD NOT SET" in without["warning"]
    # The demo cells give both masses: their programs and reports set the load.
    report = json.loads((planned_job("seal_plate_kr16")[1] / "report.json").read_text())
    assert report["payload"]["set"] is True and report["payload"]["warning"] is None
    assert list(report).index("payload") < 10  # near the top: prominent
    assert "WARNING: PAYLOAD NOT SET" not in program(plans[0], "krl", tmp_path / "d")


@pytest.mark.parametrize(
    ("record", "missing"),
    [
        ({}, "gripper.mass_kg / part.mass_kg"),
        ({k: v for k, v in RECORD.items() if k.startswith("gripper")}, "part.mass_kg"),
        ({k: v for k, v in RECORD.items() if k.startswith("part")}, "gripper.mass_kg"),
    ],
)
def test_the_warning_names_the_cell_keys(record, missing):
    from offline_prog.export.payload import payload_note

    note = payload_note(record, np.eye(4))
    assert note.startswith(f"WARNING: PAYLOAD NOT SET (the cell gives no {missing}): ")


def test_a_job_reports_and_prints_the_payload_warning(planned_job, tmp_path):
    """report.json of a job has the payload entry, and ``plan`` prints its warning once
    when the cell gives no masses (none for the demo, which gives them)."""
    import io

    from rich.console import Console

    from offline_prog.results.summary import print_job_summary

    _, folder = planned_job("seal_job_kr16")
    report = json.loads((folder / "report.json").read_text())
    assert report["payload"]["set"] is True and report["payload"]["total"]["mass_kg"] > 0
    assert list(report).index("payload") < 10  # near the top: prominent
    out = io.StringIO()
    print_job_summary(Console(file=out, width=400), report, {"report": folder / "x"}, 1.0)
    assert "payload" not in out.getvalue()
    report["payload"] = payload_summary(load_cell(write_cell(tmp_path)), tmp_path / "cell.yaml")
    assert "(the cell gives no gripper.mass_kg / part.mass_kg)" in report["payload"]["warning"]
    out = io.StringIO()
    print_job_summary(Console(file=out, width=400), report, {"report": folder / "x"}, 1.0)
    assert out.getvalue().count(f"payload   {report['payload']['warning']}") == 1  # once


def test_no_payload_writes_no_load_even_when_the_cell_gives_one(plans, tmp_path):
    """``--no-payload`` with masses in the cell: no load statement, and the header says
    the controller's active load is used."""
    for data, fmt in zip(plans, ("krl", "rapid", "urscript"), strict=True):
        text = program(with_payload(data), fmt, tmp_path / fmt, no_payload=True)
        note = "Payload: not written (--no-payload): the controller's active load is used"
        assert note in unwrapped(text)
        assert "$LOAD" not in text and "GripLoad" not in text and "set_payload(" not in text


def test_cli_export_refuses_a_plan_without_masses_in_one_line(plans, tmp_path, capsys):
    """``plan`` wrote the folder; ``export`` of its controller program without masses
    is one line (exit 2) until ``--no-payload``."""
    from offline_prog.cli import main

    data = dataclasses.replace(plans[0], job=dataclasses.replace(plans[0].job, payload={}))
    data.save(tmp_path / "plan")
    argv = ["export", str(tmp_path / "plan"), "--format", "krl", "--out", str(tmp_path / "p")]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--no-payload" in err[0] and "part.mass_kg" in err[0], err
    assert main([*argv, "--no-payload"]) == 0
    assert "WARNING: PAYLOAD NOT SET" in (tmp_path / "p" / "offline_prog.src").read_text()


def inertia_record(data) -> dict:
    """RECORD with inertias about each centre of mass (gripper in E, part in P, seeded
    random) and the total the plan would store (scene.payload.combined)."""
    from pydrake.math import RigidTransform

    from offline_prog.scene.payload import MassProperties, combined

    rng = np.random.default_rng(3)

    def inertia():
        A = rng.uniform(-1, 1, (3, 3))
        return A @ A.T * 0.01 + np.eye(3) * 0.005

    record = dict(RECORD, gripper_inertia_E_kgm2=inertia().tolist())
    record["part_inertia_P_kgm2"] = inertia().tolist()
    bodies = [
        MassProperties(
            4.0,
            np.array(RECORD["gripper_com_E_m"]),
            np.array(record["gripper_inertia_E_kgm2"]),
            "",
            "",
        ),
        MassProperties(
            2.0, np.array(RECORD["part_com_P_m"]), np.array(record["part_inertia_P_kgm2"]), "", ""
        ),
    ]
    record["total"] = combined(*bodies, RigidTransform(data.job.X_EP))
    return record


def test_programs_carry_the_inertia_the_cell_gives(plans, tmp_path):
    """KRL $LOAD's J about the axes CM's A, B, C name and RAPID's loaddata (ix, iy, iz
    about aom) give back the inertia matrices of the record: the total on $FLANGE, the
    gripper's (tload) in tool0 and the part's (GripLoad) in the object frame."""
    kuka = plans[0]
    record = inertia_record(kuka)
    data = dataclasses.replace(kuka, job=dataclasses.replace(kuka.job, payload=record))
    text = program(data, "krl", tmp_path / "k")
    m = re.search(r"A (\S+),B (\S+),C (\S+)\},J \{X (\S+),Y (\S+),Z (\S+)\}\}", text)
    R = Rotation.from_euler("ZYX", [float(m[i]) for i in (1, 2, 3)], degrees=True).as_matrix()
    J = np.diag([float(m[i]) for i in (4, 5, 6)])
    np.testing.assert_allclose(R @ J @ R.T, record["total"]["inertia_E_kgm2"], atol=2e-5)
    abb = plans[1]
    record = inertia_record(abb)
    data = dataclasses.replace(abb, job=dataclasses.replace(abb.job, payload=record))
    text = program(data, "rapid", tmp_path / "r")
    frames = (tmp_path / "r" / "OfflineProgFrames.mod").read_text()
    loads = {
        "gripper_inertia_E_kgm2": re.search(
            r"tooldata \w+ := \[FALSE,\[\[.*?\]\],(\[.*\])\];", frames
        )[1],
        "part_inertia_P_kgm2": re.search(r"partLoad := (\[.*\]);", text)[1],
    }
    for key, load in loads.items():
        value = json.loads(load)
        R = Rotation.from_quat(value[2], scalar_first=True).as_matrix()
        inertia = R @ np.diag(value[3:6]) @ R.T
        np.testing.assert_allclose(inertia, record[key], atol=2e-5)
