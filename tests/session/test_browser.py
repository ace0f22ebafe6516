"""The session in a real browser (the issue's acceptance): Playwright drives Debian's
Chromium (``executable_path``, no browser download). Open the session, move the X_IT
slider, wait for the new status, compare the scene and status with `plan` of the same
changed cell, Save and Export, check the files; a bad typed value is refused; Ctrl-C
ends the session with 130."""

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix

from offline_prog.config.cell import load_cell
from offline_prog.plan import plan_cell, plan_job
from offline_prog.results.job_folder import write_job_outputs

from browser import WEBGL_ARGS, require_chromium
from conftest import CELLS, REPO
from live_session import free_port_pair

pytestmark = pytest.mark.slow
TIMEOUT_MS = 60_000
MOVE_MM = 20  # the X_IT x slider moved by 20 steps of 1 mm


@pytest.fixture
def session(tmp_path):
    cell = tmp_path / "seal_plate_kr16.yaml"
    shutil.copyfile(CELLS / "seal_plate_kr16.yaml", cell)
    port = free_port_pair()
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "session",
            cell.name,
            "--port",
            str(port),
            "--no-browser",
        ],
        cwd=tmp_path,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    line = process.stdout.readline()
    url = re.search(rf" at (http://localhost:{port}/\?token=[\w-]+) ", line)
    assert url, (line, process.stderr.read())
    hint = process.stdout.readline()
    assert f"ssh -N -L {port}:localhost:{port} -L {port + 1}:localhost:{port + 1}" in hint
    yield tmp_path, cell, url.group(1), process
    if process.poll() is None:
        process.kill()
        process.wait()


def status(page) -> dict:
    """The session's status as the panel page reads it (with the token of its URL)."""
    return page.evaluate(
        "fetch('/status', {headers: {'X-Session-Token': "
        "new URLSearchParams(location.search).get('token')}}).then(r => r.json())"
    )


def wait_for_values(page, values: dict) -> dict:
    """The session's status once it holds ``values`` and shows their plan: each key
    press is its own request, so a plan of the first presses may be current for a
    moment while the last are still on their way."""
    deadline = time.monotonic() + TIMEOUT_MS / 1000
    while True:
        now = status(page)
        held = all(now["values"].get(key) == value for key, value in values.items())
        if (held and now["current"]) or time.monotonic() > deadline:
            assert held and now["current"], (now["values"], now["current"])
            return now
        page.wait_for_timeout(100)


def node_pose(frame, path: list[str]) -> RigidTransform:
    """The pose of a MeshCat scene node in its parent, read from the viewer's three.js."""
    p, q = frame.evaluate(
        """path => { const o = viewer.scene_tree.find(path).object;
                     return [o.position.toArray(), o.quaternion.toArray()]; }""",
        path,
    )
    from pydrake.common.eigen_geometry import Quaternion

    return RigidTransform(RotationMatrix(Quaternion(q[3], q[0], q[1], q[2])), p)


def settled_pose(frame, path: list[str], holds) -> RigidTransform:
    """The node's pose once ``holds(pose)``, or its last one after TIMEOUT_MS: the viewer
    gets the session's drawing over MeshCat's websocket, a moment after the status (a
    busy machine once took longer than a fixed wait)."""
    deadline = time.monotonic() + TIMEOUT_MS / 1000
    while True:
        pose = node_pose(frame, path)
        if holds(pose) or time.monotonic() > deadline:
            return pose
        frame.wait_for_timeout(100)


