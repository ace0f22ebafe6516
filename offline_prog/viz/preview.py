"""MeshCat preview of a plan: the cell, the paths, the frames, the animated motion.

The whole cell (robot, part in the gripper, fixed tool, obstacles) is drawn from the
Drake plant's illustration geometry; on top of it the processing path is a line on the
part (it moves with the part), process frames are small triads at a readable spacing,
and the flange path is a line in space. Samples close to a joint limit or to a
collision are marked. The motion is an animation (play, pause, scrub).

Two outputs share the overlays computed here:
- ``write_preview_html``: a standalone preview.html, built without any server
  (``viz.static_scene``); every plan writes one.
- ``show_plan``: the same in a live Drake ``Meshcat`` (``offline-prog preview``).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from pydrake.geometry import Box, Capsule, Convex, Cylinder, Mesh, Meshcat, Rgba, Role, Sphere
from pydrake.math import RigidTransform

from offline_prog.atomic import write_atomic
from offline_prog.config.cell import transform
from offline_prog.scene.drake_cell import build_cell_model
from offline_prog.scene.mesh_cache import drawn_arrays
from offline_prog.viz.static_scene import StaticScene

PREVIEW_FPS = 30.0
TRIAD_SPACING_M = 0.03
TRIAD_LENGTH_M = 0.015
NEAR_LIMIT_RAD = np.deg2rad(10.0)  # joint-limit margin that gets a marker
MARKER_RADIUS_M = 0.006
MAX_MARKERS = 200  # per kind, evenly thinned
PATH_COLOR = (0.1, 0.4, 1.0, 1.0)
FLANGE_COLOR = (0.2, 0.7, 0.2, 1.0)
LIMIT_COLOR = (1.0, 0.6, 0.0, 1.0)
COLLISION_COLOR = (0.9, 0.1, 0.1, 1.0)
AXIS_COLORS = ((0.9, 0.1, 0.1, 1), (0.1, 0.8, 0.1, 1), (0.1, 0.2, 0.9, 1))
DEFAULT_RGBA = (0.8, 0.8, 0.8, 1.0)


@dataclasses.dataclass
class Overlays:
    """What the preview draws on top of the cell.

    Attributes:
        p_P_path: (K, 3) the processing path in P [m].
        triads: three (M, 2, 3) segment arrays (x, y, z axes of F) in P [m].
        p_I_flange: (N, 3) the flange path in I [m].
        markers: (name, rgba, (J, 3) positions in I [m]) per marker kind.
        camera: (p_I_camera, p_I_target) [m].
    """

    p_P_path: np.ndarray
    triads: list[np.ndarray]
    p_I_flange: np.ndarray
    markers: list[tuple[str, tuple, np.ndarray]]
    camera: tuple[np.ndarray, np.ndarray]


def overlays(plan, near_collision: np.ndarray | None) -> Overlays:
    """The paths, frames, markers and camera of a plan (shared by both outputs)."""
    dense = plan.path(np.linspace(0.0, plan.path.length, 600), order=0)[0]
    s = np.arange(0.0, plan.path.length, TRIAD_SPACING_M)
    f = plan.flange(s)
    triads = [
        np.stack([f.p_PF, f.p_PF + TRIAD_LENGTH_M * f.R_PF[:, :, axis]], axis=1)
        for axis in range(3)
    ]
    q, robot = plan.joints.q, plan.robot
    q_c = robot.controller_joints(q)
    margin = np.minimum(q_c - robot.q_lower, robot.q_upper - q_c).min(axis=1)
    kinds = [("joint_limit", LIMIT_COLOR, margin < NEAR_LIMIT_RAD)]
    if near_collision is not None:
        kinds.append(("collision", COLLISION_COLOR, near_collision))
    p_IE = plan.trajectory.flange.p_IE
    markers = []
    for name, color, mask in kinds:
        index = np.flatnonzero(mask)
        index = index[:: max(1, len(index) // MAX_MARKERS)]
        markers.append((name, color, p_IE[index]))
    view = camera(transform(plan.cell.robot.X_IB).translation(), plan.flange.X_IT.translation())
    return Overlays(dense, triads, p_IE, markers, view)


def near_collision_mask(plan) -> np.ndarray:
    """(N,) True at samples closer than the clearance (from the collision check)."""
    mask = np.zeros(len(plan.trajectory.t), dtype=bool)
    index = np.asarray(plan.collisions.samples_in_collision, dtype=int)
    mask[index[(index >= 0) & (index < len(mask))]] = True
    return mask


def _animation_times(plan) -> np.ndarray:
    """Frame times [s]: every 1/PREVIEW_FPS, and the plan's end."""
    end = plan.trajectory.t[-1]
    return np.append(np.arange(0.0, end, 1.0 / PREVIEW_FPS), end)


