"""A candidate's collisions at a coarse step, before it is planned.

The candidate's cell (its Drake model, the pairs and clearances ``collision.check``
holds every plan to) at a few samples of the planner's first variant: the approach's
start, the seam's screen samples, the retract's end; at the samples only, not between
them. Two answers:

* the fixed layout (robot base, tool, obstacles: pairs that never move) in contact:
  no configuration helps, the candidate cannot be planned (sound; a mesh pair is
  decided on its original triangles, as the check decides it);
* a moving pair below its clearance on that variant: the planner's first attempt
  collides and the plan goes to collision avoidance (other turns and branches), which
  may or may not find a way: no verdict, a rank (after the candidates whose first
  variant is clear).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.collision.check import TOUCH_TOL_M
from offline_prog.collision.pairs import Pairs
from offline_prog.scene.drake_cell import DrakeCell

LOOK_SAMPLES = 16  # seam samples looked at (of the screen's), ends included


@dataclasses.dataclass(frozen=True)
class CollisionLook:
    """What the coarse look found.

    Attributes:
        layout: the fixed layout's overlapping pair "a – b" ("" when none).
        first_collides: a moving pair is below its clearance on the first variant.
        worst: the pair furthest below its clearance there ("" when none).
    """

    layout: str
    first_collides: bool
    worst: str


def look_rows(q: np.ndarray) -> np.ndarray:
    """(≤ LOOK_SAMPLES, 6) rows of a joint path q (N, 6), evenly spaced, ends included."""
    return q[np.unique(np.linspace(0, len(q) - 1, LOOK_SAMPLES).round().astype(int))]


def collision_look(
    scene: DrakeCell, rows: np.ndarray, *, clearance: float, self_clearance: float
) -> CollisionLook:
    """The coarse look at the joint rows (M, 6) [rad] (see the module)."""
    pairs = Pairs(scene, fixed_layout=True)
    clear_s = np.where(pairs.is_self, self_clearance, clearance)
    layout, worst, deepest = "", "", 0.0
    for i, q_i in enumerate(rows):
        pairs.set(q_i)
        for g, s in enumerate(pairs.shape_of):
            fixed = pairs.c[g] == 0.0
            if fixed and i > 0:
                continue  # the fixed layout is the same at every sample
            d = pairs.distance(g)
            name = " – ".join(pairs.names[s])
            if fixed:
                if d < -TOUCH_TOL_M and pairs.has_mesh[s]:
                    d = pairs.exact(q_i, s)  # as the check decides a mesh pair
                if d < -TOUCH_TOL_M and not layout:
                    layout = name
                continue
            if d < clear_s[s] and pairs.has_mesh[s]:
                d = pairs.exact(q_i, s)  # Drake's convex pieces only bound a mesh's distance
            if d - clear_s[s] < deepest:
                deepest, worst = d - clear_s[s], name
    return CollisionLook(layout, bool(worst), worst)
