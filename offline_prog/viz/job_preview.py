"""preview.html of a whole job: the cell, every seam drawn on the part, the flange's
path through the whole job, and the motion from home to home with the active seam
highlighted (a thicker orange copy of its path shown only while it runs).

Built like the one-seam preview (``viz.preview``, no server): the same cell drawing
and animation, seams and links instead of one path.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.config.cell import transform
from offline_prog.scene.drake_cell import build_cell_model
from offline_prog.viz.preview import (
    FLANGE_COLOR,
    PATH_COLOR,
    PREVIEW_FPS,
    body_poses,
    camera,
    draw_cell,
    part_node,
)
from offline_prog.viz.static_scene import StaticScene

ACTIVE_COLOR = (1.0, 0.45, 0.0, 1.0)  # the seam being processed
LINK_COLOR = (0.55, 0.55, 0.55, 1.0)  # the flange's path on links (air moves)
ACTIVE_LIFT_M = 5e-4  # the highlight sits just off the surface, in front of the path


def job_preview_scene(job) -> tuple[StaticScene, dict]:
    """The job as MeshCat commands; returns the scene and {"frames", "seams"}."""
    drake = build_cell_model(job.cell, job.cell_file, job.robot)
    scene = StaticScene()
    bodies = draw_cell(scene, drake)
    part = part_node(drake.plant, bodies)
    times = np.append(np.arange(0.0, job.samples.t[-1], 1.0 / PREVIEW_FPS), job.samples.t[-1])
    scales = {}
    for option in job.chosen:
        plan = option.plan
        s = np.linspace(0.0, plan.path.length, 600)
        p_PF = plan.path(s, order=0)[0]
        scene.set_lines(f"{part}/seams/{option.name}", p_PF, PATH_COLOR)
        n_P = plan.flange(s[:1]).R_PF[0][:, 1]  # lift against n: off the surface
        highlight = f"{part}/active/{option.name}"
        scene.set_lines(highlight, p_PF - ACTIVE_LIFT_M * n_P, ACTIVE_COLOR)
        segment = next(
            g for g in job.samples.segments if g.kind == "process" and g.seam == option.name
        )
        scales[highlight] = ((times >= segment.t_start) & (times < segment.t_stop)).astype(float)
    X_IE = transform(job.cell.robot.X_IB).GetAsMatrix4() @ job.robot.forward(job.samples.q)
    p_IE = X_IE[:, :3, 3]
    for k, segment in enumerate(job.samples.segments):
        rows = slice(segment.start, min(segment.stop + 1, len(p_IE)))
        color = LINK_COLOR if segment.kind == "link" else FLANGE_COLOR
        scene.set_lines(f"/offline_prog/flange_path/{k}_{segment.kind}", p_IE[rows], color)
    scene.set_camera(
        *camera(
            transform(job.cell.robot.X_IB).translation(),
            transform(job.cell.tool.X_IT).translation(),
        )
    )
    q = np.column_stack([np.interp(times, job.samples.t, job.samples.q[:, j]) for j in range(6)])
    paths, poses = body_poses(drake, bodies, q)
    scene.set_animation(paths, times, poses, PREVIEW_FPS, scales=scales)
    frames = int(np.floor(times[-1] * PREVIEW_FPS + 1e-9)) + 1
    return scene, {"frames": frames, "seams": len(job.chosen)}


def write_job_preview_html(job, file) -> dict:
    """Write the job's standalone preview.html; returns job_preview_scene's info."""
    scene, info = job_preview_scene(job)
    title = f"Preview: {job.cell.name or Path(job.cell_file).stem}"
    write_atomic(Path(file), scene.html(title))
    return info


def show_job(job, meshcat) -> dict:
    """Draw the job in a live Drake ``meshcat`` and record its motion as an animation,
    each seam's highlight visible only while it runs.

    Returns:
        {"frames": recorded animation frames, "frames_per_second", "seams": their number}.
    """
    from pydrake.geometry import Rgba

    drake = build_cell_model(job.cell, job.cell_file, job.robot, meshcat=meshcat)
    part = f"/drake/visualizer/part/{drake.plant.GetBodyByName('part').name()}"
    highlights = {}
    for option in job.chosen:
        plan = option.plan
        s = np.linspace(0.0, plan.path.length, 600)
        p_PF = plan.path(s, order=0)[0]
        meshcat.SetLine(f"{part}/seams/{option.name}", p_PF.T, 3.0, Rgba(*PATH_COLOR))
        n_P = plan.flange(s[:1]).R_PF[0][:, 1]
        path = f"{part}/active/{option.name}"
        meshcat.SetLine(path, (p_PF - ACTIVE_LIFT_M * n_P).T, 6.0, Rgba(*ACTIVE_COLOR))
        highlights[option.name] = path
    X_IE = transform(job.cell.robot.X_IB).GetAsMatrix4() @ job.robot.forward(job.samples.q)
    for k, segment in enumerate(job.samples.segments):
        rows = slice(segment.start, min(segment.stop + 1, len(X_IE)))
        color = LINK_COLOR if segment.kind == "link" else FLANGE_COLOR
        meshcat.SetLine(
            f"/offline_prog/flange_path/{k}_{segment.kind}", X_IE[rows, :3, 3].T, 2.0, Rgba(*color)
        )
    diagram, plant = drake.diagram, drake.plant
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyContextFromRoot(context)
    times = np.append(np.arange(0.0, job.samples.t[-1], 1.0 / PREVIEW_FPS), job.samples.t[-1])
    drake.visualizer.StartRecording(set_transforms_while_recording=False)
    for time in times:
        context.SetTime(time)
        q = [np.interp(time, job.samples.t, job.samples.q[:, j]) for j in range(6)]
        plant.SetPositions(plant_context, drake.robot, q)
        diagram.ForcedPublish(context)
    drake.visualizer.StopRecording()
    animation = drake.visualizer.get_mutable_recording()
    for segment in job.samples.segments:
        if segment.kind != "process":
            continue
        path = highlights[segment.seam]
        for time in times:
            active = segment.t_start <= time < segment.t_stop
            animation.SetProperty(animation.frame(time), path, "visible", active)
    drake.visualizer.PublishRecording()
    return {
        "frames": int(animation.frame(times[-1])) + 1,
        "frames_per_second": animation.frames_per_second(),
        "seams": len(job.chosen),
    }