def _joints_at(plan, times: np.ndarray) -> np.ndarray:
    """(F, 6) joint positions [rad] at the frame times (linear between samples)."""
    traj, q = plan.trajectory, plan.joints.q
    return np.column_stack([np.interp(times, traj.t, q[:, j]) for j in range(q.shape[1])])


# --- standalone preview.html (no server) ------------------------------------------------


def _mesh_file(shape) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(vertices (V, 3) [m], faces (F, 3), vertex colours (V, 3) or None) of a Drake
    Mesh (its file; each part coloured by its material, e.g. an OBJ's .mtl) or Convex
    (its hull); the file's arrays are kept in the mesh cache (``drawn_arrays``)."""
    file = shape.source().path()
    if isinstance(shape, Convex):
        arrays = drawn_arrays(file, "preview hull v1", lambda: _hull_arrays(file))
    else:
        arrays = drawn_arrays(file, "preview parts v1", lambda: _part_arrays(file))
    scale = np.asarray(shape.scale3())
    return arrays["vertices"] * scale, arrays["faces"], arrays.get("colors")


def _hull_arrays(file: str) -> dict[str, np.ndarray]:
    """{vertices (V, 3), faces (F, 3)} of a mesh file's convex hull, in file units."""
    import trimesh  # only for a mesh file not drawn before: ~0.2 s of import

    hull = trimesh.load(file, force="mesh").convex_hull
    return {"vertices": np.asarray(hull.vertices), "faces": np.asarray(hull.faces)}


def _part_arrays(file: str) -> dict[str, np.ndarray]:
    """{vertices (V, 3), faces (F, 3), colors (V, 3) if every part has a material} of a
    mesh file's parts joined, in file units."""
    import trimesh  # only for a mesh file not drawn before: ~0.2 s of import

    parts = trimesh.load(file, force="scene").dump(concatenate=False)
    vertices, faces, offset = [], [], 0
    for part in parts:
        vertices.append(np.asarray(part.vertices))
        faces.append(np.asarray(part.faces) + offset)
        offset += len(part.vertices)
    arrays = {"vertices": np.vstack(vertices), "faces": np.vstack(faces)}
    colors = [_part_color(part) for part in parts]
    if all(color is not None for color in colors):
        arrays["colors"] = np.vstack(
            [
                np.tile(color, (len(part.vertices), 1))
                for color, part in zip(colors, parts, strict=True)
            ]
        )
    return arrays


def _part_color(part) -> np.ndarray | None:
    """(3,) the diffuse colour of one mesh part's material, or None, as linear RGB in
    [0, 1]: materials give sRGB, three.js takes vertex colours as linear."""
    material = getattr(part.visual, "material", None)
    color = getattr(material, "main_color", None) if material is not None else None
    if color is None:
        return None
    srgb = np.asarray(color[:3], dtype=float) / 255.0
    return np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)


