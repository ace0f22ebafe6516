"""Collision checks (collision, geometry, drake_cell shapes) on swept cells and the demos."""

import json
from pathlib import Path

import numpy as np
import pytest
import trimesh
from pydrake.math import RigidTransform, RollPitchYaw

from offline_prog.collision.check import PRUNE_MARGIN_M, check_trajectory, write_collisions_json
from offline_prog.config.cell import ShapeConfig
from offline_prog.plan import plan_cell
from offline_prog.robot.model import load_robot
from offline_prog.scene.drake_cell import build_cell_model, build_drake_cell
from offline_prog.scene.exact_distance import bounding_radius, exact_distance, exact_shape
from offline_prog.scene.shapes import CellShape, ShapeError, cell_geometry, load_shape, mesh_shape

DATA = Path(__file__).resolve().parents[2] / "cells"
CLEARANCE_M = 0.005
EXACT_TOL_M = 1e-6  # FCL against analytic distances [m]
DRAKE_TOL_M = 1e-6  # Drake's primitive distances against analytic ones [m]
X_PE = RigidTransform(RollPitchYaw(np.pi, 0.0, 0.0), [0.0, 0.0, 0.1])  # flange 0.1 m above P
X_IT = RigidTransform(RollPitchYaw(np.pi / 2, 0.0, 0.0), [1.0, -1.0, 0.5])  # out of the way
SWEEP_RAD = 0.6  # joint 1 turns ±this about the start pose
BALL_R_M = 0.02


