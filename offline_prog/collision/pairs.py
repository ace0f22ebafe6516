"""The geometry pairs a collision check measures, and how fast each pair's distance can
change as the joints move.

Motion bound (Schwarzer, Saha & Latombe, "Adaptive dynamic collision checking for single
and multiple articulated robots in complex environments", IEEE T-RO 21(3), 2005), per
pair: seen from link i (a body fixed to it), a point of a body fixed to link j > i moves
only by the joints i+1 … j between them, by at most Σ_{k=i+1..j} ρ_k |Δq_k| along the
straight line from q_a to q_b, where ρ_k bounds the distance of every geometry outboard
of joint k from a point on its axis (``DrakeCell.motion_radii``). The distance of a pair
A (on link i) and B (on link j) changes by no more than B moves seen from A, so by at most
that bound: its *span* (i, j) names the joints it counts. Link 0 is the world (robot
base, tool, obstacles); the gripper and the part move with the flange link. A pair whose
two sides sit on one link (both fixed to the world) never changes.

The gripper on the flange shows why the span matters: it sits 9 mm in front of the
wrist link behind the flange whatever the other joints do, and only the last joint moves
one against the other; counted with every joint's motion, each check of a link move
advanced by a few millimetres of motion bound.
"""

from __future__ import annotations

import threading

import numpy as np

from offline_prog.scene.drake_cell import DrakeCell
from offline_prog.scene.exact_distance import bounding_radius, exact_distance, exact_shape
from offline_prog.scene.filters import allow_fixed_layout

OWNER_ORDER = ("part", "gripper", "tool", "robot", "obstacle")


def _chain(cell: DrakeCell) -> list:
    """The robot's one-position joints in order (a serial chain: joint k's child link)."""
    plant = cell.plant
    joints = [plant.get_joint(j) for j in plant.GetJointIndices(cell.robot)]
    return sorted((j for j in joints if j.num_positions() == 1), key=lambda j: j.position_start())


def chain_links(cell: DrakeCell) -> dict[str, int]:
    """Body name ↦ the link it moves with: k for joint k's child link and every body
    welded to it (1-based, the serial chain of revolute joints), 0 for the world's."""
    plant = cell.plant
    links = {body.name(): 0 for body in plant.GetBodiesWeldedTo(plant.world_body())}
    for k, joint in enumerate(_chain(cell), start=1):
        links |= {body.name(): k for body in plant.GetBodiesWeldedTo(joint.child_body())}
    return links


def axis_reach(cell: DrakeCell) -> dict:
    """GeometryId ↦ how far [m] the collision geometry reaches from the axis of the
    joint whose child link it moves with (its bounding sphere's farthest point), for
    every geometry on a moving link: turning that joint alone moves it no farther."""
    plant, context = cell.plant, cell.plant.CreateDefaultContext()
    inspector = cell.diagram.scene_graph().model_inspector()
    reach = {}
    for joint in _chain(cell):
        link = joint.child_body()
        X_LM = joint.frame_on_child().GetFixedPoseInBodyFrame()  # M: the joint's frame
        axis_L, p_LO = X_LM.rotation() @ joint.revolute_axis(), X_LM.translation()
        for body in plant.GetBodiesWeldedTo(link):
            X_LB = plant.CalcRelativeTransform(context, link.body_frame(), body.body_frame())
            for g in plant.GetCollisionGeometriesForBody(body):
                p = (X_LB @ inspector.GetPoseInFrame(g)).translation() - p_LO
                off_axis = np.linalg.norm(p - (p @ axis_L) * axis_L)
                reach[g] = off_axis + bounding_radius(inspector.GetShape(g))
    return reach


