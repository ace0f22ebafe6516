"""Certified clearance of one configuration and of a straight joint move, for planners
(the link moves of a job): the same geometry pairs, filters, clearances and motion bound
as :func:`~offline_prog.collision.check.check_trajectory`.

At q, every moving pair g has a *motion budget* b_g = (d_g − c̲_g) / c_g: the motion
bound M (Σ_k ρ_k |Δq_k|, see ``check``) by which the joints may move before pair g could
come closer than its clearance c̲_g (c_g = 1 when one side is fixed, 2 when both move).
A straight move q_a → q_b is certified by conservative advancement: from q_a, advance by
the smallest budget, re-measure, until the rest of the move fits into the budget; a
budget below ``MIN_ADVANCE_M`` or a negative one rejects the move. Distances are Drake's
(convex pieces of meshes: never larger than the original shapes', so conservative).
Pairs farther than ``REACH_M`` are not measured (their budget counts as (REACH_M − c̲)/c).
"""

from __future__ import annotations

import numpy as np

from offline_prog.collision.check import CheckedPairs
from offline_prog.scene.drake_cell import DrakeCell

REACH_M = 0.25  # pairs farther apart than this are not measured at a configuration
MIN_ADVANCE_M = 1e-4  # a move that must advance by less than this is rejected


class MotionChecker:
    """Clearance checks of configurations q (6,) [rad, URDF order] and straight moves.

    Args:
        cell: the Drake cell.
        clearance: robot and part vs everything else [m]; self_clearance: robot link vs
            robot link [m] (the pairs the self-collision matrix checks).
    """

    def __init__(self, cell: DrakeCell, *, clearance: float, self_clearance: float):
        self.pairs = pairs = CheckedPairs(cell, fixed_layout=True)
        clear_s = np.where(pairs.is_self, self_clearance, clearance)
        moving = pairs.c > 0  # the fixed layout does not move: checked with the seams
        clear_g = clear_s[pairs.shape_of]
        # (id_A, id_B) in either order ↦ (clearance [m], c) of each moving pair.
        self.pair = {}
        for g, (a, b) in enumerate(pairs.ids):
            if moving[g]:
                entry = (float(clear_g[g]), float(pairs.c[g]))
                self.pair[a, b] = self.pair[b, a] = entry
        self.far = (REACH_M - float(clear_g.max())) / 2.0  # the budget of unmeasured pairs
        self.rho = cell.motion_radii()
        self.states, self.motions = 0, 0

    def budget(self, q: np.ndarray) -> float:
        """min_g b_g [m of motion bound] at q: negative when a pair is below its clearance."""
        self.states += 1
        self.pairs.set(q)
        budget, pair = self.far, self.pair
        for r in self.pairs.query.ComputeSignedDistancePairwiseClosestPoints(REACH_M):
            entry = pair.get((r.id_A, r.id_B))
            if entry is not None:
                budget = min(budget, (r.distance - entry[0]) / entry[1])
        return budget

    def min_distance(self, q: np.ndarray) -> float:
        """The smallest distance of any moving pair at q [m] (REACH_M if none nearer)."""
        self.pairs.set(q)
        results = self.pairs.query.ComputeSignedDistancePairwiseClosestPoints(REACH_M)
        moving = [r.distance for r in results if (r.id_A, r.id_B) in self.pair]
        return min(moving, default=REACH_M)

    def clear(self, q: np.ndarray) -> bool:
        """Every moving pair at least its clearance apart at q."""
        return bool(self.budget(q) >= 0.0)

    def move_clear(self, q_a: np.ndarray, q_b: np.ndarray) -> bool:
        """Every configuration on the straight line q_a → q_b is clear (certified)."""
        self.motions += 1
        step = q_b - q_a
        total = float(np.abs(step) @ self.rho)  # the motion bound of the whole move [m]
        done = 0.0  # of total
        while True:
            budget = self.budget(q_a + (done / total if total else 0.0) * step)
            if budget < 0.0:
                return False
            if budget >= total - done:
                return True
            if budget < MIN_ADVANCE_M:
                return False
            done += budget
