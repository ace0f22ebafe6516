"""The gripper in the collision check: a gripper that hits the tool stand is a collision
naming the gripper; what holds what is listed, not checked; everything else is checked."""

import json
import subprocess
import sys

import numpy as np
import pytest
from gripper_clearance import GRIPPER_CLEARANCE_TOL_M, flange_poses, gripper_clearance

from offline_prog.collision.check import check_trajectory
from offline_prog.config.cell import load_cell
from offline_prog.scene.drake_cell import build_cell_model

from conftest import CELLS, REPO

DEMO = "seal_plate_kr16"
# A probe hanging 300 mm below the flange, 120 mm off its axis: through the plate (the
# gripper's own part: not checked) and, while the nozzle seals the plate's end near it,
# down into the nozzle's stand (its top 200 mm below the nozzle tip).
PROBE = (
    "    - {name: gripper_probe, shape: cylinder, radius_mm: 10, length_mm: 300,\n"
    "       pose: {translation: [0.120, 0, 0.250]}}\n"
)


def probe_cell(tmp_path):
    text = (CELLS / f"{DEMO}.yaml").read_text(encoding="utf-8")
    marker = "    # four suction cups"
    assert marker in text
    file = tmp_path / "probe.yaml"
    file.write_text(text.replace(marker, PROBE + marker), encoding="utf-8")
    return file


def planned_joints(folder):
    """(t (N,), q (N, 6)) of a plan folder's trajectory.csv."""
    header = (folder / "trajectory.csv").read_text(encoding="utf-8").split("\n", 1)[0]
    names = header.split(",")
    columns = [names.index(c) for c in ("t", "q1", "q2", "q3", "q4", "q5", "q6")]
    table = np.loadtxt(folder / "trajectory.csv", delimiter=",", skiprows=1, usecols=columns)
    return table[:, 0], table[:, 1:]


def test_a_gripper_hitting_the_stand_is_a_collision_naming_the_gripper(tmp_path, planned_job):
    """The demo's planned motion with a longer gripper: the check finds the probe in the
    nozzle's stand and its message names the gripper."""
    job, folder = planned_job(DEMO)
    t, q = planned_joints(folder)
    file = probe_cell(tmp_path)
    cell = load_cell(file)
    scene = build_cell_model(cell, file, job.robot)
    result = check_trajectory(scene, q, t, np.zeros(len(t)), clearance=cell.motion.clearance)
    assert not result.collision_free
    assert result.message.startswith("collision: gripper_probe (gripper) vs nozzle_stand at σ")
    first = result.first_contact
    assert (first.a, first.b, first.group) == ("gripper_probe", "nozzle_stand", "gripper-obstacle")
    depth = max(c.worst.depth_m for c in result.collisions if c.a == "gripper_probe")
    assert depth > 0.05  # the probe reaches 100 mm below the stand's top
    # The same motion without the probe is clear (the demo as planned).
    demo = build_cell_model(load_cell(CELLS / f"{DEMO}.yaml"), CELLS / f"{DEMO}.yaml", job.robot)
    clear = check_trajectory(demo, q, t, np.zeros(len(t)), clearance=cell.motion.clearance)
    assert clear.collision_free, clear.message


def test_what_holds_what_is_listed_and_the_rest_is_checked(planned_job):
    """report.json lists the gripper on the flange link and the part in the gripper with
    their reasons; collisions.json has the gripper against the tool, the stand and the
    other links, and none of the listed pairs."""
    _, folder = planned_job(DEMO)
    report = json.loads((folder / "report.json").read_text(encoding="utf-8"))
    held = {tuple(h["pair"]): h["reason"] for h in report["held_contacts_not_checked"]}
    assert held[("gripper_adapter", "link_6")] == "the gripper is mounted on the flange of link_6"
    assert held[("plate", "gripper_cup_1")] == "the gripper holds the part"
    assert held[("plate", "link_6")].startswith("the part is held at the flange of link_6")
    owners = {name.split("_")[0] for pair in held for name in pair}
    assert owners == {"gripper", "plate", "link"}  # nothing of the tool or obstacles
    collisions = json.loads((folder / "collisions.json").read_text(encoding="utf-8"))
    checked = {(p["a"], p["b"]): p for p in collisions["pairs"]}
    assert not set(checked) & set(held)
    for pair in [
        ("gripper_adapter", "link_5"),
        ("gripper_frame", "link_4"),
        ("gripper_cup_1", "tool_tip"),
        ("gripper_body", "nozzle_stand"),
        ("gripper_frame", "fence_post"),
    ]:
        assert pair in checked, pair
        assert checked[pair]["distance_m"] >= collisions["clearance_m"]
    assert [h for h in collisions["held_contacts"] if h[0] == "gripper_adapter"] == [
        ["gripper_adapter", "link_6", "the gripper is mounted on the flange of link_6"]
    ]