@pytest.fixture(scope="module", autouse=True)
def mesh_cache(tmp_path_factory):
    """Keep CoACD's pieces and converted meshes out of the user's cache."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("OFFLINE_PROG_CACHE", str(tmp_path_factory.mktemp("cache")))
        yield


@pytest.fixture(scope="module")
def kr16():
    return load_robot("kuka_kr16_2")


def sweep(robot, n: int, half_angle: float = SWEEP_RAD):
    """q (n, 6) [rad] turning joint 1 about a pose with the flange 1 m out, pointing down,
    and t (n,) [s]."""
    X_BE = RigidTransform(RollPitchYaw(np.pi, 0.0, 0.0), [1.0, 0.0, 0.7]).GetAsMatrix4()
    solutions = robot.inverse(X_BE[None])[0]
    inside = np.all((solutions >= robot.q_lower) & (solutions <= robot.q_upper), axis=1)
    q0 = solutions[np.flatnonzero(inside & ~np.any(np.isnan(solutions), axis=1))[0]]
    q = np.tile(q0, (n, 1))
    q[:, 0] += np.linspace(-half_angle, half_angle, n)
    return q, np.linspace(0.0, 2.0, n)


def part_poses(cell, q) -> list[RigidTransform]:
    return [cell.X_IE(q_i) @ X_PE.inverse() for q_i in q]


def arc_length(poses) -> np.ndarray:
    p = np.array([X.translation() for X in poses])
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])


def box(name, size, X=None):
    return CellShape(name, "box", X or RigidTransform(), tuple(size))


def ball(name, p_I, r=BALL_R_M):
    return CellShape(name, "sphere", RigidTransform(p_I), (r,))


def box_sphere_distance(X_IO, size, p_IC, r) -> float:
    """Analytic signed distance [m] of a box O (size [m], posed X_IO) and a sphere
    (centre p_IC, radius r [m])."""
    p_OC = X_IO.inverse() @ p_IC
    outside = np.maximum(np.abs(p_OC) - np.asarray(size) / 2, 0.0)
    inside = min(0.0, np.max(np.abs(p_OC) - np.asarray(size) / 2))
    return float(np.linalg.norm(outside) + inside - r)


PLATE = (0.2, 0.15, 0.01)  # in P, from its underside up
X_PPlate = RigidTransform([0.0, 0.0, 0.005])


def plate_cell(robot, obstacles, part=None, **kwargs):
    part = part or [box("plate", PLATE, X_PPlate)]
    return build_drake_cell(
        robot,
        X_IB=RigidTransform(),
        X_IT=X_IT,
        X_PE=X_PE,
        part_shapes=part,
        obstacles=obstacles,
        **kwargs,
    )


def test_obstacle_in_the_path_collides_at_the_right_sigma_with_the_right_pair(kr16):
    q, t = sweep(kr16, 401)
    probe = plate_cell(kr16, [])
    poses = part_poses(probe, q)
    sigma = arc_length(poses)
    p_IC = (poses[240] @ X_PPlate).translation()  # the plate's centre at sample 240
    cell = plate_cell(kr16, [ball("ball", p_IC)])
    result = check_trajectory(cell, q, t, sigma, clearance=CLEARANCE_M)
    analytic = [box_sphere_distance(X @ X_PPlate, PLATE, p_IC, BALL_R_M) for X in poses]
    expected = int(np.flatnonzero(np.array(analytic) < 0.0)[0])
    first = result.first_contact
    assert not result.collision_free
    assert (first.a, first.b, first.group) == ("plate", "ball", "part-obstacle")
    assert abs(first.sample - expected) <= 1
    assert abs(first.sigma_m - sigma[expected]) <= np.diff(sigma).max()
    assert result.message.startswith(f"collision: plate vs ball at σ = {first.sigma_m:.4f} m")
    assert result.min_distance_m == pytest.approx(min(analytic), abs=DRAKE_TOL_M)


def test_moving_the_obstacle_1_cm_away_clears_it(kr16):
    q, t = sweep(kr16, 401)
    poses = part_poses(plate_cell(kr16, []), q)
    sigma = arc_length(poses)
    below = poses[200].translation() - [0.0, 0.0, BALL_R_M - 0.003]  # 3 mm into the plate
    hit_cell = plate_cell(kr16, [ball("ball", below)])
    hit = check_trajectory(hit_cell, q, t, sigma, clearance=CLEARANCE_M)
    assert not hit.collision_free and hit.message.startswith("collision: plate vs ball")
    assert hit.min_distance_m == pytest.approx(-0.003, abs=DRAKE_TOL_M)
    assert hit.collisions[0].worst.depth_m == pytest.approx(0.003, abs=DRAKE_TOL_M)
    assert 200 in hit.samples_in_collision
    one = check_trajectory(hit_cell, q[200:201], t[:1], sigma[:1], clearance=CLEARANCE_M)
    assert one.min_distance_m == pytest.approx(-0.003, abs=DRAKE_TOL_M)
    with pytest.raises(ValueError, match=r"^q: expected \(N, 6\)"):
        check_trajectory(hit_cell, q[:, :5], t, sigma, clearance=CLEARANCE_M)
    with pytest.raises(ValueError, match=r"^clearance: "):
        check_trajectory(hit_cell, q, t, sigma, clearance=-1.0)
    moved = below - [0.0, 0.0, 0.01]
    clear = check_trajectory(
        plate_cell(kr16, [ball("ball", moved)]), q, t, sigma, clearance=CLEARANCE_M
    )
    assert clear.collision_free and clear.message == "" and clear.collisions == []
    assert clear.min_distance_m == pytest.approx(0.007, abs=DRAKE_TOL_M)
    assert (clear.closest.a, clear.closest.b) == ("plate", "ball")


def test_a_thin_plate_between_two_samples_is_not_tunnelled_through(kr16):
    q, t = sweep(kr16, 9)  # 0.15 rad per step: the part jumps ~150 mm
    small = [box("block", (0.04, 0.04, 0.01), X_PPlate)]
    probe = plate_cell(kr16, [], part=small)
    poses = part_poses(probe, q)
    q_mid = (q[4] + q[5]) / 2
    X_IP_mid = probe.X_IE(q_mid) @ X_PE.inverse()
    tangent = poses[5].translation() - poses[4].translation()
    yaw = np.arctan2(tangent[1], tangent[0])
    X_IW = RigidTransform(RollPitchYaw(0.0, 0.0, yaw), (X_IP_mid @ X_PPlate).translation())
    wall = box("wall", (0.001, 0.06, 0.06), X_IW)  # 1 mm thick, across the motion
    cell = plate_cell(kr16, [wall], part=small)
    centres = [(X @ X_PPlate).translation() for X in poses]
    samples = [box_sphere_distance(X_IW, (0.001, 0.06, 0.06), p, 0.0) for p in centres]
    half_diagonal = np.linalg.norm([0.02, 0.02, 0.005])
    assert min(samples) - half_diagonal > 0.04  # every sample alone is far from the wall
    result = check_trajectory(cell, q, t, arc_length(poses), clearance=CLEARANCE_M)
    assert not result.collision_free
    assert (result.first_contact.a, result.first_contact.b) == ("block", "wall")
    assert 4 < result.first_contact.sample < 5
    assert result.stats["substeps"] > 0


def test_pruned_check_finds_every_sample_a_full_check_finds(kr16, rng):
    """Against Drake's distances of every pair at every sample (no pruning)."""
    q, t = sweep(kr16, 201)
    poses = part_poses(plate_cell(kr16, []), q)
    sigma = arc_length(poses)
    verdicts, exact_cases = [], 0
    for _ in range(8):
        near = [poses[k].translation() + rng.uniform(-0.1, 0.1, 3) for k in rng.integers(0, 201, 4)]
        cell = plate_cell(kr16, [ball(f"ball_{i}", p) for i, p in enumerate(near)])
        result = check_trajectory(cell, q, t, sigma, clearance=CLEARANCE_M)
        context = cell.diagram.CreateDefaultContext()
        scene_graph = cell.diagram.scene_graph()
        full = []
        for q_i in q:
            cell.plant.SetPositions(cell.plant.GetMyMutableContextFromRoot(context), q_i)
            query = scene_graph.get_query_output_port().Eval(
                scene_graph.GetMyContextFromRoot(context)
            )
            full.append(min(r.distance for r in query.ComputeSignedDistancePairwiseClosestPoints()))
        full = np.array(full)
        assert set(np.flatnonzero(full < CLEARANCE_M)) <= set(result.samples_in_collision)
        assert result.min_distance_m <= full.min() + DRAKE_TOL_M
        assert result.collision_free == (result.min_distance_m >= CLEARANCE_M)
        if full.min() < CLEARANCE_M + PRUNE_MARGIN_M and not result.stats["substeps"]:
            assert result.min_distance_m == pytest.approx(full.min(), abs=DRAKE_TOL_M)
        exact_cases += full.min() < CLEARANCE_M + PRUNE_MARGIN_M and not result.stats["substeps"]
        verdicts.append(result.collision_free)
    assert verdicts.count(True) and verdicts.count(False) and exact_cases


