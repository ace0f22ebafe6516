"""``offline-prog place`` end to end: a placement out of reach becomes a feasible one
that ``plan`` accepts with the cycle time placement.json promised; the same seed gives
the same placement in one process and on a 2-worker LocalCluster; an unreachable
scheduler and Ctrl-C end with one line."""

import json
import os
import queue
import signal
import subprocess
import sys
import threading
import time

import pytest

from offline_prog.cli import main
from offline_prog.config.cell import load_cell, transform
from offline_prog.plan import plan_job

from conftest import CELLS

DEMO = CELLS / "placement" / "seal_out_of_reach_kr16.yaml"
CONTRACT = {
    "X_IT",
    "X_PE",
    "feasible",
    "cycle_time_s",
    "joint_limit_margin_deg",
    "singularity_margin_deg",
    "clearance_mm",
    "reason",
}


def assert_stands_on_the_floor(placed):
    """Every stand of a placed.yaml has its foot on the floor: on z = 0 of I, where the
    demo cells stand it (their floor slab's top is 1 mm under it), whatever its length."""
    cell = load_cell(placed)
    floor = next(o for o in cell.obstacles if o.name == "floor")
    floor_top = transform(floor.pose).translation()[2] + 0.5e-3 * floor.size_mm[2]
    assert cell.place.moves_with_tool
    for name in cell.place.moves_with_tool:
        stand = next(o for o in cell.obstacles if o.name == name)
        X_IO = transform(stand.pose)
        length = 1e-3 * (stand.size_mm[2] if stand.shape == "box" else stand.length_mm)
        assert abs(X_IO.rotation().matrix()[2, 2]) == pytest.approx(1.0)  # upright
        foot = X_IO.translation()[2] - length / 2
        assert foot == pytest.approx(0.0, abs=1e-6), (name, foot)
        assert 0.0 <= foot - floor_top <= 1e-3 + 1e-6  # on the floor
        top = X_IO.translation()[2] + length / 2
        tool_z = cell.tool.X_IT.translation[2]
        assert top == pytest.approx(tool_z - 0.2, abs=1e-6)  # 0.2 m under the nozzle's tip


def small_search(tmp_path, screen_points: int = 100):
    """The demo with a coarse screen (3 levels per axis), written next to a copy of it."""
    file = tmp_path / "cells" / "out_of_reach.yaml"
    file.parent.mkdir()
    file.write_text(
        DEMO.read_text().replace("seed: 0", f"seed: 0\n  screen_points: {screen_points}")
    )
    return file


def test_no_feasible_placement_is_exit_1_with_the_closest_reason_and_outputs(tmp_path, capsys):
    file = small_search(tmp_path, screen_points=4).parent / "out_of_reach.yaml"
    file.write_text(file.read_text().replace("x: [700, 1900]", "x: [2300, 2600]"))
    out = tmp_path / "out"
    code = main(["place", str(file), "--out", str(out), "--budget", "3", "--workers", "0"])
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert code == 1 and len(err) == 1, err
    assert "no feasible placement in 1 candidate planned (32 by reach screened out)" in err[0]
    assert "out of reach" in err[0]
    data = json.loads((out / "placement.json").read_text())
    assert not data["best"]["feasible"] and data["best"]["failure"] == "out_of_reach"
    assert data["search"]["failures"] == {"out_of_reach": 1}  # the cell as given
    assert data["screening"]["fates"]["reach"] == 32  # the grid: 2 levels ^ 4 axes, 2 grasps
    assert not (out / "best_preview.html").exists()
    said = captured.out.strip().splitlines()[-1]
    assert said.endswith(f"wrote into {out}: placed.yaml, placement.html, placement.json")
    assert_stands_on_the_floor(out / "placed.yaml")