def test_the_second_library_sees_the_probe(tmp_path, planned_job):
    """The independent check (python-fcl on trajectory.csv) finds the probe in the stand
    too: it can fail."""
    _, folder = planned_job(DEMO)
    distance, pair, _ = gripper_clearance(probe_cell(tmp_path), folder / "trajectory.csv")
    assert distance < -0.05 and pair == ("gripper_probe", "nozzle_stand")


def test_flange_poses_read_back_the_planned_flange(planned_job):
    """The independent check's flange poses (trajectory.csv) are Drake's X_IE at the
    planned joints: the second library sees the motion the planner checked."""
    job, folder = planned_job(DEMO)
    _, q = planned_joints(folder)
    X = flange_poses(folder / "trajectory.csv")
    cell = load_cell(CELLS / f"{DEMO}.yaml")
    scene = build_cell_model(cell, CELLS / f"{DEMO}.yaml", job.robot)
    for i in np.linspace(0, len(q) - 1, 25).astype(int):
        np.testing.assert_allclose(X[i], scene.X_IE(q[i]).GetAsMatrix4(), atol=1e-8)


@pytest.mark.slow
def test_plan_stops_naming_the_gripper(tmp_path):
    """``plan`` on the cell with the probe: exit 1, one line naming the gripper and the
    stand, the report written, no programs."""
    out = tmp_path / "out"
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "plan",
            str(probe_cell(tmp_path)),
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=900,
    )
    assert done.returncode == 1, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "(gripper) vs nozzle_stand" in lines[0], lines
    report = json.loads((out / "report.json").read_text(encoding="utf-8"))
    assert report["failure_kind"] == "collision" and "gripper_probe (gripper)" in report["failure"]
    assert not (out / "programs").exists()


@pytest.mark.slow
@pytest.mark.parametrize("name", ["seal_far_kr16", "seal_job_far_kr16"])
def test_placement_demos_plan_with_their_grippers(tmp_path, name):
    """The placement demos that plan as given still do with their grippers, and the
    gripper keeps the clearance by the second library."""
    cell = CELLS / "placement" / f"{name}.yaml"
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "offline_prog", "plan", str(cell), "--out", str(out)],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=1800,
    )
    assert done.returncode == 0, done.stderr
    assert "payload" not in done.stdout  # no payload warning: the cell gives the masses
    distance, pair, row = gripper_clearance(cell, out / "trajectory.csv")
    assert distance >= load_cell(cell).motion.clearance - GRIPPER_CLEARANCE_TOL_M, (pair, row)


def test_a_gripper_mesh_is_a_shape_in_E_with_its_mass_properties(tmp_path):
    """``gripper.mesh`` (here a box in mm, off the flange axis) is the shape "gripper" on
    the gripper body, posed in E; its centre of mass is the box's; a placement worker
    gets the file."""
    import trimesh

    from offline_prog.placement.payload import cell_payload, data_file_keys
    from offline_prog.robot.model import load_robot
    from offline_prog.scene.payload import payload_record

    box = trimesh.creation.box([80, 60, 40])
    box.apply_translation([10, 0, 20])
    box.export(tmp_path / "gripper.stl")
    text = (CELLS / f"{DEMO}.yaml").read_text(encoding="utf-8")
    start, end = text.index("\ngripper:") + 1, text.index("\npart:\n") + 1
    gripper = "gripper:\n  mass_kg: 2\n  mesh: gripper.stl\n  mesh_units: mm\n"
    file = tmp_path / "mesh.yaml"
    file.write_text(text[:start] + gripper + text[end:], encoding="utf-8")
    cell = load_cell(file)
    scene = build_cell_model(cell, file, load_robot(cell.robot.model))
    (label,) = [lb for lb in scene.labels.values() if lb.owner == "gripper"]
    assert (label.name, label.body) == ("gripper", "gripper")
    inspector = scene.diagram.scene_graph().model_inspector()
    (g,) = [g for g, lb in scene.labels.items() if lb.owner == "gripper"]
    X_EG = inspector.GetPoseInFrame(g)  # the mesh's frame is E
    np.testing.assert_allclose(X_EG.GetAsMatrix4(), np.eye(4), atol=1e-12)
    record = payload_record(cell, file)
    np.testing.assert_allclose(record["gripper_com_E_m"], [0.01, 0, 0.02], atol=1e-9)
    assert data_file_keys(cell)["gripper.mesh"] == "gripper.stl"
    assert any(name.endswith("gripper.stl") for name, _ in cell_payload(file, cell).files)