def test_session_in_the_browser(session):
    pytest.importorskip("playwright.sync_api", reason="pip install playwright (the test extras)")
    from playwright.sync_api import expect, sync_playwright

    folder, cell, url, process = session
    port = int(url.split(":")[2].split("/")[0])
    chromium = require_chromium()
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(
            executable_path=chromium, args=["--no-sandbox", *WEBGL_ARGS[:2]]
        )
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        # The panel itself; the MeshCat frame in it loads while the first plan runs.
        page.goto(url, wait_until="domcontentloaded", timeout=TIMEOUT_MS)
        line = page.locator("#status")
        expect(line).to_have_class("feasible", timeout=TIMEOUT_MS)
        first = status(page)
        assert first["current"] and first["status"]["details"]["ran"][0] == "fit"

        # Move the tool stand 20 mm along x with the slider (keyboard: 1 mm a step).
        slider = page.locator('input[type=range][data-key="X_IT.x"]')
        slider.focus()
        for _ in range(MOVE_MM):
            slider.press("ArrowRight")
        slider.blur()
        expect(line).not_to_have_attribute(
            "data-generation", str(first["shown_generation"]), timeout=TIMEOUT_MS
        )
        now = wait_for_values(page, {"X_IT.x": 1000 + MOVE_MM})
        details = now["status"]["details"]
        assert details["ran"] == ["frames", "scene", "joints", "check"]  # not refitted
        text = line.inner_text()

        # Save: the changed cell next to the original.
        page.click("#save")
        expect(page.locator("#files")).to_contain_text("saved:", timeout=TIMEOUT_MS)
        saved = folder / "seal_plate_kr16-1.yaml"
        assert saved.is_file() and cell.read_text() == (CELLS / cell.name).read_text()
        assert load_cell(saved).tool.X_IT.translation[0] == pytest.approx(1.02, abs=1e-15)
        assert "# Nozzle tip 1.0 m in front of the robot" in saved.read_text()

        # The status is that of `plan` of the changed cell.
        reference = plan_cell(saved)
        assert details["feasible"] == reference.feasible
        assert details["cycle_time_s"] == pytest.approx(reference.trajectory.duration, abs=1e-9)
        assert details["min_distance_m"] == pytest.approx(
            reference.collisions.min_distance_m, abs=1e-9
        )
        margin = np.rad2deg(reference.joints.margin_rad.min())
        assert details["joint_limit_margin_deg"] == pytest.approx(margin, abs=1e-9)
        assert f"cycle {reference.trajectory.duration:.2f} s" in text

        # The scene: the tool at the new X_IT, the part where the plan puts it at σ = 0.
        page.locator("#sigma").fill("0")  # scrub to the start
        page.wait_for_load_state("load", timeout=TIMEOUT_MS)  # the MeshCat frame too
        viewer = next(f for f in page.frames if f.url.startswith(f"http://localhost:{port + 1}"))
        viewer.wait_for_function("typeof viewer !== 'undefined'", timeout=TIMEOUT_MS)

        def at_new_pose(tool: RigidTransform) -> bool:
            return np.allclose(tool.translation(), [1.02, 0.0, 0.5], atol=1e-6)

        tool = settled_pose(viewer, ["drake", "visualizer", "tool", "tool"], at_new_pose)
        assert at_new_pose(tool), tool
        flange = reference.trajectory.flange
        X_IE = RigidTransform(RotationMatrix(flange.R_IE[0]), flange.p_IE[0])
        X_IP = X_IE @ reference.flange.X_PE.inverse()

        def at_start(part: RigidTransform) -> bool:  # where the plan puts it at σ = 0
            return np.allclose(part.translation(), X_IP.translation(), atol=1e-5) and np.allclose(
                part.rotation().matrix(), X_IP.rotation().matrix(), atol=1e-5
            )

        part = settled_pose(viewer, ["drake", "visualizer", "part", "part"], at_start)
        assert at_start(part), part
        ok_path = viewer.evaluate(
            "viewer.scene_tree.find(['drake','visualizer','part','part','session','path',"
            "'0']).object.children.length"
        )
        assert ok_path >= 1  # the path drawn on the part (ok samples in green)

        # Export: the plan folder as `plan` writes it.
        page.click("#export")
        expect(page.locator("#files")).to_contain_text("exported:", timeout=TIMEOUT_MS)
        exported = folder / "out" / "seal_plate_kr16-1"
        expected = folder / "expected"
        write_job_outputs(plan_job(saved), expected)  # a path: cell is a one-seam job
        names = sorted(p.relative_to(expected) for p in expected.rglob("*"))
        assert sorted(p.relative_to(exported) for p in exported.rglob("*")) == names
        ours, theirs = ((f / "trajectory.csv").read_text() for f in (exported, expected))
        assert ours == theirs
        report = json.loads((exported / "report.json").read_text())
        assert report["cell"].endswith("seal_plate_kr16-1.yaml")  # the saved cell

        # Another page in the same browser (MeshCat's, another origin) posts as a web
        # page may without asking (text/plain, no-cors): refused, the tool stays.
        other = browser.new_page()
        other.goto(f"http://localhost:{port + 1}/", wait_until="commit")  # its origin only
        other.evaluate(
            """port => fetch(`http://localhost:${port}/set`, {method: "POST", mode: "no-cors",
                 headers: {"Content-Type": "text/plain"},
                 body: JSON.stringify({key: "X_IT.x", value: 1234})})""",
            port,
        )
        assert status(page)["values"]["X_IT.x"] == 1000 + MOVE_MM
        other.goto(f"http://localhost:{port}/")  # the panel without the printed token
        assert "open the URL the session printed" in other.inner_text("body")
        other.close()

        # A bad typed value: refused in the status line, the session goes on.
        speed = page.locator('input.num[data-key="speed"]')
        speed.fill("0")
        speed.press("Enter")
        expect(page.locator("#message")).to_contain_text("refused speed", timeout=TIMEOUT_MS)
        assert status(page)["values"]["speed"] == 100.0
        browser.close()
    assert process.poll() is None  # still serving
    process.send_signal(signal.SIGINT)
    assert process.wait(timeout=30) == 130
    assert re.search(r"interrupted", process.stderr.read())
