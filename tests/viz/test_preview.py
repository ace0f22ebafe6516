"""The MeshCat preview: a standalone preview.html that shows the robot and part in a
real browser (software WebGL), an animation as long as the plan, and the preview
command; plus a plan that fails its collision check."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from PIL import Image
from scipy.spatial.transform import Rotation

from offline_prog.path.lead import path_ends
from offline_prog.plan import plan_cell
from offline_prog.viz.preview import show_plan

from browser import WEBGL_ARGS, keep_artifact, require_chromium, screenshot
from conftest import CELLS, REPO
from live_session import free_port_pair


@pytest.fixture(scope="module")
def seal(planned_folder):
    return planned_folder("seal_plate_kr16")


def test_animation_has_the_plan_duration(seal):
    from pydrake.geometry import Meshcat

    plan, _ = seal
    info = show_plan(plan, Meshcat())
    # Frames 0 .. floor(T · fps): one per 1/fps of the plan, the last at its end.
    expected = int(np.floor(plan.trajectory.duration * info["frames_per_second"])) + 1
    assert info["frames"] == expected


def test_preview_html_needs_no_server(seal, tmp_path, monkeypatch):
    """preview.html is written from the plan alone: no MeshCat server is started, the
    page opens no connection, and its animation is as long as the plan."""
    import offline_prog.viz.preview as preview

    def no_server(*args, **kwargs):
        raise AssertionError("a MeshCat server was started to write a file")

    monkeypatch.setattr(preview, "Meshcat", no_server)
    monkeypatch.setattr("pydrake.geometry.Meshcat", no_server)
    plan, _ = seal
    info = preview.write_preview_html(plan, tmp_path / "preview.html")
    text = (tmp_path / "preview.html").read_text()
    assert "make_connection(" not in text and "handle_command_bytearray(_b(" in text
    expected = int(np.floor(plan.trajectory.duration * info["frames_per_second"])) + 1
    assert info["frames"] == expected


def test_preview_draws_the_vendor_meshes_in_their_colours(seal):
    """Every robot link is drawn from its vendor mesh (hundreds of vertices, coloured
    by its materials), not from boxes."""
    import umsgpack

    import offline_prog.viz.preview as preview

    plan, _ = seal
    scene, _ = preview.preview_scene(plan)
    drawn = {}
    for message in scene.messages:
        if isinstance(message, bytes):
            command = umsgpack.unpackb(message)
            if command["type"] == "set_object" and "/kuka_kr16_2/" in command["path"]:
                link = command["path"].split("/")[3]
                drawn[link] = command["object"]["geometries"][0]
    assert set(drawn) == {"base_link", *(f"link_{k}" for k in range(1, 7))}
    for link, geometry in drawn.items():
        attributes = geometry["data"]["attributes"]
        n_vertices = len(attributes["position"]["array"].data) // 12  # float32 x, y, z
        assert n_vertices > 300 and "color" in attributes, link


def test_preview_draws_the_gripper_at_the_flange(seal):
    """The gripper's shapes are drawn under its body's node, and the animation moves that
    node with the flange: at every frame its pose is the link_6 frame's (it is welded to
    the flange) and the part's is X_IE · X_PE⁻¹."""
    import umsgpack

    import offline_prog.viz.preview as preview

    plan, _ = seal
    scene, _ = preview.preview_scene(plan)
    drawn, animation = [], None
    for message in scene.messages:
        if isinstance(message, bytes):
            command = umsgpack.unpackb(message)
            if command["type"] == "set_object" and command["path"].startswith("/drake/gripper/"):
                node = command["path"].split("/")[4]  # gripper::<shape>.visual_<i>
                drawn.append(node.split("::")[1].rsplit(".visual_", 1)[0])
        elif '"set_animation"' in message:
            animation = json.loads(message)
    names = [shape.name for shape in plan.cell.gripper.geometry]
    assert sorted(drawn) == sorted(names)
    tracks = {a["path"]: a["clip"]["tracks"] for a in animation["animations"]}
    gripper, part = tracks["/drake/gripper/gripper"], tracks["/drake/part/part"]
    X_EP = plan.flange.X_PE.inverse().GetAsMatrix4()
    for k in range(0, len(gripper[0]["keys"]), 37):
        X_IE, X_IP = np.eye(4), np.eye(4)
        X_IE[:3, 3] = gripper[0]["keys"][k]["value"]
        X_IE[:3, :3] = Rotation.from_quat(gripper[1]["keys"][k]["value"]).as_matrix()
        X_IP[:3, 3] = part[0]["keys"][k]["value"]
        X_IP[:3, :3] = Rotation.from_quat(part[1]["keys"][k]["value"]).as_matrix()
        np.testing.assert_allclose(X_IE @ X_EP, X_IP, atol=1e-9)


