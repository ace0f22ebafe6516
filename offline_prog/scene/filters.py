"""Which geometry pairs of a cell are checked: SceneGraph's collision filters.

MultibodyPlant filters every pair of geometries on bodies welded together, which in a
cell means the robot base, the fixed tool and the obstacles (all welded to the world):
a cable duct through the robot's base would never be seen. ``allow_fixed_layout`` puts
those pairs back in the collision check's context (robot base vs obstacles and tool,
tool vs obstacles; obstacles among themselves stay filtered: they stand on each other
by design). Then the intended
contacts (the part in its gripper, ``allowed_contact``) and the robot's own link pairs
that its self-collision matrix does not mark ``check`` are filtered out.

What holds what is never checked: the gripper against the flange link it is mounted on
(Drake: bodies welded together), the part against the gripper holding it and the
flange link (``filter_contacts``). :func:`held_contacts` lists those pairs with their
reason; everything else of the gripper (tool, obstacles, the other links) is checked.
"""

from __future__ import annotations

from pydrake.geometry import CollisionFilterDeclaration, GeometryId, GeometrySet

from offline_prog.robot.model import RobotModel
from offline_prog.scene.self_collision import read_matrix
from offline_prog.scene.shapes import ShapeError


def ids_by_name(labels) -> dict[str, list[GeometryId]]:
    """The collision GeometryIds of each shape name (a mesh has several pieces)."""
    by_name: dict[str, list[GeometryId]] = {}
    for geometry_id, label in labels.items():
        by_name.setdefault(label.name, []).append(geometry_id)
    return by_name


def allow_fixed_layout(scene_graph, plant, model, labels, context, allowed_contact=()) -> None:
    """Check the robot base vs obstacles and tool, and the tool vs obstacles, although
    they never move: their overlap is a layout error (checked once, held to contact).

    Applied to one SceneGraph ``context`` (the collision check's), so Drake IK with a
    minimum-distance constraint and the distance plots keep Drake's own filters: a
    base resting on its floor must not count there."""
    manager = scene_graph.collision_filter_manager(context)
    base = plant.GetBodyByName("base_link", model)
    fixed = {b.index() for b in plant.GetBodiesWeldedTo(plant.world_body())}
    owners = {"robot": [], "tool": [], "obstacle": []}
    for geometry_id, label in labels.items():
        if label.owner in owners and plant.GetBodyByName(label.body).index() in fixed:
            owners[label.owner].append(geometry_id)
    base_ids = [g for g in plant.GetCollisionGeometriesForBody(base)]
    for a, b in (
        (base_ids, owners["obstacle"]),
        (base_ids, owners["tool"]),
        (owners["tool"], owners["obstacle"]),
    ):
        if a and b:
            manager.Apply(CollisionFilterDeclaration().AllowBetween(GeometrySet(a), GeometrySet(b)))
    by_name = ids_by_name(labels)
    for pair in allowed_contact:  # intended contacts stay unchecked
        if all(name in by_name for name in pair):
            a, b = (GeometrySet(by_name[name]) for name in pair)
            manager.Apply(CollisionFilterDeclaration().ExcludeBetween(a, b))


def filter_contacts(scene_graph, plant, labels, part, allowed_contact) -> None:
    """Part vs the bodies it is welded to (the flange link, the gripper), and each
    allowed pair."""
    by_name = ids_by_name(labels)
    manager = scene_graph.collision_filter_manager()
    holders = [b for b in plant.GetBodiesWeldedTo(part) if b.index() != part.index()]
    part_ids = [g for g, label in labels.items() if label.owner == "part"]
    holder_ids = [g for b in holders for g in plant.GetCollisionGeometriesForBody(b)]
    if part_ids and holder_ids:
        manager.Apply(
            CollisionFilterDeclaration().ExcludeBetween(
                GeometrySet(part_ids), GeometrySet(holder_ids)
            )
        )
    for i, pair in enumerate(allowed_contact):
        for name in pair:
            if name not in by_name:
                known = ", ".join(sorted(by_name))
                raise ShapeError(
                    f"allowed_contact[{i}]", f"unknown shape {name!r} (known: {known})"
                )
        a, b = (GeometrySet(by_name[name]) for name in pair)
        manager.Apply(CollisionFilterDeclaration().ExcludeBetween(a, b))


# Why a pair of (owner, owner) is not checked when its shapes' bodies are welded together.
HELD_REASONS = {
    ("gripper", "robot"): "the gripper is mounted on the flange of {b}",
    ("part", "gripper"): "the gripper holds the part",
    ("part", "robot"): "the part is held at the flange of {b} (the gripper's contact)",
}


def held_contacts(scene_graph, labels, allowed_contact=()) -> list[tuple[str, str, str]]:
    """(a, b, reason) of each shape pair of the part and the gripper not checked
    because one holds the other (filtered in the model, and not an allowed_contact)."""
    inspector = scene_graph.model_inspector()
    allowed = {frozenset(pair) for pair in allowed_contact}
    held: dict[tuple[str, str], str] = {}
    for g, a in labels.items():
        for h, b in labels.items():
            reason = HELD_REASONS.get((a.owner, b.owner))
            names = (a.name, b.name)
            if reason is None or names in held or frozenset(names) in allowed:
                continue
            if inspector.CollisionFiltered(g, h):
                held[names] = reason.format(b=b.name)
    return [(a, b, reason) for (a, b), reason in held.items()]


def filter_self_pairs(scene_graph, plant, model, robot: RobotModel):
    """Exclude the robot's link pairs that its self-collision matrix does not mark
    ``check``; returns those pairs (None: the robot has no matrix, all are checked)."""
    try:
        pairs = read_matrix(robot.urdf_path.parent)
    except ValueError as error:
        raise ShapeError("robot.model", str(error)) from None
    if pairs is None:
        return None
    manager = scene_graph.collision_filter_manager()
    skipped = [p for p in pairs if p.kind != "check"]
    for pair in skipped:
        a, b = (plant.GetBodyByName(name, model) for name in (pair.a, pair.b))
        ids = [plant.GetCollisionGeometriesForBody(body) for body in (a, b)]
        if all(ids):
            manager.Apply(
                CollisionFilterDeclaration().ExcludeBetween(
                    GeometrySet(ids[0]), GeometrySet(ids[1])
                )
            )
    return skipped
