"""The work cell as a Drake MultibodyPlant (robot, part in the gripper, fixed tool).

Built like Drake model directives: the robot URDF is welded to the world at
X_IB, the part body is welded to the flange (tool0) at X_EP = X_PE⁻¹, and the
tool body is welded to the world at X_IT. Part and tool meshes, when the cell
gives them, are converted once to OBJ with trimesh (Drake's mesh format) and
cached by content hash.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
from pathlib import Path

import numpy as np
from pydrake.geometry import Mesh, Rgba
from pydrake.math import RigidTransform
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex, SpatialInertia
from pydrake.planning import RobotDiagram, RobotDiagramBuilder

from offline_prog.robot_model import ROBOTS_DIR, RobotModel

PART_COLOR = Rgba(0.85, 0.55, 0.15, 1.0)
TOOL_COLOR = Rgba(0.3, 0.3, 0.35, 1.0)


def mesh_cache_dir() -> Path:
    """Where converted meshes live (``$OFFLINE_PROG_CACHE`` or ~/.cache/offline_prog)."""
    root = os.environ.get("OFFLINE_PROG_CACHE") or Path.home() / ".cache" / "offline_prog"
    return Path(root) / "meshes"


def as_obj(mesh_file: Path, scale: float) -> Path:
    """An OBJ copy of a mesh file (STL/OBJ/PLY/GLB) in metres, cached by content hash."""
    import trimesh

    data = Path(mesh_file).read_bytes()
    key = hashlib.sha256(data + f"{scale!r}".encode()).hexdigest()[:20]
    target = mesh_cache_dir() / f"{key}.obj"
    if not target.exists():
        mesh = trimesh.load(mesh_file, force="mesh")
        mesh.apply_scale(scale)
        target.parent.mkdir(parents=True, exist_ok=True)
        temp = target.with_suffix(f".{os.getpid()}.tmp")
        temp.write_text(trimesh.exchange.obj.export_obj(mesh))
        os.replace(temp, target)
    return target


@dataclasses.dataclass
class DrakeCell:
    """The cell's Drake model.

    Attributes:
        diagram: RobotDiagram (plant + scene graph), finalized and built.
        plant: its MultibodyPlant; the robot's joints are its only positions (nq = 6).
        robot: the robot's ModelInstanceIndex.
        X_IB: robot base in I; X_IT: fixed tool in I; X_PE: flange in the part frame.
    """

    diagram: RobotDiagram
    plant: MultibodyPlant
    robot: ModelInstanceIndex
    X_IB: RigidTransform
    X_IT: RigidTransform
    X_PE: RigidTransform

    @property
    def frame_E(self):
        return self.plant.GetFrameByName("tool0", self.robot)

    def X_IE(self, q: np.ndarray) -> RigidTransform:
        """Flange pose in I from Drake's kinematics at joint vector q (6,) [rad]."""
        context = self.plant.CreateDefaultContext()
        self.plant.SetPositions(context, self.robot, q)
        return self.frame_E.CalcPoseInWorld(context)


def _add_welded_body(plant, name, X_parent_child, parent_frame, mesh_obj, color):
    body = plant.AddRigidBody(
        name, plant.AddModelInstance(name), SpatialInertia.SolidSphereWithMass(1.0, 0.05)
    )
    plant.WeldFrames(parent_frame, body.body_frame(), X_parent_child)
    if mesh_obj is not None and plant.geometry_source_is_registered():
        shape = Mesh(str(mesh_obj))
        plant.RegisterVisualGeometry(body, RigidTransform(), shape, f"{name}_visual", color)
        plant.RegisterCollisionGeometry(
            body, RigidTransform(), shape, f"{name}_collision", CoulombFriction(0.5, 0.5)
        )
    return body


def build_drake_cell(
    robot: RobotModel,
    *,
    X_IB: RigidTransform,
    X_IT: RigidTransform,
    X_PE: RigidTransform,
    part_mesh: Path | None = None,
    part_mesh_scale: float = 1.0,
    tool_mesh: Path | None = None,
    tool_mesh_scale: float = 1.0,
) -> DrakeCell:
    """Build and finalize the cell's plant (paper §3: robot carries P past T).

    Args:
        robot: the robot record (its URDF is parsed unchanged).
        X_IB: robot base frame B (URDF base_link) in I.
        X_IT: fixed TCP frame T in I.
        X_PE: flange frame E (URDF tool0) in the part frame P.
        part_mesh, tool_mesh: optional mesh files, in P and T respectively.
    """
    builder = RobotDiagramBuilder(time_step=0.0)
    plant = builder.plant()
    parser = builder.parser()
    parser.package_map().AddPackageXml(str(ROBOTS_DIR / "package.xml"))
    (model,) = parser.AddModels(str(robot.urdf_path))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("base_link", model), X_IB)
    part_obj = as_obj(part_mesh, part_mesh_scale) if part_mesh else None
    tool_obj = as_obj(tool_mesh, tool_mesh_scale) if tool_mesh else None
    _add_welded_body(
        plant, "part", X_PE.inverse(), plant.GetFrameByName("tool0", model), part_obj, PART_COLOR
    )
    _add_welded_body(plant, "tool", X_IT, plant.world_frame(), tool_obj, TOOL_COLOR)
    plant.Finalize()
    diagram = builder.Build()
    return DrakeCell(diagram, plant, model, X_IB, X_IT, X_PE)
