"""Calibration in the session: a touches file from the panel is checked at once (a bad
one refused in one line, nothing changed), solved on the planner thread, drawn as the
nominal and the calibrated flange paths side by side, and "Use calibrated values" sets
the controls to the calibrated frames, which re-plans and saves like any control."""

import numpy as np
import pytest
from pydrake.geometry import Meshcat
from test_server import run_until

from offline_prog.session.server import Session

from conftest import CELLS

TOUCHES = (CELLS / "calibration" / "seal_plate_kr16_touches.csv").read_text()


@pytest.fixture(scope="module")
def calibrated():
    """A seal-demo session with the demo touches solved (its first plan shown)."""
    session = Session(CELLS / "seal_plate_kr16.yaml", Meshcat())
    run_until(session, lambda: session.snapshot()["current"])
    assert session.load_touches("touches.csv", TOUCHES, False) == {"ok": True}
    run_until(session, lambda: session.snapshot()["calibration"] is not None)
    return session


def test_the_calibration_is_listed_and_drawn_beside_the_plan(calibrated):
    snapshot = calibrated.snapshot()
    found = snapshot["calibration"]
    assert found["file"] == "touches.csv" and not found["applied"]
    assert [line.split()[0] for line in found["lines"]] == [
        "X_IT",
        "pointer",
        "X_PE",
        "touches:",
        "the",
    ]
    assert snapshot["message"]["text"].startswith("calibrated from touches.csv: the planned path")
    meshcat = calibrated.view.meshcat
    for name in ("nominal", "calibrated"):
        assert meshcat.HasPath(f"/session/calibration/{name}/path"), name
        assert meshcat.HasPath(f"/session/calibration/{name}/tip"), name


def test_the_calibrated_path_is_the_calibrated_cells(calibrated):
    """The orange path: the flange path the calibrated frames ask for, a few mm from
    the plan's (the demo's cell is 1.5 mm and 0.3° off)."""
    from offline_prog.calibration.path_shift import moved_flange

    plan = calibrated.view.shown.plan
    c = calibrated.last_calibration.calibration
    flange = plan.trajectory.flange
    moved = moved_flange(
        flange.p_IE,
        flange.R_IE,
        X_IT=plan.flange.X_IT,
        X_PE=plan.flange.X_PE,
        X_IT_new=c.X_IT,
        X_PE_new=c.X_PE,
    )
    distance = np.linalg.norm(moved - flange.p_IE, axis=1) * 1e3
    assert 0.5 < distance.max() < 10.0


BAD = [
    (("t.csv", "target,q1\n", False), "touches refused: t.csv: line 1: the header must be"),
    (("t.csv", 12, False), "text 12 is not text"),
    ((["t.csv"], TOUCHES, False), "file ['t.csv'] is not text"),
    (("t.csv", TOUCHES, "no"), "controller_angles 'no' is not true or false"),
    (("t.csv", TOUCHES.replace("tool_tip,", "tool_tip,300", 1), False), "line 6: '300-6.3005'"),
    (("t.csv", TOUCHES.replace("tool_tip,-6.3005", "tool_tip,-300", 1), False), "axis 1 at -300"),
]


@pytest.mark.parametrize(("args", "reason"), BAD)
def test_a_bad_touches_file_is_refused_and_nothing_changes(calibrated, args, reason):
    before = calibrated.snapshot()
    reply = calibrated.load_touches(*args)
    assert reply["ok"] is False and reason in reply["message"], reply
    assert "\n" not in reply["message"]
    calibrated.step()
    after = calibrated.snapshot()
    for key in ("values", "generation", "calibration"):
        assert after[key] == before[key], key


def test_use_calibrated_values_sets_the_controls_and_re_plans(calibrated):
    c = calibrated.last_calibration.calibration
    generation = calibrated.snapshot()["generation"]
    assert calibrated.action("calibrated") == {"ok": True}
    snapshot = calibrated.snapshot()
    assert snapshot["generation"] == generation + 1 and snapshot["calibration"]["applied"]
    assert snapshot["values"]["X_IT.x"] == pytest.approx(c.pose_IT[0][0] * 1e3)
    assert snapshot["values"]["X_PE.roll"] == pytest.approx(c.pose_PE[1][0])
    run_until(calibrated, lambda: calibrated.snapshot()["current"])
    assert calibrated.snapshot()["status"]["kind"] == "feasible"
    assert calibrated.action("calibrated") == {"ok": True}  # again: nothing to change
    assert calibrated.snapshot()["generation"] == generation + 1


def test_use_calibrated_values_needs_a_calibration():
    session = Session(CELLS / "tape_cylinder_ur10e.yaml", Meshcat())
    reply = session.action("calibrated")
    assert reply["ok"] is False and "no calibration yet: load a touches file" in reply["message"]
    reply = session.load_touches("t.csv", TOUCHES, False)
    assert reply["ok"] is False and "calibration: missing" in reply["message"]