def l_bracket(tmp_path) -> Path:
    """An L-shaped bracket (arms 200 mm, 30 mm thick, 50 mm high) as an STL in mm."""
    a, w = 200.0, 30.0
    outline = np.array([[0, 0], [a, 0], [a, w], [w, w], [w, a], [0, a]], dtype=float)
    triangles = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 5], [3, 4, 5]])
    mesh = trimesh.creation.extrude_triangulation(outline, triangles, 50.0)
    file = tmp_path / "l_bracket.stl"
    mesh.export(file)
    return file


def test_concave_part_passes_where_its_convex_hull_would_collide(kr16, tmp_path):
    bracket = mesh_shape("bracket", l_bracket(tmp_path), 1e-3)
    assert bracket.mesh.is_watertight and len(bracket.pieces) >= 2
    q, t = sweep(kr16, 101, half_angle=0.01)  # ±10 mm at the part
    poses = part_poses(plate_cell(kr16, []), q)
    p_PC = np.array([0.1, 0.1, 0.025])  # in the L's notch: 70 mm from both arms
    p_IC = poses[50] @ p_PC
    cell = plate_cell(kr16, [ball("ball", p_IC, 0.01)], part=[bracket])
    hull = bracket.mesh.convex_hull
    assert all(hull.contains([X.inverse() @ p_IC])[0] for X in poses)  # hull would collide
    result = check_trajectory(cell, q, t, arc_length(poses), clearance=CLEARANCE_M, n_worst=99)
    assert result.collision_free, result.message
    pair = next(p for p in result.pairs if (p.a, p.b) == ("bracket", "ball"))
    assert pair.distance_m > 0.04 and pair.exact_distance_m > 0.04  # 60 mm ± the sweep


