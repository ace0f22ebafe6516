"""A seam run's planned samples, as the writers that place their own points on it
(UR ``movel``/``movep``, FANUC ``L``) take them: the job's approach rows (from the
approach's start, the link's end), the seam's densified samples, the job's retract
rows (to the retract's end, the next link's first row).

On a flying seam (``entry: flying``) the densified samples run on past the seam's
ends (its lead-in and lead-out, path position σ < 0 and σ > L, up to the whole
approach and retract), so the job's rows they cover are left out: each planned pose
appears once, in time order. Time: the densified samples carry
the seam's own clock; the job's time of σ = 0 is the process segment's first row.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.export.record import SeamRun

TIME_TOL_S = 1e-9  # a job row within this of a densified sample's time is that sample


@dataclasses.dataclass(frozen=True)
class RunSamples:
    """A seam run's planned samples from its approach's start to its retract's end.

    Attributes:
        path_m: (K,) path position σ [m], non-decreasing (the retract's last row, the
            next link's, continues it by its distance from the row before).
        t: (K,) job time [s], increasing.
        q: (K, 6) URDF joints [rad].
        X_BP: (K, 4, 4) the part P in the robot base B.
        seam_points: (M,) indices of the seam's points (the writer's ``PointRule``).
        first, last: indices of the first and last of the seam's points (on a flying
            seam the densified samples' ends: where its approach starts and its retract
            ends when those are densified too).
    """

    path_m: np.ndarray
    t: np.ndarray
    q: np.ndarray
    X_BP: np.ndarray
    seam_points: np.ndarray
    first: int
    last: int


def run_samples(rows, run: SeamRun) -> RunSamples:
    """The samples of ``run`` (module docstring) from the job's ``rows``
    (``JobProgramData.job``: t, path_m, q, X_BE, X_EP, X_PT)."""
    segments = {s.kind: s for s in run.segments}
    dense, idx = run.process.data, run.process.indices
    approach, retract = segments.get("approach"), segments.get("retract")
    a_rows = np.arange(approach.start, approach.stop) if approach else np.arange(0)
    r_rows = np.arange(0)
    if retract:
        r_rows = np.arange(retract.start + 1, min(retract.stop, len(rows.t) - 1) + 1)
    # The job's rows the densified samples cover (a flying seam's: its leads, or the
    # whole approach and retract) are left out: each planned pose once, in time order.
    t0 = rows.t[segments["process"].start] - np.interp(0.0, dense.path_m, dense.t)
    a_rows = a_rows[rows.t[a_rows] < dense.t[0] + t0 - TIME_TOL_S]
    r_rows = r_rows[rows.t[r_rows] > dense.t[-1] + t0 + TIME_TOL_S]
    path_r = rows.path_m[r_rows].copy()
    if len(path_r) > 1 and np.isnan(path_r[-1]):  # the retract's end: the next link's row
        gap = np.linalg.norm(rows.X_PT[r_rows[-1], :3, 3] - rows.X_PT[r_rows[-2], :3, 3])
        path_r[-1] = path_r[-2] + gap
    X_BE = np.concatenate([rows.X_BE[a_rows], dense.X_BE, rows.X_BE[r_rows]])
    return RunSamples(
        path_m=np.concatenate([rows.path_m[a_rows], dense.path_m, path_r]),
        t=np.concatenate([rows.t[a_rows], dense.t + t0, rows.t[r_rows]]),
        q=np.concatenate([rows.q[a_rows], dense.q, rows.q[r_rows]]),
        X_BP=X_BE @ rows.X_EP,
        seam_points=len(a_rows) + idx,
        first=len(a_rows) + int(idx[0]),
        last=len(a_rows) + int(idx[-1]),
    )
