"""Joint path by Drake InverseKinematics, for robots without a closed-form solver.

The general fallback of ``joint_plan``: the flange poses on the σ grid are solved
one after the other, each seeded with the previous solution (so the whole path
stays on one configuration branch). Several start configurations are tried
(zero, the middle of the limits, seeded random ones); each distinct first
solution is carried along the path, and the path with the largest joint-limit
margin wins. q(σ) between grid points is a quintic interpolating spline, so its
σ-derivatives are smooth and the final samples need no further solves.
"""

from __future__ import annotations

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.tree import JacobianWrtVariable
from scipy.interpolate import make_interp_spline

from offline_prog.errors import Failure
from offline_prog.joints.drake_ik import PoseIk
from offline_prog.joints.path_ik import MAX_JOINT_STEP_RAD, BranchResult
from offline_prog.scene.drake_cell import build_drake_cell
from offline_prog.timing.joint_timing import JointRates

N_RANDOM_SEEDS = 6
MAX_START_BRANCHES = 4
DISTINCT_RAD = 1e-3


class DrakeIkPath:
    """q(σ) along the flange path from Drake IK (same interface as BranchPath).

    Args:
        robot: the robot record; X_IB: its base in I; flange: X_IE(s);
        parameter: σ ↦ s.
    """

    def __init__(self, robot, X_IB, flange, parameter):
        self.robot, self.X_IB, self.flange, self.parameter = robot, X_IB, flange, parameter
        cell = build_drake_cell(robot, X_IB=X_IB, X_IT=flange.X_IT, X_PE=flange.X_PE)
        self.cell = cell
        self.ik = PoseIk(cell)
        self.branch = -1  # not an analytic branch
        self._spline = None

    def _targets(self, sigma):
        f = self.flange(self.parameter.s(sigma)[0])
        return f.p_IE, f.R_IE

    def _solve_along(self, p_IE, R_IE, q_start) -> BranchResult:
        q = np.empty((len(p_IE), 6))
        seed = q_start
        for i in range(len(p_IE)):
            q[i], ok, _, _ = self.ik.solve(p_IE[i], R_IE[i], seed)
            if not ok:
                return BranchResult(
                    -1, q, False, -np.inf, "out of reach (Drake IK)", i, Failure.OUT_OF_REACH
                )
            if i and np.abs(q[i] - q[i - 1]).max() > MAX_JOINT_STEP_RAD:
                return BranchResult(
                    -1,
                    q,
                    False,
                    -np.inf,
                    "singularity (the configuration flips)",
                    i,
                    Failure.SINGULARITY,
                )
            seed = q[i]
        margin = float(
            np.minimum(q.min(0) - self.robot.q_lower, self.robot.q_upper - q.max(0)).min()
        )
        return BranchResult(-1, q, True, margin, "", -1)

    def choose(self, grid: np.ndarray) -> BranchResult:
        """Solve the grid from several starts; keep the path with the largest margin."""
        p_IE, R_IE = self._targets(grid)
        lower, upper = self.robot.q_lower, self.robot.q_upper
        rng = np.random.default_rng(0)
        seeds = [np.clip(np.zeros(6), lower, upper), 0.5 * (lower + upper)]
        seeds += list(
            rng.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi), (N_RANDOM_SEEDS, 6))
        )
        starts = []
        for seed in seeds:
            q0, ok, _, _ = self.ik.solve(p_IE[0], R_IE[0], seed)
            if ok and all(np.abs(q0 - s).max() > DISTINCT_RAD for s in starts):
                starts.append(q0)
        if not starts:
            return BranchResult(
                -1,
                np.full((len(grid), 6), np.nan),
                False,
                -np.inf,
                "out of reach (Drake IK)",
                0,
                Failure.OUT_OF_REACH,
            )
        results = [self._solve_along(p_IE, R_IE, q0) for q0 in starts[:MAX_START_BRANCHES]]
        best = max(results, key=lambda r: (r.feasible, r.margin_rad, r.sample))
        if best.feasible:
            self._spline = make_interp_spline(grid, best.q, k=5, axis=0)
        return best

    def poses(self, sigma: np.ndarray) -> np.ndarray:
        """(N, 4, 4) X_BE at σ (for singularity reports)."""
        p_IE, R_IE = self._targets(sigma)
        X_BI = self.X_IB.inverse()
        out = np.empty((len(sigma), 4, 4))
        for i in range(len(sigma)):
            out[i] = (X_BI @ RigidTransform(RotationMatrix(R_IE[i]), p_IE[i])).GetAsMatrix4()
        return out

    def rates(self, sigma: np.ndarray, q_near: np.ndarray | None = None) -> JointRates:
        """q, q′, q″ at σ from the quintic spline through the grid solutions."""
        assert self._spline is not None, "choose() must succeed first"
        return JointRates(
            sigma, self._spline(sigma), self._spline(sigma, 1), self._spline(sigma, 2)
        )

    def singularity_distances(self, q: np.ndarray, sigma: np.ndarray) -> dict:
        """{"jacobian": (N,) smallest singular value of the flange's spatial-velocity
        Jacobian (angular rows scaled by 1 m) — zero at any singularity}."""
        plant, cell = self.cell.plant, self.cell
        context = plant.CreateDefaultContext()
        frame_E = cell.frame_E
        smallest = np.empty(len(q))
        for i in range(len(q)):
            plant.SetPositions(context, cell.robot, q[i])
            J = plant.CalcJacobianSpatialVelocity(
                context,
                JacobianWrtVariable.kQDot,
                frame_E,
                np.zeros(3),
                plant.world_frame(),
                plant.world_frame(),
            )
            smallest[i] = np.linalg.svd(J, compute_uv=False)[-1]
        return {"jacobian": smallest}