@pytest.mark.parametrize("name", ["seal_plate_kr16", "weld_seam_irb2400", "tape_cylinder_ur10e"])
def test_demo_cells_with_geometry_are_clear_and_list_the_tool_contact(name, tmp_path):
    plan = plan_cell(DATA / f"{name}.yaml")
    cell = build_cell_model(plan.cell, plan.cell_file, plan.robot)
    traj, clearance = plan.trajectory, plan.cell.motion.clearance
    result = check_trajectory(cell, plan.joints.q, traj.t, traj.s, clearance=clearance)
    allowed = [tuple(pair) for pair in plan.cell.allowed_contact]
    assert result.collision_free, result.message
    assert result.allowed == allowed and result.min_distance_m >= clearance
    checked = {(p.a, p.b) for p in result.pairs} | {(p.b, p.a) for p in result.pairs}
    assert not checked & set(allowed)
    assert {"part-robot", "tool-robot", "robot-self", "part-tool"} <= {
        p.group for p in result.pairs
    }
    write_collisions_json(result, tmp_path / "collisions.json")
    saved = json.loads((tmp_path / "collisions.json").read_text())
    assert saved["collision_free"] and saved["allowed"] == [list(pair) for pair in allowed]
    # Without the tool-on-part contact allowed, that contact is what the check reports.
    geometry = cell_geometry(plan.cell, plan.cell_file)
    unfiltered = build_drake_cell(
        plan.robot,
        X_IB=cell.X_IB,
        X_IT=cell.X_IT,
        X_PE=cell.X_PE,
        part_shapes=geometry.part,
        tool_shapes=geometry.tool,
        obstacles=geometry.obstacles,
        allowed_contact=allowed[1:],
    )
    touching = check_trajectory(unfiltered, plan.joints.q, traj.t, traj.s, clearance=clearance)
    assert not touching.collision_free
    assert {touching.closest.a, touching.closest.b} == set(allowed[0])
    assert f"{touching.closest.a} vs {touching.closest.b}" in touching.message


def test_exact_distances_match_the_analytic_ones(rng):
    for _ in range(50):
        X_IA = RigidTransform(RollPitchYaw(rng.uniform(-np.pi, np.pi, 3)), rng.uniform(-1, 1, 3))
        p_IC = rng.uniform(-1, 1, 3)
        r_a, r_b = rng.uniform(0.01, 0.2, 2)
        spheres = exact_distance(
            exact_shape("sphere", (r_a,), None),
            X_IA,
            exact_shape("sphere", (r_b,), None),
            RigidTransform(p_IC),
        )
        expected = np.linalg.norm(p_IC - X_IA.translation()) - r_a - r_b
        assert spheres == pytest.approx(expected, abs=EXACT_TOL_M)
        size = tuple(rng.uniform(0.05, 0.5, 3))
        p_IC = X_IA @ (np.asarray(size) / 2 + rng.uniform(0.01, 0.3, 3))  # outside, off a corner
        expected = box_sphere_distance(X_IA, size, p_IC, 0.005)
        small = exact_shape("sphere", (0.005,), None)
        for solid in (
            exact_shape("box", size, None),
            exact_shape("mesh", (), trimesh.creation.box(extents=size)),
        ):
            d = exact_distance(solid, X_IA, small, RigidTransform(p_IC))
            assert d == pytest.approx(expected, abs=EXACT_TOL_M)
    inside = exact_distance(
        exact_shape("mesh", (), trimesh.creation.box(extents=(0.2, 0.2, 0.2))),
        RigidTransform(),
        exact_shape("sphere", (0.01,), None),
        RigidTransform(),
    )
    assert inside == 0.0  # a solid inside a mesh is in contact, not 90 mm away


@pytest.mark.parametrize(
    "entry, key, fragment",
    [
        (dict(shape="box"), "obstacles[3].size_mm", "missing for the 'post' shape"),
        (dict(shape="cone"), "obstacles[3].shape", "unknown 'cone' for 'post'"),
        (dict(shape="sphere", radius_mm=-2.0), "obstacles[3].radius_mm", "positive"),
        (dict(shape="cylinder", radius_mm=5.0), "obstacles[3].length_mm", "missing"),
        (dict(shape="mesh", mesh="nowhere.stl"), "obstacles[3].mesh", "cannot read"),
        (dict(shape="mesh", mesh="junk.stl"), "obstacles[3].mesh", "cannot read"),
        (dict(shape="mesh", mesh="junk.stl", mesh_units="in"), "obstacles[3].mesh_units", "'in'"),
    ],
)
def test_bad_shapes_raise_one_line_errors_naming_the_key_and_shape(tmp_path, entry, key, fragment):
    (tmp_path / "junk.stl").write_text("not a mesh at all\n")
    with pytest.raises(ShapeError) as error:
        load_shape(ShapeConfig(name="post", **entry), tmp_path, key="obstacles[3]")
    message = str(error.value)
    assert "\n" not in message and message.startswith(f"{key}: ") and fragment in message


