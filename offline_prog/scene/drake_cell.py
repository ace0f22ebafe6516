"""The work cell as a Drake MultibodyPlant (robot, gripper and part, fixed tool).

Built like Drake model directives: the robot URDF is welded to the world at
X_IB, the gripper body (its frame is E) to the flange (tool0), the part body to the
flange at X_EP = X_PE⁻¹, and the tool body to the world at X_IT. Part and tool meshes, when the cell
gives them, are converted once to OBJ with trimesh (Drake's mesh format) and
cached by content hash.

The cell's shapes (:mod:`offline_prog.scene.shapes`) are registered on the part body (in P),
the gripper body (in E), the tool body (in T) and the world (obstacles, anchored, in I),
each geometry named after its shape; ``DrakeCell.labels`` maps every collision GeometryId
to (owner, shape name), robot geometries being named after their link. Collision filters:
Drake filters adjacent links and bodies welded together (the gripper on the flange link);
the part is also filtered against the bodies it is welded to (the flange link and the
gripper that holds it), and each ``allowed_contact`` pair is filtered out. The first
kind are listed with their reasons in ``DrakeCell.held_contacts``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from pydrake.geometry import GeometryId, Rgba
from pydrake.math import RigidTransform
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex, SpatialInertia
from pydrake.planning import RobotDiagram, RobotDiagramBuilder

from offline_prog.config.cell import Cell, transform
from offline_prog.robot.model import ROBOTS_DIR, RobotModel
from offline_prog.scene.exact_distance import ExactShape, bounding_radius, exact_shape_of_drake
from offline_prog.scene.filters import filter_contacts, filter_self_pairs, held_contacts
from offline_prog.scene.shapes import CellShape, ShapeError, cell_geometry, mesh_shape

PART_COLOR = Rgba(0.85, 0.55, 0.15, 1.0)
TOOL_COLOR = Rgba(0.3, 0.3, 0.35, 1.0)
OBSTACLE_COLOR = Rgba(0.5, 0.55, 0.6, 0.6)
GRIPPER_COLOR = Rgba(0.25, 0.35, 0.55, 1.0)
# Where each owner's shapes sit in a cell file (for error messages).
OWNER_KEYS = {
    "part": "part.geometry",
    "gripper": "gripper.geometry",
    "tool": "tool.geometry",
    "obstacle": "obstacles",
}


@dataclasses.dataclass(frozen=True)
class GeometryLabel:
    """What a collision geometry is: its owner (robot | part | gripper | tool | obstacle), the
    shape's name (the link's name for robot geometry), its body and the CellShape."""

    owner: str
    name: str
    body: str
    shape: CellShape | None = None


@dataclasses.dataclass
class DrakeCell:
    """The cell's Drake model.

    Attributes:
        diagram: RobotDiagram (plant + scene graph), finalized and built.
        plant: its MultibodyPlant; the robot's joints are its only positions (nq = 6).
        robot: the robot's ModelInstanceIndex.
        X_IB: robot base in I; X_IT: fixed tool in I; X_PE: flange in the part frame.
        labels: every collision GeometryId -> its GeometryLabel.
        allowed_contact: pairs of shape names whose contact is intended (filtered out).
        held_contacts: (a, b, reason) of the shape pairs not checked because one holds
            the other (the gripper on the flange link, the part in the gripper).
    """

    diagram: RobotDiagram
    plant: MultibodyPlant
    robot: ModelInstanceIndex
    X_IB: RigidTransform
    X_IT: RigidTransform
    X_PE: RigidTransform
    labels: dict[GeometryId, GeometryLabel] = dataclasses.field(default_factory=dict)
    allowed_contact: list[tuple[str, str]] = dataclasses.field(default_factory=list)
    visualizer: object = None  # MeshcatVisualizer when built with a Meshcat
    # Robot link pairs not checked for self-collision (robots/<robot>/self_collision.yaml:
    # every class but "check"), or None when the robot has no matrix (all pairs checked).
    skipped_self_pairs: list | None = None
    held_contacts: list[tuple[str, str, str]] = dataclasses.field(default_factory=list)
    _motion_radii: np.ndarray | None = dataclasses.field(default=None, repr=False, compare=False)
    _exact: dict = dataclasses.field(default_factory=dict, repr=False, compare=False)
    # What other packages build once per cell and reuse (``collision.pairs.cell_pairs``).
    kept: dict = dataclasses.field(default_factory=dict, repr=False, compare=False)

    @property
    def frame_E(self):
        return self.plant.GetFrameByName("tool0", self.robot)

    def X_IE(self, q: np.ndarray) -> RigidTransform:
        """Flange pose in I from Drake's kinematics at joint vector q (6,) [rad]."""
        context = self.plant.CreateDefaultContext()
        self.plant.SetPositions(context, self.robot, q)
        return self.frame_E.CalcPoseInWorld(context)

    def exact_shape(self, g: GeometryId) -> ExactShape:
        """The ExactShape of collision geometry g (its Drake shape; a mesh by its hull),
        built once per cell: every collision check of a plan asks for the same shapes."""
        if g not in self._exact:
            inspector = self.diagram.scene_graph().model_inspector()
            self._exact[g] = exact_shape_of_drake(inspector.GetShape(g))
        return self._exact[g]

    def motion_radii(self) -> np.ndarray:
        """(6,) ρ_k [m]: no collision geometry outboard of joint k (the part included) is
        farther than ρ_k from the joint's origin, at any joint position (serial chain:
        ρ_k = max(reach of link k's geometry, |p_LkJk+1| + ρ_k+1), frames fixed in link k).
        Computed once per cell (the model is built and does not change)."""
        if self._motion_radii is None:
            self._motion_radii = self._reach()
        return self._motion_radii.copy()

    def _reach(self) -> np.ndarray:
        plant, context = self.plant, self.plant.CreateDefaultContext()
        inspector = self.diagram.scene_graph().model_inspector()
        joints = [plant.get_joint(j) for j in plant.GetJointIndices(self.robot)]
        joints = sorted(
            (j for j in joints if j.num_positions() == 1), key=lambda j: j.position_start()
        )
        rho = np.zeros(len(joints))
        for k in reversed(range(len(joints))):
            link = joints[k].child_body()  # L: link k; J: joint k's origin, on its axis
            p_LJ = joints[k].frame_on_child().GetFixedPoseInBodyFrame().translation()
            for body in plant.GetBodiesWeldedTo(link):
                X_LB = plant.CalcRelativeTransform(context, link.body_frame(), body.body_frame())
                for g in plant.GetCollisionGeometriesForBody(body):
                    p_LG = (X_LB @ inspector.GetPoseInFrame(g)).translation()
                    reach = np.linalg.norm(p_LG - p_LJ) + bounding_radius(inspector.GetShape(g))
                    rho[k] = max(rho[k], reach)
            if k + 1 < len(joints):  # N: the next joint's origin, fixed in L
                assert joints[k + 1].parent_body().index() == link.index(), "serial chain"
                p_LN = joints[k + 1].frame_on_parent().GetFixedPoseInBodyFrame().translation()
                rho[k] = max(rho[k], np.linalg.norm(p_LN - p_LJ) + rho[k + 1])
        return rho


