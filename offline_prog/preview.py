"""MeshCat preview of a plan: the cell, the paths, the frames, the animated motion.

The whole cell (robot, part in the gripper, fixed tool, obstacles) is drawn by
Drake's MeshcatVisualizer; on top of it the processing path is a line on the part
(it moves with the part), process frames are small triads at a readable spacing,
and the flange path is a line in space. Samples close to a joint limit or to a
collision are marked. The motion is recorded as a MeshCat animation (play,
pause, scrub) and saved as a standalone HTML file that opens offline.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pydrake.geometry import Meshcat, Rgba, Sphere
from pydrake.math import RigidTransform

from offline_prog.cell import transform
from offline_prog.drake_cell import build_cell_model

PREVIEW_FPS = 30.0
TRIAD_SPACING_M = 0.03
TRIAD_LENGTH_M = 0.015
NEAR_LIMIT_RAD = np.deg2rad(10.0)  # joint-limit margin that gets a marker
MARKER_RADIUS_M = 0.006
PATH_COLOR = Rgba(0.1, 0.4, 1.0, 1.0)
FLANGE_COLOR = Rgba(0.2, 0.7, 0.2, 1.0)
LIMIT_COLOR = Rgba(1.0, 0.6, 0.0, 1.0)
COLLISION_COLOR = Rgba(0.9, 0.1, 0.1, 1.0)
AXIS_COLORS = (Rgba(0.9, 0.1, 0.1, 1), Rgba(0.1, 0.8, 0.1, 1), Rgba(0.1, 0.2, 0.9, 1))


def _part_path(meshcat: Meshcat, cell) -> str:
    """The MeshCat path of the part body's frame (children move with the part)."""
    return f"/drake/visualizer/part/{cell.plant.GetBodyByName('part').name()}"


def _draw_paths(meshcat: Meshcat, plan, part_path: str) -> None:
    traj = plan.trajectory
    dense = plan.path(np.linspace(0.0, plan.path.length, 600), order=0)[0]
    meshcat.SetLine(f"{part_path}/processing_path", dense.T, 3.0, PATH_COLOR)
    # Triads of the process frames F, in P, every TRIAD_SPACING_M of path.
    s = np.arange(0.0, plan.path.length, TRIAD_SPACING_M)
    f = plan.flange(s)
    for axis, color in enumerate(AXIS_COLORS):
        start = f.p_PF.T
        end = (f.p_PF + TRIAD_LENGTH_M * f.R_PF[:, :, axis]).T
        meshcat.SetLineSegments(f"{part_path}/frames/{'xyz'[axis]}", start, end, 2.0, color)
    meshcat.SetLine("/offline_prog/flange_path", traj.flange.p_IE.T, 2.0, FLANGE_COLOR)


def _draw_markers(meshcat: Meshcat, plan, near_collision: np.ndarray | None) -> int:
    """Spheres on the flange path where a joint is near its limit or the cell near a
    collision; returns how many were drawn."""
    q, robot = plan.joints.q, plan.robot
    margin = np.minimum(q - robot.q_lower, robot.q_upper - q).min(axis=1)
    kinds = [(margin < NEAR_LIMIT_RAD, "joint_limit", LIMIT_COLOR)]
    if near_collision is not None:
        kinds.append((near_collision, "collision", COLLISION_COLOR))
    count = 0
    p_IE = plan.trajectory.flange.p_IE
    for mask, name, color in kinds:
        for k, i in enumerate(np.flatnonzero(mask)[:: max(1, int(mask.sum() // 200))]):
            path = f"/offline_prog/near_{name}/{k}"
            meshcat.SetObject(path, Sphere(MARKER_RADIUS_M), color)
            meshcat.SetTransform(path, RigidTransform(p_IE[i]))
            count += 1
    return count


def _frame_camera(meshcat: Meshcat, plan) -> None:
    """Look at the cell (robot base to tool) from the front-left, above."""
    base = transform(plan.cell.robot.X_IB).translation()
    tool = plan.flange.X_IT.translation()
    target = 0.5 * (base + tool) + np.array([0.0, 0.0, 0.2])
    reach = max(1.0, float(np.linalg.norm(tool - base)))
    camera = target + reach * np.array([1.2, 1.6, 0.9])
    meshcat.SetCameraPose(camera, target)


def show_plan(plan, meshcat: Meshcat, *, near_collision: np.ndarray | None = None) -> dict:
    """Draw the plan in ``meshcat`` and record its motion as an animation.

    Returns:
        {"frames": recorded animation frames, "markers": marker count}.
    """
    drake = build_cell_model(plan.cell, plan.cell_file, plan.robot, meshcat=meshcat)
    part_path = _part_path(meshcat, drake)
    _draw_paths(meshcat, plan, part_path)
    markers = _draw_markers(meshcat, plan, near_collision)
    _frame_camera(meshcat, plan)
    diagram, plant = drake.diagram, drake.plant
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyContextFromRoot(context)
    visualizer = drake.visualizer
    traj = plan.trajectory
    times = np.arange(0.0, traj.t[-1], 1.0 / PREVIEW_FPS)
    times = np.append(times, traj.t[-1])
    q = np.column_stack([np.interp(times, traj.t, plan.joints.q[:, j]) for j in range(6)])
    visualizer.StartRecording(set_transforms_while_recording=False)
    for time, q_i in zip(times, q, strict=True):
        context.SetTime(time)
        plant.SetPositions(plant_context, drake.robot, q_i)
        diagram.ForcedPublish(context)
    visualizer.StopRecording()
    visualizer.PublishRecording()
    animation = visualizer.get_mutable_recording()
    return {
        "frames": int(animation.frame(times[-1])) + 1,
        "markers": markers,
        "frames_per_second": animation.frames_per_second(),
    }


def near_collision_mask(plan) -> np.ndarray:
    """(N,) True at samples closer than the clearance (from the collision check)."""
    mask = np.zeros(len(plan.trajectory.t), dtype=bool)
    index = np.asarray(plan.collisions.samples_in_collision, dtype=int)
    mask[index[(index >= 0) & (index < len(mask))]] = True
    return mask


def write_preview_html(plan, file) -> dict:
    """Record the plan in an off-screen MeshCat and save its standalone HTML."""
    from offline_prog.atomic import write_atomic

    meshcat = Meshcat()
    info = show_plan(plan, meshcat, near_collision=near_collision_mask(plan))
    write_atomic(Path(file), meshcat.StaticHtml())
    return info