def test_cell_errors_for_duplicate_names_and_unknown_allowed_pairs(kr16):
    with pytest.raises(ShapeError, match=r"obstacles: shape name 'plate' used twice"):
        plate_cell(kr16, [box("plate", (0.1, 0.1, 0.1), RigidTransform([2.0, 0, 0]))])
    with pytest.raises(ShapeError, match=r"allowed_contact\[0\]: unknown shape 'tip'"):
        plate_cell(kr16, [], allowed_contact=[("tip", "plate")])


def test_motion_bound_holds_for_random_joint_steps(kr16, rng):
    """No collision geometry moves farther than Σ ρ_k |Δq_k| (checked on each geometry's
    bounding sphere, which the bound covers)."""
    cell = plate_cell(kr16, [])
    rho = cell.motion_radii()
    plant, context = cell.plant, cell.plant.CreateDefaultContext()
    inspector = cell.diagram.scene_graph().model_inspector()
    points = []  # (body, (8, 3) points on the geometry's bounding sphere, in the body frame)
    for geometry_id, label in cell.labels.items():
        X_BG = inspector.GetPoseInFrame(geometry_id)
        directions = rng.normal(size=(8, 3))
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        radius = bounding_radius(inspector.GetShape(geometry_id))
        points.append((plant.GetBodyByName(label.body), X_BG @ (radius * directions.T)))
    for _ in range(200):
        q_a = rng.uniform(kr16.q_lower, kr16.q_upper)
        q_b = q_a + rng.normal(scale=0.05, size=6)
        moved = 0.0
        for body, p_BQ in points:
            plant.SetPositions(context, q_a)
            p_IQ_a = plant.EvalBodyPoseInWorld(context, body) @ p_BQ
            plant.SetPositions(context, q_b)
            p_IQ_b = plant.EvalBodyPoseInWorld(context, body) @ p_BQ
            moved = max(moved, np.linalg.norm(p_IQ_b - p_IQ_a, axis=0).max())
        assert moved <= np.abs(q_b - q_a) @ rho


def test_a_mesh_in_mm_declared_as_metres_is_refused_at_once(tmp_path):
    """cylinder_shell.stl is in mm: read as metres it is hundreds of metres across, which
    CoACD would grind on for minutes; it is one line naming the key, with the hint."""
    with pytest.raises(ShapeError) as error:
        mesh_shape("shell", DATA / "data" / "cylinder_shell.stl", 1.0, key="part.mesh")
    message = str(error.value)
    assert message.startswith("part.mesh: ") and "set part.mesh_units: mm" in message
    assert "\n" not in message
    assert mesh_shape("shell", DATA / "data" / "cylinder_shell.stl", 1e-3).kind == "mesh"


def test_a_cells_kept_pairs_check_as_a_fresh_cells_do(kr16):
    """The collision check keeps its geometry pairs in the cell (``pairs.cell_pairs``):
    checks one after the other on one cell (another trajectory between them) report the
    same verdict, distances and counts of queries as each check on a cell of its own."""
    q, t = sweep(kr16, 401)
    poses = part_poses(plate_cell(kr16, []), q)
    sigma = arc_length(poses)
    near = poses[200].translation() - [0.0, 0.0, BALL_R_M + 0.004]  # 4 mm below the plate
    kept = plate_cell(kr16, [ball("ball", near)])
    runs = [(q, t, sigma), (q[::-1][:150], t[:150], sigma[:150]), (q, t, sigma)]
    for run in runs:
        ours = check_trajectory(kept, *run, clearance=CLEARANCE_M)
        fresh = check_trajectory(
            plate_cell(kr16, [ball("ball", near)]), *run, clearance=CLEARANCE_M
        )
        assert ours.collision_free == fresh.collision_free
        assert ours.samples_in_collision == fresh.samples_in_collision
        assert [(p.a, p.b, p.distance_m, p.sample) for p in ours.pairs] == [
            (p.a, p.b, p.distance_m, p.sample) for p in fresh.pairs
        ]
        for key in ("checked_samples", "distance_queries", "exact_checks"):
            assert ours.stats[key] == fresh.stats[key]
    assert not ours.collision_free  # the ball is within the clearance
