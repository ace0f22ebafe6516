"""Link-time estimates between seam options, and the best options for a seam order.

:func:`ptp_time` estimates a link (see :mod:`offline_prog.job.order`). :class:`LinkCosts`
computes every estimate once, as arrays, and answers the one question the order search
asks over and over: given a seam order, which option of each seam makes the least air
time home → … → home, and how long is it (a shortest path through the layers of options,
O(n w²) for n seams of at most w options each)?

For the search the estimates are also kept seam by seam: ``D[a, b, i, j]`` is the link
from option slot i of seam a to slot j of seam b, with seam index n standing for home
(one slot, 0) and ∞ for empty slots, so that a tour reads ``[n, seam₁, …, seam_n, n]``
and every step of the dynamic programme is one gather, add and min over many orders at
once. A candidate order that differs from the current one only between two positions is
costed on that window alone, from the current order's prefix and suffix tables
(``forward``, ``backward``).
"""

from __future__ import annotations

import numpy as np


def ptp_time(q_a, q_b, qd_max, qdd_max) -> np.ndarray:
    """(...) the synchronised rest-to-rest move's duration [s] between (..., 6) joint
    vectors [rad] under joint limits qd_max [rad/s], qdd_max [rad/s²] (see job.order)."""
    d = np.abs(np.asarray(q_b, dtype=float) - np.asarray(q_a, dtype=float))
    v, a = np.asarray(qd_max, dtype=float), np.asarray(qdd_max, dtype=float)
    triangle = d <= v**2 / a
    t = np.where(triangle, 2.0 * np.sqrt(d / a), d / v + v / a)
    return t.max(axis=-1)


class LinkCosts:
    """Link estimates between options: ``into[o]`` from home, ``out[o]`` to home,
    ``C[o, p]`` option o's end to option p's start [s]; the same by seam in ``D``.

    Args:
        options: [(seam index, label, q_in (6,), q_out (6,))], seams 0 .. n − 1.
        q_home: (6,) [rad]; qd_max, qdd_max: (6,) joint limits (controller axes).
        controller_joints: maps URDF q to the controller's axes (None: the same).
    """

    def __init__(self, options, q_home, qd_max, qdd_max, controller_joints=None):
        to_c = controller_joints or (lambda q: q)
        self.seam = np.array([o[0] for o in options], dtype=int)
        q_in = to_c(np.array([o[2] for o in options], dtype=float))
        q_out = to_c(np.array([o[3] for o in options], dtype=float))
        home = to_c(np.asarray(q_home, dtype=float))
        self.into = ptp_time(home, q_in, qd_max, qdd_max)
        self.out = ptp_time(q_out, home, qd_max, qdd_max)
        self.C = ptp_time(q_out[:, None, :], q_in[None, :, :], qd_max, qdd_max)
        self.n = n = int(self.seam.max()) + 1
        self.of_seam = [np.flatnonzero(self.seam == k) for k in range(n)]
        self.width = w = max(len(o) for o in self.of_seam)
        slots = np.full((n, w), -1)
        for k, found in enumerate(self.of_seam):
            slots[k, : len(found)] = found
        valid, s = slots >= 0, np.maximum(slots, 0)
        D = np.full((n + 1, n + 1, w, w), np.inf)
        pairs = valid[:, None, :, None] & valid[None, :, None, :]
        D[:n, :n] = np.where(pairs, self.C[s[:, None, :, None], s[None, :, None, :]], np.inf)
        D[n, :n, 0, :] = np.where(valid, self.into[s], np.inf)
        D[:n, n, :, 0] = np.where(valid, self.out[s], np.inf)
        self.slots, self.D = slots, D
        self.at_home = np.full(w, np.inf)  # the tour's first and last "options": home
        self.at_home[0] = 0.0

    def layered(self, seams: list[int]) -> tuple[float, list[int]]:
        """The best options for seams run in this order: (air time, option indices)."""
        layer = self.of_seam[seams[0]]
        cost, back = self.into[layer], []
        for k in seams[1:]:
            nxt = self.of_seam[k]
            total = cost[:, None] + self.C[np.ix_(layer, nxt)]
            back.append((layer, np.argmin(total, axis=0)))
            cost, layer = total.min(axis=0), nxt
        total = cost + self.out[layer]
        j = int(np.argmin(total))
        chosen = [int(layer[j])]
        for prev_layer, arg in reversed(back):
            j = int(arg[j])
            chosen.append(int(prev_layer[j]))
        return float(total.min()), chosen[::-1]

    def links(self, sequence: list[int]) -> list[float]:
        """Each link's estimate [s] of an option sequence, home → … → home."""
        first = [float(self.into[sequence[0]])]
        middle = [float(self.C[a, b]) for a, b in zip(sequence[:-1], sequence[1:], strict=True)]
        return first + middle + [float(self.out[sequence[-1]])]

    def tour(self, order: np.ndarray) -> np.ndarray:
        """(n + 2,) the seam order (n,) with home (index n) at both ends."""
        return np.concatenate([[self.n], order, [self.n]])

    def forward(self, tour: np.ndarray) -> np.ndarray:
        """(n + 2, w): [p, j] the least time from home to slot j of tour[p] [s]."""
        F = np.empty((len(tour), self.width))
        F[0] = self.at_home
        for p in range(1, len(tour)):
            F[p] = (F[p - 1][:, None] + self.D[tour[p - 1], tour[p]]).min(axis=0)
        return F

    def backward(self, tour: np.ndarray) -> np.ndarray:
        """(n + 2, w): [p, i] the least time from slot i of tour[p] on to home [s]."""
        B = np.empty((len(tour), self.width))
        B[-1] = self.at_home
        for p in range(len(tour) - 2, -1, -1):
            B[p] = (self.D[tour[p], tour[p + 1]] + B[p + 1][None, :]).min(axis=1)
        return B

    def window_times(self, window, lo, tour, F, B) -> np.ndarray:
        """(K,) air times [s] of tours equal to ``tour`` (n + 2,) but for positions
        lo .. lo + L − 1, which hold ``window`` (K, L) (lo: (K,), ≥ 1), from the
        tour's tables F and B."""
        prev, S = tour[lo - 1], F[lo - 1]  # (K,), (K, w)
        for t in range(window.shape[1]):
            S = (S[:, :, None] + self.D[prev, window[:, t]]).min(axis=1)
            prev = window[:, t]
        after = lo + window.shape[1]
        total = S[:, :, None] + self.D[prev, tour[after]] + B[after][:, None, :]
        return total.min(axis=(1, 2))

    def window_work(self, count: int, length: int) -> int:
        """Link estimates ``window_times`` adds up for ``count`` windows of ``length``."""
        return count * (length + 1) * self.width**2

    def lower_bound(self) -> float:
        """No tour takes less [s]: each seam and home entered by its cheapest link from
        another seam or home (or each left by its cheapest, whichever sum is larger)."""
        D = self.D.copy()
        D[np.arange(self.n), np.arange(self.n)] = np.inf  # a seam never follows itself
        entering = D.min(axis=(0, 2)).min(axis=1)  # (n + 1,) per seam and home
        leaving = D.min(axis=(1, 3)).min(axis=1)
        return float(max(entering.sum(), leaving.sum()))
