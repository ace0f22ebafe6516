"""``offline-prog calibrate CELL --touches FILE --out calibrated.yaml`` on the demo:
calibrated.yaml is the cell file with only X_IT's and X_PE's numbers changed (comments
and everything else byte-identical), calibration.json holds the contract's figures, one
line per frame is printed, bad input is one line with exit 2, and a plan of the
calibrated cell passes every check the nominal plan passes."""

import json
import shutil

import numpy as np
import pytest
from synthetic_touches import nominal_truth, start_pose, synthetic_touches

from offline_prog.cli import main
from offline_prog.config.cell import load_cell, transform

from conftest import CELLS

DEMO = CELLS / "seal_plate_kr16.yaml"
TOUCHES = CELLS / "calibration" / "seal_plate_kr16_touches.csv"
# The demo's true cell (scripts/make_demo_touches.py prints it).
TRUE_P_IT_MM = [1000.721, 0.372, 501.262]
TRUE_P_PE_MM = [0.962, 0.938, 100.666]


def run(capsys, *args):
    code = main(["calibrate", *map(str, args)])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """The README's command on the demo, run once: (folder, printed lines)."""
    folder = tmp_path_factory.mktemp("calibrated")
    code = main(
        ["calibrate", str(DEMO), "--touches", str(TOUCHES), "--out", str(folder / "c.yaml")]
    )
    assert code == 0
    return folder


def test_only_the_two_frames_change(demo):
    old = DEMO.read_text().splitlines()
    new = (demo / "c.yaml").read_text().splitlines()
    changed = [(a, b) for a, b in zip(old, new, strict=True) if a != b]
    assert [a.split(":")[0].strip() for a, _ in changed] == ["X_IT", "X_PE"]
    for a, b in changed:  # the same line, its numbers replaced
        assert a.split("{")[0] == b.split("{")[0] and b.endswith("]}}")
    cell = load_cell(demo / "c.yaml")
    assert np.allclose(transform(cell.tool.X_IT).translation() * 1e3, TRUE_P_IT_MM, atol=0.1)
    assert np.allclose(transform(cell.part.X_PE).translation() * 1e3, TRUE_P_PE_MM, atol=0.1)


def test_calibration_json_holds_the_contract_figures(demo):
    data = json.loads((demo / "calibration.json").read_text())
    estimates = data["estimates"]
    assert set(estimates) == {"tool_tip", "pointer", "tool_axis", "grasp"}
    assert len(estimates["tool_tip"]["sigma_mm"]) == 3 and estimates["tool_axis"]["sigma_deg"] > 0
    assert set(estimates["grasp"]) >= {"p_PE_mm", "sigma_mm", "rotation_sigma_deg"}
    assert [t["line"] for t in data["touches"]] == list(range(6, 27))
    assert all(len(t["residual_mm"]) == 3 and t["used"] for t in data["touches"])
    distances = [np.linalg.norm(t["residual_mm"]) for t in data["touches"]]
    assert data["rms_mm"] == pytest.approx(np.sqrt(np.mean(np.square(distances))), rel=1e-3)
    assert 0.01 < data["rms_mm"] < 0.06 and 1 < data["condition_number"] < 100
    assert data["outlier"] is None and data["controller_angles"] is False
    shift = data["path_shift"]
    assert 1.0 < shift["max_mm"] < 10.0 and 0 <= shift["sigma_mm"] <= 1200.0
    assert shift["seams"][0]["seam"] == "seam" and shift["seams"][0]["max_tilt_deg"] > 0.1
    assert data["X_IT"]["translation"] == [
        round(v * 1e-3, 7) for v in estimates["tool_tip"]["p_IT_mm"]
    ]


def test_one_line_per_frame_is_printed(tmp_path, capsys):
    code, out, err = run(capsys, DEMO, "--touches", TOUCHES, "--out", tmp_path / "c.yaml")
    assert code == 0 and err == ""
    lines = out.strip().splitlines()
    assert [line.split()[0] for line in lines] == ["X_IT", "pointer", "X_PE", "touches:", "the"]
    assert "axis tilted" in lines[0] and "±" in lines[0] and "no outlier" in lines[3]
    assert lines[4].startswith("the planned path on the part moves up to ")


