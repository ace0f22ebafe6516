"""The session loop without a browser: refused values keep the session and its state,
a plan older than the controls is never shown as current, a plan still running when
the controls move on stops at its next stage."""

import time

import numpy as np
import pytest
from pydrake.geometry import Meshcat

from offline_prog.session.replan import SupersededError
from offline_prog.session.server import Session

from conftest import CELLS

TIMEOUT_S = 30


def run_until(session: Session, done) -> None:
    deadline = time.monotonic() + TIMEOUT_S
    while not done():
        assert time.monotonic() < deadline, session.snapshot()["status"]
        session.step()
        time.sleep(0.01)


def new_session() -> Session:
    """A session with its first plan shown."""
    session = Session(CELLS / "tape_cylinder_ur10e.yaml", Meshcat())
    run_until(session, lambda: session.snapshot()["current"])
    return session


@pytest.fixture(scope="module")
def untouched():
    """One session for the tests whose requests are all refused; each checks that its
    own requests changed nothing, so none depends on another's order."""
    return new_session()


@pytest.fixture
def session():
    """A session of the test's own: it changes the state."""
    return new_session()


def test_the_first_plan_is_shown_with_its_figures(untouched):
    snapshot = untouched.snapshot()
    status = snapshot["status"]
    assert status["kind"] == "feasible" and status["line"].startswith("feasible · cycle")
    assert snapshot["duration"] > 0 and snapshot["length"] > 0
    assert status["details"]["samples"]["colliding"] == 0


def test_a_bad_value_is_refused_and_the_session_goes_on(untouched):
    before = untouched.snapshot()
    reply = untouched.set_value("speed", "-3")
    after = untouched.snapshot()
    assert reply["ok"] is False and after["message"]["kind"] == "refused"
    assert "refused speed = '-3': must be > 0" in after["message"]["text"]
    assert after["values"] == before["values"] and after["current"]
    assert untouched.action("seek", "abc")["ok"] is False
    untouched.step()  # nothing to re-plan
    assert untouched.snapshot()["generation"] == before["generation"]


BAD_ACTIONS = [
    ("seek", "nan", "σ 'nan' is not a finite number"),  # Drake aborts on a NaN pose
    ("seek", float("inf"), "σ inf is not a finite number"),
    ("seek", True, "σ True is not a number"),
    ("auto", "no", "auto 'no' is not true or false"),
    ("auto", None, "auto None is not true or false"),
    ("plan", 1, "plan takes no value"),
    ("jump", None, "no action 'jump'"),
]


def test_a_bad_action_changes_nothing(untouched):
    for name, value, reason in BAD_ACTIONS:
        before = untouched.snapshot()
        reply = untouched.action(name, value)
        assert reply["ok"] is False and reason in reply["message"], (name, value, reply)
        untouched.step()
        after = untouched.snapshot()
        assert after["message"] == {"kind": "refused", "text": f"refused: {reply['message']}"}
        for key in ("values", "auto", "generation", "playing", "t", "sigma"):
            assert after[key] == before[key], (name, value, key)


def test_auto_reads_true_and_false(session):
    for value, auto in (("false", False), (False, False), ("true", True), (True, True)):
        session.action("auto", not auto)
        assert session.action("auto", value) == {"ok": True}
        assert session.snapshot()["auto"] is auto, value


def test_an_older_plan_is_never_shown_as_current(session):
    old = session.view.shown
    assert session.set_value("X_IT.y", 5)["ok"]
    snapshot = session.snapshot()
    assert not snapshot["current"] and snapshot["status"]["kind"] == "planning"
    # A late answer for the previous values: dropped, not drawn.
    session.answers.put(("plan", snapshot["generation"] - 1, old))
    session.step()
    assert session.view.shown is old and not session.snapshot()["current"]
    run_until(session, lambda: session.snapshot()["current"])
    shown = session.view.shown
    assert shown is not old and shown.state.p_IT[1] == pytest.approx(0.005)