@pytest.mark.slow  # ~25 s: two searches of 10 candidates, a LocalCluster, one plan
def test_place_makes_an_out_of_reach_cell_feasible_the_same_on_any_workers(tmp_path, capsys):
    file = small_search(tmp_path)
    serial, dask = tmp_path / "serial", tmp_path / "dask"
    assert main(["place", str(file), "--out", str(serial), "--budget", "10", "--workers", "0"]) == 0
    said = capsys.readouterr().out.strip().splitlines()[-1]  # what it wrote, preview too
    assert said.endswith(
        f"wrote into {serial}: best_preview.html, placed.yaml, placement.html, placement.json"
    )
    assert main(["place", str(file), "--out", str(dask), "--budget", "10", "--workers", "2"]) == 0
    ours, theirs = (json.loads((d / "placement.json").read_text()) for d in (serial, dask))
    assert ours["best"] == {**theirs["best"], "evaluation_s": ours["best"]["evaluation_s"]}
    assert theirs["engine"]["workers"] == 2 and theirs["engine"]["scheduler"] == "LocalCluster"
    assert ours["engine"]["candidates_evaluated"] == 10
    best = ours["best"]
    assert set(best) >= CONTRACT and best["feasible"] and best["reason"] == ""
    assert not ours["baseline"]["feasible"] and "out of reach" in ours["baseline"]["reason"]
    assert ours["baseline"]["failure"] == "out_of_reach" and best["failure"] == ""
    assert all(set(c) >= CONTRACT for c in ours["candidates"])
    assert ours["candidates"][0]["X_IT"] == best["X_IT"]
    # placed.yaml: the cell's text (comments kept) with the best placement; plan agrees.
    placed = (serial / "placed.yaml").read_text()
    assert "# Deliberately poor: 2.2 m from the robot base" in placed
    assert_stands_on_the_floor(serial / "placed.yaml")
    assert_stands_on_the_floor(dask / "placed.yaml")
    description = load_cell(serial / "placed.yaml").description  # says what was placed
    assert description.startswith("Placed by offline-prog place from out_of_reach.yaml")
    assert "nozzle_stand 500 -> " in description and f"{best['cycle_time_s']:.2f} s" in description
    plan = plan_job(serial / "placed.yaml")  # a path: cell: a one-seam job, home to home
    assert plan.feasible
    assert plan.samples.t[-1] == pytest.approx(best["cycle_time_s"], abs=1e-9)
    assert list(plan.cell.tool.X_IT.translation) == best["X_IT"]["translation"]
    page = (serial / "placement.html").read_text()
    assert '<svg id="search-map"' in page and 'src="best_preview.html"' in page
    assert (serial / "best_preview.html").stat().st_size > 10_000


