"""Certified clearance of one configuration and of a straight joint move, for planners
(the link moves of a job): the same geometry pairs, filters, clearances and motion bounds
as :func:`~offline_prog.collision.check.check_trajectory`.

At q, every moving pair g has a margin m_g = d_g − c̲_g above its clearance c̲_g. Along a
straight move q_a → q_b, a fraction Δs of the move changes the pair's distance by at most
Δs · M_g, M_g = Σ_k ρ_k |q_b,k − q_a,k| over the joints of its span (``pairs``: the
joints between its two sides; the last of them with the outer side's own reach from its
axis, ``Pairs.pair_radii``). The move is certified by conservative advancement: from
s = 0, advance by the smallest m_g / M_g, re-measure, until the rest of the move fits; an
advance below ``MIN_ADVANCE_M`` of the whole move's bound (every joint) or a negative
margin rejects it. Distances are Drake's (convex pieces of meshes: never larger than the
original shapes', so conservative). Pairs farther than ``REACH_M`` are not measured
(their margin counts as REACH_M − c̲, against the whole move's bound).
"""

from __future__ import annotations

import numpy as np

from offline_prog.collision.pairs import Pairs
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
        self.pairs = pairs = Pairs(cell, fixed_layout=True)
        clear_s = np.where(pairs.is_self, self_clearance, clearance)
        moving = pairs.c > 0  # the fixed layout does not move: checked with the seams
        clear_g = clear_s[pairs.shape_of]
        # (id_A, id_B) in either order ↦ (clearance [m], g) of each moving pair.
        self.pair = {}
        for g, (a, b) in enumerate(pairs.ids):
            if moving[g]:
                self.pair[a, b] = self.pair[b, a] = (float(clear_g[g]), g)
        self.far = REACH_M - float(clear_g.max())  # the margin of unmeasured pairs [m]
        self.rho = cell.motion_radii()
        self.pair_rho = pairs.pair_radii(self.rho)  # (G, 6) [m]
        self.states, self.motions = 0, 0

    def margins(self, q: np.ndarray) -> list[tuple[float, int]]:
        """(d_g − c̲_g [m], g) of each moving pair g nearer than REACH_M at q: negative
        for a pair below its clearance."""
        self.states += 1
        self.pairs.set(q)
        pair, out = self.pair, []
        for r in self.pairs.query.ComputeSignedDistancePairwiseClosestPoints(REACH_M):
            entry = pair.get((r.id_A, r.id_B))
            if entry is not None:
                out.append((r.distance - entry[0], entry[1]))
        return out

    def min_distance(self, q: np.ndarray) -> float:
        """The smallest distance of any moving pair at q [m] (REACH_M if none nearer)."""
        self.pairs.set(q)
        results = self.pairs.query.ComputeSignedDistancePairwiseClosestPoints(REACH_M)
        moving = [r.distance for r in results if (r.id_A, r.id_B) in self.pair]
        return min(moving, default=REACH_M)

    def clear(self, q: np.ndarray) -> bool:
        """Every moving pair at least its clearance apart at q."""
        return all(margin >= 0.0 for margin, _ in self.margins(q))

    def move_clear(self, q_a: np.ndarray, q_b: np.ndarray) -> bool:
        """Every configuration on the straight line q_a → q_b is clear (certified)."""
        self.motions += 1
        step = q_b - q_a
        motion = (self.pair_rho @ np.abs(step)).tolist()  # each pair's bound of the move [m]
        total = float(np.abs(step) @ self.rho)  # every joint's: the whole move's bound [m]
        done = 0.0  # of the move, s ∈ [0, 1]
        while True:
            advance = self.far / total if total else np.inf
            for margin, g in self.margins(q_a + done * step):
                if margin < 0.0:
                    return False
                if motion[g] > 0.0:
                    advance = min(advance, margin / motion[g])
            if done + advance >= 1.0:
                return True
            if advance * total < MIN_ADVANCE_M:
                return False
            done += advance
