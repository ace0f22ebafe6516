"""The brute-force oracle of the seam order: every order (n!), each with its best
options by a shortest path through the layers of options, all orders at once. For
tests and scripts/bench_order.py only."""

import itertools

import numpy as np

from offline_prog.job.link_costs import LinkCosts


def brute_force_order(
    options, q_home, *, qd_max, qdd_max, n_seams: int, controller_joints=None
) -> tuple[float, list[int]]:
    """(least air time [s], option indices in run order) over every seam order."""
    costs = LinkCosts(options, q_home, qd_max, qdd_max, controller_joints)
    orders = np.array(list(itertools.permutations(range(n_seams))))  # (n!, n)
    by_seam = [[i for i, o in enumerate(options) if o[0] == k] for k in range(n_seams)]
    width = max(len(b) for b in by_seam)
    slot = np.array([b + [-1] * (width - len(b)) for b in by_seam])  # (n, width)
    into = np.where(slot >= 0, costs.into[slot], np.inf)
    out = np.where(slot >= 0, costs.out[slot], np.inf)
    empty = (slot[:, None, :, None] < 0) | (slot[None, :, None, :] < 0)
    link = np.where(empty, np.inf, costs.C[slot[:, None, :, None], slot[None, :, None, :]])
    cost, back = into[orders[:, 0]], []  # (n!, width)
    for a, b in zip(orders.T[:-1], orders.T[1:], strict=True):
        total = cost[:, :, None] + link[a, b]
        back.append(total.argmin(axis=1))
        cost = total.min(axis=1)
    total = cost + out[orders[:, -1]]
    best = int(total.min(axis=1).argmin())
    j = int(total[best].argmin())
    chosen = [int(slot[orders[best, -1], j])]
    for t in range(n_seams - 2, -1, -1):
        j = int(back[t][best, j])
        chosen.append(int(slot[orders[best, t], j]))
    return float(total[best].min()), chosen[::-1]