def _draw_shape(scene: StaticScene, path: str, shape, rgba) -> None:
    """One Drake shape at ``path`` (in its own frame G)."""
    if isinstance(shape, Box):
        scene.set_primitive(path, "box", (shape.width(), shape.depth(), shape.height()), rgba)
    elif isinstance(shape, Sphere):
        scene.set_primitive(path, "sphere", (shape.radius(),), rgba)
    elif isinstance(shape, Cylinder | Capsule):
        kind = "cylinder" if isinstance(shape, Cylinder) else "capsule"
        scene.set_primitive(path, kind, (shape.radius(), shape.length()), rgba)
    elif isinstance(shape, Mesh | Convex):
        vertices, faces, colors = _mesh_file(shape)
        scene.set_mesh(path, vertices, faces, rgba, colors)
    else:
        raise ValueError(f"preview: no drawing for Drake {type(shape).__name__}")


def draw_cell(scene: StaticScene, drake) -> dict[str, object]:
    """Every illustration geometry under ``/drake/<model>/<body>``; returns the bodies
    by node path."""
    plant, inspector = drake.plant, drake.diagram.scene_graph().model_inspector()
    bodies = {}
    # Numbered in the scene's order, not by GeometryId: ids count every geometry the
    # process registered before, so the same cell would draw under other names.
    for i, g in enumerate(inspector.GetAllGeometryIds(Role.kIllustration)):
        body = plant.GetBodyFromFrameId(inspector.GetFrameId(g)) or plant.world_body()
        node = f"/drake/{plant.GetModelInstanceName(body.model_instance())}/{body.name()}"
        bodies[node] = body
        props = inspector.GetIllustrationProperties(g)
        rgba = props.GetPropertyOrDefault("phong", "diffuse", Rgba(*DEFAULT_RGBA))
        path = f"{node}/{inspector.GetName(g).replace('/', '_')}_{i}"
        color = (rgba.r(), rgba.g(), rgba.b(), rgba.a())
        _draw_shape(scene, f"{path}/shape", inspector.GetShape(g), color)
        scene.set_transform(path, inspector.GetPoseInFrame(g).GetAsMatrix4())
    return bodies


def part_node(plant, bodies: dict) -> str:
    """The part's node path (added to ``bodies`` when the part has no geometry: its
    frame still carries the paths drawn on it)."""
    part = next((p for p, b in bodies.items() if b.name() == "part"), None)
    if part is None:
        body = plant.GetBodyByName("part")
        part = f"/drake/{plant.GetModelInstanceName(body.model_instance())}/part"
        bodies[part] = body
    return part


def body_poses(drake, bodies: dict, q: np.ndarray) -> tuple[list[str], np.ndarray]:
    """(node paths, (n_nodes, F, 4, 4) poses in I) of the drawn bodies at joints q (F, 6)."""
    plant = drake.plant
    context = plant.CreateDefaultContext()
    paths = list(bodies)
    poses = np.empty((len(paths), len(q), 4, 4))
    for i, q_i in enumerate(q):
        plant.SetPositions(context, drake.robot, q_i)
        for k, path in enumerate(paths):
            poses[k, i] = plant.EvalBodyPoseInWorld(context, bodies[path]).GetAsMatrix4()
    return paths, poses