@pytest.mark.slow  # the scheduler's connect timeout: 5 s
def test_an_unreachable_scheduler_is_one_line_exit_2_within_seconds(tmp_path, capsys):
    start = time.monotonic()
    code = main(
        ["place", str(DEMO), "--out", str(tmp_path / "o"), "--scheduler", "tcp://127.0.0.1:9"]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "tcp://127.0.0.1:9" in err[0] and "--scheduler" in err[0] and "cannot reach" in err[0]
    assert time.monotonic() - start < 15
    assert not (tmp_path / "o").exists()


@pytest.mark.slow  # a LocalCluster started, then interrupted
def test_ctrl_c_stops_the_workers_exit_130_one_line_no_folder(tmp_path):
    file = small_search(tmp_path, screen_points=1000)
    out = tmp_path / "o"
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "place",
            str(file),
            "--out",
            str(out),
            "--workers",
            "2",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    # Interrupt it once its workers take candidates: its first screening line (piped,
    # the command prints its progress as lines on stdout) comes after the LocalCluster's
    # workers started and loaded the cell and a candidate was screened on one; a signal
    # while a worker still starts (dask's Status.init) is not what this test is about.
    lines = queue.Queue()
    reader = threading.Thread(target=lambda: [lines.put(line) for line in process.stdout])
    reader.start()
    deadline, line = time.monotonic() + 180, ""
    while not line.startswith("place: screening") and process.poll() is None:
        try:
            line = lines.get(timeout=max(0.0, deadline - time.monotonic()))
        except queue.Empty:
            break
    assert line.startswith("place: screening"), (line, process.poll())
    group = subprocess.run(["pgrep", "-g", str(process.pid)], capture_output=True, text=True)
    assert len(group.stdout.split()) >= 3, "the command and its 2 worker processes"
    os.killpg(process.pid, signal.SIGINT)  # what a terminal's Ctrl-C does
    try:
        process.wait(timeout=30)
        err = process.stderr.read()  # one line (stdout: the reader's)
    finally:
        process.kill()
        reader.join(timeout=30)
    assert process.returncode == 130, err
    assert err.strip().splitlines()[-1] == "interrupted", err
    assert not out.exists() and not list(tmp_path.glob(".offline_prog*"))
    deadline = time.monotonic() + 15  # the workers finish their task and exit
    while time.monotonic() < deadline:
        left = subprocess.run(["pgrep", "-g", str(process.pid)], capture_output=True, text=True)
        if not left.stdout.strip():
            break
        time.sleep(0.5)
    assert left.stdout.strip() == "", "worker processes outlived the interrupt"


@pytest.mark.slow  # ~40 s: six whole-job plans and the plan of placed.yaml
def test_a_whole_job_is_placed_and_plan_agrees(tmp_path):
    source = CELLS / "placement" / "seal_job_far_kr16.yaml"
    file = tmp_path / "job.yaml"
    file.write_text(source.read_text().replace("seed: 0", "seed: 0\n  screen_points: 100"))
    out = tmp_path / "out"
    assert main(["place", str(file), "--out", str(out), "--budget", "6", "--workers", "0"]) == 0
    data = json.loads((out / "placement.json").read_text())
    best, base = data["best"], data["baseline"]
    assert base["feasible"] and best["feasible"]
    assert best["cycle_time_s"] <= base["cycle_time_s"]
    assert best["air_time_s"] > 0  # approach, retract and links are part of the cycle
    from offline_prog.plan import plan_job

    job = plan_job(out / "placed.yaml")
    assert job.feasible
    assert_stands_on_the_floor(out / "placed.yaml")
    assert job.samples.t[-1] - job.samples.t[0] == pytest.approx(best["cycle_time_s"], abs=1e-9)


@pytest.fixture
def scheduler(tmp_path):
    """A Dask scheduler on this machine (no workers yet): its address."""
    file = tmp_path / "scheduler.json"
    process = subprocess.Popen(
        [sys.executable, "-m", "dask", "scheduler", "--scheduler-file", str(file), "--port", "0"]
        + ["--dashboard-address", ":0"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 60
    while not file.exists() and time.monotonic() < deadline:
        time.sleep(0.2)
    time.sleep(0.5)  # written whole
    try:
        yield json.loads(file.read_text())["address"]
    finally:
        process.kill()
        process.wait()


def _worker(address: str) -> subprocess.Popen:
    """A worker process without a nanny (killed, it stays dead)."""
    return subprocess.Popen(
        [sys.executable, "-m", "dask", "worker", address, "--nthreads", "1", "--no-nanny"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


@pytest.mark.slow  # a scheduler started; the wait for a worker: 5 s
def test_a_scheduler_without_workers_is_one_line_exit_2(tmp_path, capsys, scheduler):
    code = main(["place", str(DEMO), "--out", str(tmp_path / "o"), "--scheduler", scheduler])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert scheduler in err[0] and "no worker joined it" in err[0]
    assert not (tmp_path / "o").exists()


@pytest.mark.slow  # ~2 min: a scheduler, two workers, a search, and the same search here
def test_a_worker_killed_mid_run_leaves_the_same_best_placement(tmp_path, scheduler):
    file = small_search(tmp_path)
    workers = [_worker(scheduler) for _ in range(2)]
    out = tmp_path / "cluster"
    command = [sys.executable, "-m", "offline_prog", "place", str(file), "--out", str(out)]
    process = subprocess.Popen(
        [*command, "--budget", "8", "--scheduler", scheduler],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        for line in process.stdout:  # piped: the progress lines
            if "planning candidates in full 1/" in line:
                workers[0].kill()  # mid-run: the other plans are still to come
                break
        _, err = process.communicate(timeout=600)
    finally:
        process.kill()
        for worker in workers:
            worker.kill()
            worker.wait()
    assert workers[0].returncode is not None and workers[0].returncode != 0
    assert process.returncode == 0, err
    serial = tmp_path / "serial"
    assert main(["place", str(file), "--out", str(serial), "--budget", "8", "--workers", "0"]) == 0
    ours, theirs = (json.loads((d / "placement.json").read_text()) for d in (out, serial))
    assert ours["best"] == {**theirs["best"], "evaluation_s": ours["best"]["evaluation_s"]}
    assert_stands_on_the_floor(out / "placed.yaml")
