"""The placement objective (issue 16), lexicographic, :meth:`Evaluation.key`:

1. feasible: reach, joint limits, one branch along the path, collision-free at the
   cell's clearances. An infeasible candidate keeps its reason and how far it is from
   feasible (``tier``, ``violation``), so a search can climb out of an infeasible
   start: tier 1 collides (violation: depth below the clearance [m]), tier 2 cannot
   follow the path (violation: share of the path out of reach plus the mean distance
   beyond reach [m] (``path_ik.reach_excess``), share on a flipping branch, joint-limit
   excess / π [rad], and the share of the path not done), tier 3 needs a stand longer
   than ``place.stand_max_length_mm`` or shorter than none (violation: by how much
   [m]), tier 4 makes geometry the method refuses (violation 1).
2. with a process model (``process:``): the share of the dispensed process length whose
   predicted quality lies within the band (larger is better), resolved to
   QUALITY_RESOLUTION (without a model every candidate scores 1), then
3. cycle time [s], resolved to CYCLE_RESOLUTION_S, then
4. the smallest joint-limit margin [deg] (larger is better),
5. the distance to the wrist and elbow singularities [deg] (larger is better),
6. the clearance [mm] (larger is better).
"""

from __future__ import annotations

import dataclasses
import math

from offline_prog.placement.space import Candidate

CYCLE_RESOLUTION_S = 0.01  # cycle times closer than this tie; the margins decide
QUALITY_RESOLUTION = 0.001  # shares within the band closer than this tie; the cycle decides
FEASIBLE, COLLIDES, CANNOT_FOLLOW, STAND, REFUSED = range(5)  # tiers


@dataclasses.dataclass(frozen=True)
class Evaluation:
    """A candidate and every objective term.

    Attributes:
        candidate: what was evaluated.
        stage: "screen" (the analytic path IK of every tool turn and branch, the
            lower bound and the steady-speed estimate), "rank" (the cheaper law:
            TOPP-RA on the planner's variant, a coarse collision check) or "plan" (the
            planning pipeline).
        tier: FEASIBLE, COLLIDES, CANNOT_FOLLOW, STAND or REFUSED; violation: how far from
            feasible within the tier (0 when feasible).
        reason: why it is infeasible, one line ("" when feasible).
        failure: its kind: a :class:`~offline_prog.errors.Failure` value
            ("out_of_reach", "joint_limit", "singularity", "collision", ...) or
            "refused" (geometry the method refuses); "" when feasible.
        cycle_time_s: the job's duration, home to home [s]: planned ("plan"), or the
            stage's estimate ("screen", "rank"); NaN without either.
        joint_limit_margin_deg: smallest distance of a joint to its limits [deg].
        singularity_margin_deg: smallest wrist or elbow angle from singular [deg].
        clearance_mm: smallest distance of a checked pair [mm] (NaN without a plan).
        tool_rotation_deg: the free tool rotation chosen [deg].
        process_bound_s: the seam at the process speed with no joint slow-down (the
            time law's nominal duration) [s]: no placement is faster.
        slowed_share: share of the path the joints slowed below the process speed;
            limiting_axis: the axis (1..6) closest to its limit there (0: none).
        air_time_s: a job's time off the seams: approach, retract, links [s].
        quality_share: with a process model, the share of the dispensed process length
            within the quality band (process.quality; NaN: no model or no plan).
        seconds: the evaluation's wall time [s].
        bound_s: no plan of the candidate is faster [s] (``placement.bound``; NaN
            without a screen, ∞ when no variant is usable).
        screened_out: why the screen rules the candidate out whatever the planner
            does ("reach", "joint_limit", "collision", "stand"; "" when it does not).
        collides: the coarse collision check found the planner's first variant below
            the clearances ("rank" only).
    """

    candidate: Candidate
    stage: str
    tier: int
    violation: float
    reason: str
    failure: str = ""
    cycle_time_s: float = math.nan
    joint_limit_margin_deg: float = -math.inf
    singularity_margin_deg: float = 0.0
    clearance_mm: float = math.nan
    tool_rotation_deg: float = 0.0
    process_bound_s: float = math.nan
    slowed_share: float = 0.0
    air_time_s: float = 0.0
    limiting_axis: int = 0
    quality_share: float = math.nan
    seconds: float = 0.0
    bound_s: float = math.nan
    screened_out: str = ""
    collides: bool = False

    @property
    def feasible(self) -> bool:
        return self.tier == FEASIBLE

    def key(self) -> tuple:
        """The lexicographic objective: smaller is better."""
        cycle = self.cycle_time_s if math.isfinite(self.cycle_time_s) else math.inf
        share = self.quality_share if math.isfinite(self.quality_share) else 1.0
        return (
            self.tier,
            self.violation,
            -round(share / QUALITY_RESOLUTION),
            round(cycle / CYCLE_RESOLUTION_S) if cycle < math.inf else math.inf,
            -self.joint_limit_margin_deg,
            -self.singularity_margin_deg,
            -(self.clearance_mm if math.isfinite(self.clearance_mm) else -math.inf),
        )