def test_a_running_plan_stops_when_the_controls_move_on(session):
    generation = session.snapshot()["generation"]
    progress = session._progress(generation, supersede=True)
    progress("fitting")  # still the newest: goes on
    session.set_value("X_IT.y", 6)
    with pytest.raises(SupersededError):
        progress("joints")
    run_until(session, lambda: session.snapshot()["current"])


@pytest.mark.slow
def test_a_job_plans_the_active_seam_and_exports_the_whole_job(tmp_path):
    """seam picks the seam planned live; its own speed is the one edited; Export saves
    the cell and writes the job's plan folder as `plan` does."""
    import json
    import shutil

    cell = tmp_path / "job.yaml"
    shutil.copyfile(CELLS / "seal_job_kr16.yaml", cell)
    session = Session(cell, Meshcat(), out_root=tmp_path / "out")
    run_until(session, lambda: session.snapshot()["current"])
    assert session.snapshot()["status"]["line"].startswith("seam border: feasible")
    session.set_value("seam", 3)
    assert session.snapshot()["values"]["speed"] == 150.0  # the stripe's own speed
    session.set_value("speed", 120)
    run_until(session, lambda: session.snapshot()["current"])
    assert session.snapshot()["status"]["line"].startswith("seam stripe: feasible")
    session.action("export")
    run_until(session, lambda: session.snapshot()["exported"] is not None)
    saved = tmp_path / "job-1.yaml"
    assert session.snapshot()["saved"] == str(saved)
    assert "    speed: 0.12\n" in saved.read_text()
    report = json.loads((tmp_path / "out" / "job-1" / "report.json").read_text())
    assert [s["seam"] for s in report["seams"]].count("stripe") == 1
    assert report["cell"] == str(saved)


@pytest.mark.slow
def test_a_path_cell_exports_its_one_seam_job(tmp_path):
    """A path: cell's Export writes the folder `plan` writes: the one-seam job, home to
    home, with the job's files (issue 24: one pipeline whatever the caller). Its values
    unchanged, it plans the cell file itself into out/<stem>: nothing is written beside
    the cell (a tape-1.yaml copy landed in cells/ before)."""
    import json
    import shutil

    shutil.copytree(CELLS / "data", tmp_path / "data")
    cell = tmp_path / "tape.yaml"
    shutil.copyfile(CELLS / "tape_cylinder_ur10e.yaml", cell)
    session = Session(cell, Meshcat(), out_root=tmp_path / "out")
    run_until(session, lambda: session.snapshot()["current"])
    assert session.snapshot()["status"]["line"].startswith("feasible")
    session.action("export")
    run_until(session, lambda: session.snapshot()["exported"] is not None)
    folder = tmp_path / "out" / "tape"
    assert (folder / "job.npz").exists() and (folder / "clearance.csv").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data", "out", "tape.yaml"]
    assert session.snapshot()["saved"] is None
    report = json.loads((folder / "report.json").read_text())
    assert report["cell"] == str(cell)
    kinds = [s["segment"] for s in report["job"]["segments"]]
    assert kinds == ["link", "approach:seam", "process:seam", "retract:seam", "link"]
    assert report["trajectory"]["duration_s"] < report["job"]["cycle_time_s"]


def test_the_gripper_is_drawn_at_the_flange(untouched):
    """The session poses the gripper's node at the flange X_IE of the time shown (the
    part at X_IE · X_PE⁻¹ beside it)."""
    import umsgpack

    view = untouched.view
    plan = view.shown.plan
    t = float(plan.trajectory.t[len(plan.trajectory.t) // 3])
    view.pose(t)
    q = [np.interp(t, plan.trajectory.t, plan.joints.q[:, j]) for j in range(6)]
    X_IE = view.drake.X_IE(np.array(q)).GetAsMatrix4()
    for path, expected in (
        ("/drake/visualizer/gripper/gripper", X_IE),
        ("/drake/visualizer/part/part", X_IE @ plan.flange.X_PE.inverse().GetAsMatrix4()),
    ):
        packed = umsgpack.unpackb(view.meshcat._GetPackedTransform(path))
        shown = np.array(packed["matrix"]).reshape(4, 4).T  # column-major
        np.testing.assert_allclose(shown, expected, atol=1e-9)