class Pairs:
    """The unfiltered geometry pairs g of a cell, grouped into shape pairs s, their spans
    (the joints that move one side against the other), and their signed distances at a
    joint vector (Drake) or on the original shapes (FCL).

    Attributes:
        ids: (id_A, id_B) of each geometry pair g; names: (a, b) of each shape pair s.
        shape_of: (G,) s of each g; c: (G,) 1 where the pair moves, 0 where it never does.
        spans: (i, j) link pairs, i < j, or (0, 0); span_of: (G,) the span index of each g.
        is_self, is_fixed, has_mesh: (S,) robot link pairs; pairs that never move (held
            to contact only); pairs with a mesh side. groups: (S,) e.g. "part-obstacle".
    """

    def __init__(self, cell: DrakeCell, *, fixed_layout: bool = False):
        self.cell, plant = cell, cell.plant
        self.context = cell.diagram.CreateDefaultContext()
        self.plant_context = plant.GetMyMutableContextFromRoot(self.context)
        scene_graph = cell.diagram.scene_graph()
        self.sg_context = scene_graph.GetMyMutableContextFromRoot(self.context)
        if fixed_layout:  # in this context only: IK and plots keep Drake's filters
            allow_fixed_layout(
                scene_graph, plant, cell.robot, cell.labels, self.sg_context, cell.allowed_contact
            )
        # The robot's joints are the plant's only positions: the whole plant's are set.
        assert plant.num_positions() == plant.num_positions(cell.robot), "robot only"
        self._set_positions = plant.SetPositions
        # The query object reads the context at each query (poses updated on demand):
        # evaluated once, it answers for the positions last set.
        self.query = scene_graph.get_query_output_port().Eval(self.sg_context)
        link = chain_links(cell)
        rank = {owner: i for i, owner in enumerate(OWNER_ORDER)}
        self.ids, self.names, self.spans, shape_of, span_of = [], [], [], [], []
        self.outer = []  # the GeometryId of each pair's side on the outer link
        for r in self.query.ComputeSignedDistancePairwiseClosestPoints():
            labels = (cell.labels[r.id_A], cell.labels[r.id_B])
            a, b = sorted(labels, key=lambda label: (rank[label.owner], label.name))
            if (a.name, b.name) not in self.names:
                self.names.append((a.name, b.name))
            self.ids.append((r.id_A, r.id_B))
            shape_of.append(self.names.index((a.name, b.name)))
            links = (link[labels[0].body], link[labels[1].body])
            self.outer.append(r.id_A if links[0] >= links[1] else r.id_B)
            span = tuple(sorted(links))
            if span not in self.spans:
                self.spans.append(span)
            span_of.append(self.spans.index(span))
        self.shape_of, self.span_of = np.array(shape_of, dtype=int), np.array(span_of, dtype=int)
        # How fast the distance can change per unit of the span's motion bound.
        self.c = np.array([float(self.spans[k][0] != self.spans[k][1]) for k in span_of])
        robot = {label.name for label in cell.labels.values() if label.owner == "robot"}
        # Robot link vs robot link: held to the self-clearance, per shape pair s.
        self.is_self = np.array([a in robot and b in robot for a, b in self.names], dtype=bool)
        # Fixed layout (robot base, tool, obstacles): never moves, held to contact only.
        fixed_s = np.ones(len(self.names), dtype=bool)
        fixed_s[self.shape_of[self.c > 0]] = False
        self.is_fixed = fixed_s
        owner = {label.name: label.owner for label in cell.labels.values()}
        self.groups = [
            "robot-self" if owner[a] == owner[b] else f"{owner[a]}-{owner[b]}"
            for a, b in self.names
        ]
        mesh = {lb.name for lb in cell.labels.values() if lb.shape and lb.shape.kind == "mesh"}
        self.has_mesh = np.array([a in mesh or b in mesh for a, b in self.names], dtype=bool)
        self._exact, self.exact_checks, self.evaluations = {}, 0, 0

    def span_radii(self, rho: np.ndarray) -> np.ndarray:
        """(n_spans, 6) ρ_k [m] of the joints each span counts (0 for the others): a
        move Δq (6,) moves the sides of a pair of span k by at most |Δq| @ row k."""
        joint = np.arange(1, len(rho) + 1)
        return np.array([np.where((joint > i) & (joint <= j), rho, 0.0) for i, j in self.spans])

    def pair_radii(self, rho: np.ndarray) -> np.ndarray:
        """(G, 6) each pair's :meth:`span_radii` row with the span's last joint j tighter:
        the outer side turns rigidly about joint j's axis, so that joint moves it by at
        most its own reach from the axis (``axis_reach``: a flange-mounted gripper's
        few centimetres instead of the farthest corner of the part)."""
        rows, reach = self.span_radii(rho)[self.span_of], axis_reach(self.cell)
        for g, outer in enumerate(self.outer):
            i, j = self.spans[self.span_of[g]]
            if j > i:
                rows[g, j - 1] = min(rows[g, j - 1], reach[outer])
        return rows

    def set(self, q: np.ndarray) -> None:
        """Set the joint positions q (6,) [rad] the next distances are measured at."""
        self._set_positions(self.plant_context, q)

    def distance(self, g: int) -> float:
        """Drake's signed distance [m] of geometry pair g at the last set q."""
        self.evaluations += 1
        return self.query.ComputeSignedDistancePairClosestPoints(*self.ids[g]).distance

    def _components(self, name: str):
        """[(ExactShape, a GeometryId giving its pose X_IG)] of a shape name."""
        if name not in self._exact:
            ids = [g for g, label in self.cell.labels.items() if label.name == name]
            shape = self.cell.labels[ids[0]].shape
            self._exact[name] = (
                [(exact_shape(shape.kind, shape.size_m, shape.mesh), ids[0])]
                if shape is not None
                else [(self.cell.exact_shape(g), g) for g in ids]
            )
        return self._exact[name]

    def exact(self, q: np.ndarray, s: int) -> float:
        """FCL's distance [m] of shape pair s on the original shapes at q."""
        self.set(q)
        self.exact_checks += 1
        a, b = (self._components(name) for name in self.names[s])
        pose = self.query.GetPoseInWorld
        return min(exact_distance(sa, pose(ga), sb, pose(gb)) for sa, ga in a for sb, gb in b)


def cell_pairs(cell: DrakeCell, *, fixed_layout: bool = False) -> Pairs:
    """The cell's :class:`Pairs`, built once per cell, layout and thread (its context,
    filters, pairs and exact shapes; ~8 ms a build, a sixth of a seam's collision check)
    and kept in ``cell.kept``, its counters set to zero. Every measurement sets the
    joint positions it is made at, so one check leaves nothing the next one reads."""
    key = (Pairs, fixed_layout, threading.get_ident())
    pairs = cell.kept.get(key)
    if pairs is None:
        pairs = cell.kept[key] = Pairs(cell, fixed_layout=fixed_layout)
    pairs.exact_checks = pairs.evaluations = 0
    return pairs