def test_data_files_are_named_from_the_new_folder(tmp_path, capsys):
    """A cell whose data files are relative (the tape demo) calibrated into another
    folder: the copy names them from there, and it loads (calibrate checks it)."""
    shutil.copytree(CELLS / "data", tmp_path / "data")
    block = "calibration: {part_points: {a: [-150, 0, 0], b: [150, 0, 0], c: [0, 60, -6]}}\n"
    text = (CELLS / "tape_cylinder_ur10e.yaml").read_text() + block
    (tmp_path / "tape.yaml").write_text(text)
    inputs, X_IE0 = start_pose(tmp_path / "tape.yaml")
    rng = np.random.default_rng(3)
    touched = synthetic_touches(
        inputs, X_IE0, nominal_truth(inputs, rng), rng, n_tip=0, per_point=4
    )
    (tmp_path / "t.csv").write_text(touched.text)
    out = tmp_path / "o" / "c.yaml"
    code, printed, err = run(
        capsys, tmp_path / "tape.yaml", "--touches", tmp_path / "t.csv", "--out", out
    )
    assert code == 0, err
    moved = out.read_text()
    assert 'points: "../data/tape_cylinder.csv"' in moved
    assert 'mesh: "../data/cylinder_shell.stl"' in moved
    assert "pointer" not in printed  # no pointer touches: no pointer line
    assert load_cell(out).path.points == "../data/tape_cylinder.csv"


@pytest.mark.parametrize(
    ("args", "reason"),
    [
        (["--out", DEMO], "--out: is the cell file itself"),
        (["--out", "calibrated.txt"], "--out: the calibrated cell is a .yaml file"),
        (
            ["--controller-angles", "--from-controller", "x.dat", "--out", "c.yaml"],
            "applies to --touches",
        ),
    ],
)
def test_a_bad_flag_is_one_line(tmp_path, capsys, monkeypatch, args, reason):
    monkeypatch.chdir(tmp_path)
    if "--from-controller" not in args:
        args = ["--touches", TOUCHES, *args]
    code, _, err = run(capsys, DEMO, *args)
    assert code == 2 and reason in err and len(err.strip().splitlines()) == 1, err


def test_radians_are_refused_with_exit_2(tmp_path, capsys):
    lines = TOUCHES.read_text().splitlines()
    rows = [lines[4]] + [
        ",".join([r.split(",")[0]] + [f"{np.radians(float(v)):.6f}" for v in r.split(",")[1:]])
        for r in lines[5:]
    ]
    (tmp_path / "rad.csv").write_text("\n".join(rows) + "\n")
    code, _, err = run(
        capsys, DEMO, "--touches", tmp_path / "rad.csv", "--out", tmp_path / "c.yaml"
    )
    assert code == 2 and "look like radians; write degrees" in err
    assert not (tmp_path / "c.yaml").exists() and not (tmp_path / "calibration.json").exists()


def test_a_cell_without_calibration_block_is_refused(tmp_path, capsys):
    text = DEMO.read_text().split("calibration:")[0]
    (tmp_path / "cell.yaml").write_text(text)
    code, _, err = run(
        capsys, tmp_path / "cell.yaml", "--touches", TOUCHES, "--out", tmp_path / "c.yaml"
    )
    assert code == 2 and "calibration: missing" in err


@pytest.mark.slow  # plans the calibrated demo (the nominal one comes from the fixture)
def test_a_plan_of_the_calibrated_cell_passes_the_nominal_plans_checks(demo, planned_job):
    from offline_prog.plan import plan_job
    from offline_prog.results.job_folder import write_job_outputs

    shutil.copyfile(demo / "c.yaml", demo / "seal_calibrated.yaml")
    _, nominal_folder = planned_job("seal_plate_kr16")
    folder = demo / "plan"
    write_job_outputs(plan_job(demo / "seal_calibrated.yaml"), folder)
    nominal = json.loads((nominal_folder / "report.json").read_text())
    calibrated = json.loads((folder / "report.json").read_text())
    for report in (nominal, calibrated):
        assert report["feasible"] and report["collision_free"] and not report["failure"]
        assert report["min_distance_m"] >= report["clearance_m"]
        motion = report["robot_motion"]
        assert min(motion["joint_limit_margin_deg"]) > 0
        assert (
            max(motion["max_joint_speed_use"]) <= 1
            and max(motion["max_joint_acceleration_use"]) <= 1
        )
    assert (
        calibrated["quality"]["share_within_band"] >= nominal["quality"]["share_within_band"] - 0.01
    )
    programs = sorted(p.name for p in (nominal_folder / "programs").iterdir())
    assert sorted(p.name for p in (folder / "programs").iterdir()) == programs