def camera(p_IB: np.ndarray, p_IT: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(p_I_camera, p_I_target) [m]: front-left and above the robot base B and tool T."""
    target = 0.5 * (p_IB + p_IT) + np.array([0.0, 0.0, 0.2])
    reach = max(1.0, float(np.linalg.norm(p_IT - p_IB)))
    return target + reach * np.array([1.2, 1.6, 0.9]), target


def preview_scene(plan, *, near_collision: np.ndarray | None = None) -> tuple[StaticScene, dict]:
    """The plan as MeshCat commands: cell, overlays, camera and the animation.

    Returns:
        The scene and {"frames", "markers", "frames_per_second"}.
    """
    drake = build_cell_model(plan.cell, plan.cell_file, plan.robot)
    scene = StaticScene()
    bodies = draw_cell(scene, drake)
    extra = overlays(plan, near_collision)
    part = part_node(drake.plant, bodies)
    scene.set_lines(f"{part}/processing_path", extra.p_P_path, PATH_COLOR)
    for axis, segments in enumerate(extra.triads):
        scene.set_lines(
            f"{part}/frames/{'xyz'[axis]}",
            segments.reshape(-1, 3),
            AXIS_COLORS[axis],
            segments=True,
        )
    scene.set_lines("/offline_prog/flange_path", extra.p_I_flange, FLANGE_COLOR)
    count = 0
    for name, color, points in extra.markers:
        for k, p in enumerate(points):
            path = f"/offline_prog/near_{name}/{k}"
            scene.set_primitive(path, "sphere", (MARKER_RADIUS_M,), color)
            scene.set_transform(path, RigidTransform(p).GetAsMatrix4())
            count += 1
    scene.set_camera(*extra.camera)
    times = _animation_times(plan)
    paths, poses = body_poses(drake, bodies, _joints_at(plan, times))
    scene.set_animation(paths, times, poses, PREVIEW_FPS)
    frames = int(np.floor(times[-1] * PREVIEW_FPS + 1e-9)) + 1
    return scene, {"frames": frames, "markers": count, "frames_per_second": PREVIEW_FPS}


def write_preview_html(plan, file) -> dict:
    """Write the plan's standalone preview.html (no server); returns preview_scene's info."""
    scene, info = preview_scene(plan, near_collision=near_collision_mask(plan))
    title = f"Preview: {plan.cell.name or Path(plan.cell_file).stem}"
    write_atomic(Path(file), scene.html(title))
    return info


# --- live Drake MeshCat (offline-prog preview) -------------------------------------------


def show_plan(plan, meshcat: Meshcat, *, near_collision: np.ndarray | None = None) -> dict:
    """Draw the plan in a live ``meshcat`` and record its motion as an animation.

    Returns:
        {"frames": recorded animation frames, "markers": marker count, "frames_per_second"}.
    """
    drake = build_cell_model(plan.cell, plan.cell_file, plan.robot, meshcat=meshcat)
    part = f"/drake/visualizer/part/{drake.plant.GetBodyByName('part').name()}"
    extra = overlays(plan, near_collision)
    meshcat.SetLine(f"{part}/processing_path", extra.p_P_path.T, 3.0, Rgba(*PATH_COLOR))
    for axis, segments in enumerate(extra.triads):
        meshcat.SetLineSegments(
            f"{part}/frames/{'xyz'[axis]}",
            segments[:, 0].T,
            segments[:, 1].T,
            2.0,
            Rgba(*AXIS_COLORS[axis]),
        )
    meshcat.SetLine("/offline_prog/flange_path", extra.p_I_flange.T, 2.0, Rgba(*FLANGE_COLOR))
    count = 0
    for name, color, points in extra.markers:
        for k, p in enumerate(points):
            path = f"/offline_prog/near_{name}/{k}"
            meshcat.SetObject(path, Sphere(MARKER_RADIUS_M), Rgba(*color))
            meshcat.SetTransform(path, RigidTransform(p))
            count += 1
    meshcat.SetCameraPose(*extra.camera)
    diagram, plant = drake.diagram, drake.plant
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyContextFromRoot(context)
    times = _animation_times(plan)
    drake.visualizer.StartRecording(set_transforms_while_recording=False)
    for time, q_i in zip(times, _joints_at(plan, times), strict=True):
        context.SetTime(time)
        plant.SetPositions(plant_context, drake.robot, q_i)
        diagram.ForcedPublish(context)
    drake.visualizer.StopRecording()
    drake.visualizer.PublishRecording()
    animation = drake.visualizer.get_mutable_recording()
    return {
        "frames": int(animation.frame(times[-1])) + 1,
        "markers": count,
        "frames_per_second": animation.frames_per_second(),
    }