@pytest.mark.slow
def test_preview_html_shows_the_cell_in_a_browser(seal, tmp_path):
    require_chromium()
    _, out = seal
    page = out / "preview.html"
    text = page.read_text()
    assert "<script" in text and len(text) > 100_000  # MeshCat's viewer is inlined
    # Software WebGL renders every animation frame of the page's time budget: its cost
    # goes with the window's pixels (1200 x 800: 82 s alone, past the 120 s timeout
    # under load; 600 x 400: ~10 s), and the cell is as plain in the smaller one.
    png = screenshot(page, tmp_path / "preview.png", size=(600, 400), extra=WEBGL_ARGS)
    keep_artifact(png, "preview_seal_plate_kr16.png")
    image = np.asarray(Image.open(png).convert("RGB")).astype(float)
    assert image.std() > 20, "the 3D view is blank"
    red, green, blue = image[..., 0], image[..., 1], image[..., 2]
    orange = (red > 180) & (green > 60) & (green < 190) & (blue < 90)  # robot and plate
    assert orange.mean() > 0.01, "no robot or part in view"
    h, w = orange.shape
    centre = orange[h // 4 : 3 * h // 4, w // 4 : 3 * w // 4]
    assert centre.mean() > orange.mean(), "the camera is not framed on the cell"


@pytest.mark.slow
def test_preview_command_serves_and_exits(tmp_path):
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "preview",
            str(CELLS / "tape_cylinder_ur10e.yaml"),
            "--port",
            "7077",
            "--seconds",
            "0",
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    assert "MeshCat preview at http://localhost:7077" in done.stdout


@pytest.mark.slow
def test_ctrl_c_ends_the_preview_with_130():
    """Ctrl-C ends ``preview`` as it ends every other command: exit 130, one line (it
    was exit 0, so a script could not tell a stopped preview from a finished one)."""
    port = free_port_pair()
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "preview",
            str(CELLS / "tape_cylinder_ur10e.yaml"),
            "--port",
            str(port),
        ],
        cwd=REPO,
        env={**os.environ, "PYTHONPATH": str(REPO), "PYTHONUNBUFFERED": "1"},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = process.stdout.readline()
        assert f"MeshCat preview at http://localhost:{port}" in line, process.stderr.read()
        time.sleep(1.0)  # serving: Ctrl-C as a user presses it, not during the print
        process.send_signal(signal.SIGINT)
        code = process.wait(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert code == 130
    assert process.stderr.read().strip().splitlines() == ["interrupted"]


@pytest.mark.slow
def test_a_colliding_plan_writes_its_reports_but_no_program(tmp_path):
    cell = (CELLS / "seal_plate_kr16.yaml").read_text()
    # A block in the plate's plane, beside the nozzle: the plate sweeps through it.
    blocked = cell.replace(
        "obstacles:   # in I",
        "obstacles:   # in I\n"
        "  - {name: intruder, shape: box, size_mm: [20, 20, 20], "
        "pose: {translation: [1.05, 0.05, 0.5025]}}",
    )
    assert blocked != cell
    file = tmp_path / "blocked.yaml"
    file.write_text(blocked)
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "offline_prog", "plan", str(file), "--out", str(out)],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=300,
    )
    assert done.returncode == 1, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "collision: plate vs intruder" in lines[0], lines
    report = json.loads((out / "report.json").read_text())
    assert report["collision_free"] is False and report["feasible"] is False
    # A path: cell is a one-seam job: the failure names the move (here the approach).
    assert (
        report["failure_kind"] == "collision"
        and "collision: plate vs intruder" in (report["failure"])
    )
    assert (out / "collisions.json").is_file() and (out / "preview.html").is_file()
    assert not (out / "programs").exists()


@pytest.mark.slow
def test_collision_avoidance_is_tried_and_reported(tmp_path):
    """A cable duct touching the forearm: the planner re-plans with the other branches
    and tool rotations (the process pose is held in all), keeps the one with the
    most clearance, and the report says which samples needed it and what changed."""
    cell = (CELLS / "weld_seam_irb2400.yaml").read_text().replace(": data/", f": {CELLS}/data/")
    file = tmp_path / "duct.yaml"
    file.write_text(
        cell.replace(
            "obstacles:   # in I",
            "obstacles:   # in I\n"
            "  - {name: cable_duct, shape: sphere, radius_mm: 60, "
            "pose: {translation: [0.695, 0.05, 1.21]}}",
        )
    )
    plan = plan_cell(file)
    record = plan.avoidance
    assert record is not None and record["attempts"] >= 1
    assert record["first_failure"].startswith("collision: link_4 vs cable_duct")
    assert record["samples_that_needed_it"]  # their σ: on the seam or its leads (σ < 0)
    assert record["sigma_m_that_needed_it"][0] >= path_ends(plan.flange)[0] - 1e-12
    first_depth = float(record["first_failure"].split("depth ")[1].split(" mm")[0]) * 1e-3
    assert plan.collisions.min_distance_m >= -first_depth - 1e-9  # never worse
    # No branch or fixed rotation clears the duct: the plan is reported as failed, and
    # the record says so (the resolved case: tests/collision/test_avoidance.py).
    assert record["resolved"] is False and not plan.feasible
    assert plan.failure.startswith("collision:")