def _add_welded_body(plant, name, X_parent_child, parent_frame):
    body = plant.AddRigidBody(
        name, plant.AddModelInstance(name), SpatialInertia.SolidSphereWithMass(1.0, 0.05)
    )
    plant.WeldFrames(parent_frame, body.body_frame(), X_parent_child)
    return body


def _register(plant, body, shape: CellShape, color) -> list[GeometryId]:
    """Register a shape's visual and collision geometry on a body (at X_BG = shape.X_OG)."""
    plant.RegisterVisualGeometry(
        body, shape.X_OG, shape.visual_shape(), f"{shape.name}.visual", color.rgba
    )
    pieces = shape.collision_shapes()
    return [
        plant.RegisterCollisionGeometry(
            body,
            shape.X_OG,
            piece,
            shape.name if len(pieces) == 1 else f"{shape.name}[{i}]",
            CoulombFriction(0.5, 0.5),
        )
        for i, piece in enumerate(pieces)
    ]


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
    part_shapes: Sequence[CellShape] = (),
    tool_shapes: Sequence[CellShape] = (),
    obstacles: Sequence[CellShape] = (),
    gripper_shapes: Sequence[CellShape] = (),
    allowed_contact: Sequence[tuple[str, str]] = (),
    meshcat=None,
) -> DrakeCell:
    """Build and finalize the cell's plant (paper §3: robot carries P past T).

    Args:
        robot: the robot record (its URDF is parsed unchanged).
        X_IB: robot base frame B (URDF base_link) in I.
        X_IT: fixed TCP frame T in I.
        X_PE: flange frame E (URDF tool0) in the part frame P.
        part_mesh, tool_mesh: optional mesh files, in P and T respectively (shapes named
            "part" and "tool"; scale: metres per file unit).
        part_shapes, tool_shapes: CellShapes posed in P and T.
        obstacles: CellShapes posed in I (anchored to the world).
        gripper_shapes: CellShapes posed in E (a "gripper" body welded to the flange;
            none: no gripper body).
        allowed_contact: pairs of shape (or robot link) names not to check.
        meshcat: a Meshcat to draw the cell in (adds a MeshcatVisualizer).

    Raises:
        ShapeError: a shape name used twice, or an unknown name in allowed_contact.
    """
    builder = RobotDiagramBuilder(time_step=0.0)
    plant = builder.plant()
    parser = builder.parser()
    parser.package_map().AddPackageXml(str(ROBOTS_DIR / "package.xml"))
    (model,) = parser.AddModels(str(robot.urdf_path))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("base_link", model), X_IB)
    part_shapes, tool_shapes = list(part_shapes), list(tool_shapes)
    if part_mesh:
        part_shapes.insert(0, mesh_shape("part", part_mesh, part_mesh_scale, key="part_mesh"))
    if tool_mesh:
        tool_shapes.insert(0, mesh_shape("tool", tool_mesh, tool_mesh_scale, key="tool_mesh"))
    part = _add_welded_body(plant, "part", X_PE.inverse(), plant.GetFrameByName("tool0", model))
    tool = _add_welded_body(plant, "tool", X_IT, plant.world_frame())
    gripper = None
    if gripper_shapes:
        gripper = _add_welded_body(
            plant, "gripper", RigidTransform(), plant.GetFrameByName("tool0", model)
        )
    links = {plant.get_body(b).name() for b in plant.GetBodyIndices(model)}
    names: set[str] = set()
    labels: dict[GeometryId, GeometryLabel] = {}
    for owner, body, shapes, color in (
        ("part", part, part_shapes, PART_COLOR),
        ("gripper", gripper, gripper_shapes, GRIPPER_COLOR),
        ("tool", tool, tool_shapes, TOOL_COLOR),
        ("obstacle", plant.world_body(), obstacles, OBSTACLE_COLOR),
    ):
        for shape in shapes:
            if shape.name in names or shape.name in links:
                raise ShapeError(OWNER_KEYS[owner], f"shape name {shape.name!r} used twice")
            names.add(shape.name)
            for geometry_id in _register(plant, body, shape, color):
                labels[geometry_id] = GeometryLabel(owner, shape.name, body.name(), shape)
    plant.Finalize()
    for body in (plant.get_body(b) for b in plant.GetBodyIndices(model)):
        for geometry_id in plant.GetCollisionGeometriesForBody(body):
            labels[geometry_id] = GeometryLabel("robot", body.name(), body.name())
    filter_contacts(builder.scene_graph(), plant, labels, part, allowed_contact)
    skipped = filter_self_pairs(builder.scene_graph(), plant, model, robot)
    held = held_contacts(builder.scene_graph(), labels, allowed_contact)
    visualizer = None
    if meshcat is not None:
        from pydrake.geometry import MeshcatVisualizer, MeshcatVisualizerParams

        visualizer = MeshcatVisualizer.AddToBuilder(
            builder.builder(), builder.scene_graph(), meshcat, MeshcatVisualizerParams()
        )
    diagram = builder.Build()
    return DrakeCell(
        diagram,
        plant,
        model,
        X_IB,
        X_IT,
        X_PE,
        labels,
        list(allowed_contact),
        visualizer,
        skipped,
        held,
    )


def build_cell_model(cell: Cell, cell_file: Path, robot: RobotModel, meshcat=None) -> DrakeCell:
    """The DrakeCell of a loaded cell file with all its shapes.

    The tool body sits at the cell's own X_IT: a free rotation of T about a symmetric
    tool's axis (plan.flange.X_IT) re-chooses the process frame, the tool does not turn.

    Raises:
        ShapeError: a bad shape entry or allowed_contact pair (one line naming the key).
    """
    geometry = cell_geometry(cell, cell_file)
    return build_drake_cell(
        robot,
        X_IB=transform(cell.robot.X_IB),
        X_IT=transform(cell.tool.X_IT),
        X_PE=transform(cell.part.X_PE),
        part_shapes=geometry.part,
        tool_shapes=geometry.tool,
        obstacles=geometry.obstacles,
        gripper_shapes=geometry.gripper,
        allowed_contact=geometry.allowed_contact,
        meshcat=meshcat,
    )
