"""The records a plan leaves: a seam's :class:`Plan`, a :class:`SeamOption` (one way to
run a seam, with its approach and retract) and the whole :class:`JobPlan`.

Every cell plans as a job (``path:`` is a one-seam job); the writers, the reports, the
session and placement read these records and never re-derive what they hold.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from offline_prog.collision.avoidance import Attempt
from offline_prog.collision.check import CollisionResult
from offline_prog.config.cell import Cell
from offline_prog.config.process_speed import ProcessSpeed
from offline_prog.errors import Failure
from offline_prog.job.approach import CartesianMove
from offline_prog.job.assemble import JobSamples
from offline_prog.job.lead_rows import LeadRows, split_leads
from offline_prog.job.links import LinkMotion
from offline_prog.job.order import JobOrder
from offline_prog.job.process_io import IoColumns
from offline_prog.joints.joint_plan import JointTrajectory
from offline_prog.joints.path_ik import BranchResult
from offline_prog.path.arc_length import ArcLengthPath
from offline_prog.path.bspline_fit import FittedSpline
from offline_prog.path.cusps import Cusp, SmoothedFlangePath
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.path.inputs import NormalFit
from offline_prog.path.lead import LeadPath
from offline_prog.path.sources import PathPoints
from offline_prog.process.quality import ProcessQuality
from offline_prog.robot.model import RobotModel
from offline_prog.stages import FittedPath, FlangePaths, Inputs, MotionSetup
from offline_prog.timing.path_timing import without_joint_limits
from offline_prog.timing.trajectory import WorkspaceTrajectory


@dataclasses.dataclass
class Plan:
    """Everything a plan produced, for the writers and the tests."""

    cell_file: Path
    cell: Cell
    points: PathPoints
    fitted: FittedSpline
    path: ArcLengthPath
    flange: FlangePath | SmoothedFlangePath
    trajectory: WorkspaceTrajectory
    cusps: list[Cusp]
    timings_s: dict[str, float]
    robot: RobotModel
    joints: JointTrajectory
    nominal_duration_s: float
    tool_rotation_rad: float
    collisions: CollisionResult
    avoidance: dict | None = None  # what the collision avoidance tried and changed
    # (t_k, {pair group: smallest distance [m]}) for the distance-over-time plot.
    clearance_profile: tuple | None = None
    normal_fit: NormalFit | None = None  # given normals vs the fitted normal field
    # The seam's process speed, as its time law ran it (the seam's cell keeps the
    # cell's motion.speed: a seam's own speed is here alone).
    process_speed: ProcessSpeed | None = None
    # A flying seam's lead-in and lead-out rows (job.lead_rows; None: that end at
    # rest). The seam's own rows (joints, trajectory) run from σ = 0 to L.
    lead_in: LeadRows | None = None
    lead_out: LeadRows | None = None

    def __post_init__(self):
        """Joints timed with the leads (path.lead) are cut at the seam's ends here, so
        every way a plan is made or replaced with new joints holds the seam's rows."""
        s, length = self.trajectory.s, self.path.length
        if isinstance(self.flange, LeadPath) and (s[0] < 0.0 or s[-1] > length):
            self.joints, self.lead_in, self.lead_out = split_leads(self.joints, length)
            self.trajectory = self.joints.trajectory

    @property
    def law_origin(self) -> tuple[float, float]:
        """(σ [m], t [s]) where the seam's time law starts, on the seam's own scale (σ
        and t 0 at its start): a flying seam's lead-in's start (its −length, −duration),
        (0, 0) at rest. The law's slowdowns and speed reductions are on the law's scale:
        add these to put them on the seam's."""
        if self.lead_in is None:
            return 0.0, 0.0
        return float(self.lead_in.s[0]), -float(self.lead_in.t[-1])

    @property
    def entry(self) -> dict:
        """How the seam is entered and left: ``{"entry": "flying" | "rest", "reason":
        why at rest (flying: "", or the joint limits' hold on a seam end its leads run
        slowed, ``timing.fallback_walk.kept_slowed``), "lead_in_mm", "lead_out_mm"}``
        (report.json)."""
        lead_in = 0.0 if self.lead_in is None else self.lead_in.length_m
        lead_out = 0.0 if self.lead_out is None else self.lead_out.length_m
        flying = lead_in > 0.0 or lead_out > 0.0
        reason = getattr(self.flange, "reason", "")
        reason = reason if flying else reason or "entry: rest"
        return {
            "entry": "flying" if flying else "rest",
            "reason": reason,
            "lead_in_mm": lead_in * 1e3,
            "lead_out_mm": lead_out * 1e3,
        }

    @classmethod
    def of_attempt(
        cls,
        inputs: Inputs,
        fit: FittedPath,
        flanges: FlangePaths,
        chosen: Attempt,
        *,
        timings_s: dict[str, float],
        avoidance: dict | None = None,
        clearance_profile: tuple | None = None,
    ) -> Plan:
        """The plan of a seam whose joints are ``chosen`` (a checked attempt)."""
        return cls(
            inputs.file,
            inputs.cell,
            inputs.points,
            fit.fitted,
            fit.path,
            chosen.flange,
            chosen.joints.trajectory,
            flanges.cusps,
            timings_s,
            inputs.robot,
            chosen.joints,
            without_joint_limits(chosen.limits.nominal, inputs.cell.motion.time_law)[0],
            chosen.rotation,
            chosen.collisions,
            avoidance,
            clearance_profile,
            fit.normal_fit,
            inputs.speed,
        )

    @property
    def feasible(self) -> bool:
        """Every check passed (collision-free at the clearance)."""
        return self.collisions.collision_free

    @property
    def failure(self) -> str:
        """Why the plan failed, one line ("" if it did not)."""
        return self.collisions.message

    @property
    def failure_kind(self) -> Failure | None:
        """The Failure of a finished plan that fails a check (a collision), or None.
        Failures that leave no plan (reach, limits, singularities) are PlanFailedErrors."""
        return None if self.feasible else Failure.COLLISION


@dataclasses.dataclass(frozen=True)
class UntimedSeam:
    """A seam option decided before its time law (``job.untimed``): the path IK on its
    branch follows the whole path within the joint limits and the path is collision-free
    at the clearances; the time law runs only if the order chooses it.

    Attributes:
        inputs: the seam's inputs in its direction; fit, frames: its stages' results.
        rotation: the tool's turn about its symmetry axis [rad]; flange: the flange path
            the time law gets (``stages.plan_motion``); branch: the IK branch.
        q_ends: (2, 6) joints at σ = 0 and at the path's end [rad], as the timed plan has
            them.
        first: the direction's first option (best rotation and branch); the others
            are the further branches offered beside it.
        run: ``motion_setup`` of ``flange`` as run (the leads' fallback, below);
            branches: every IK branch's verdict on its σ grid (``path_branches``): the
            timed plan starts from them (``stages.plan_motion``).
        start: where no branch follows the leads first asked, and ``run`` holds the
            fallback ``stages.plan_motion`` turns to (``timing.lead_length.fallbacks``),
            that path's ``motion_setup`` and verdicts: the direction's first timed plan
            starts there and walks the same fallbacks as a plan in full (None: it
            starts from ``run``).
    """

    inputs: Inputs
    fit: FittedPath
    frames: FlangePaths
    rotation: float
    flange: FlangePath | SmoothedFlangePath
    branch: int
    q_ends: np.ndarray
    first: bool
    run: MotionSetup
    branches: list[BranchResult]
    start: tuple[MotionSetup, list[BranchResult]] | None = None


@dataclasses.dataclass
class SeamOption:
    """One way to run a seam: its plan in one direction (None while ``untimed``: the
    time law runs for the options the order chooses), the approach and retract, and
    the link ends q_in / q_out (6,) [rad]."""

    seam: int
    name: str
    reverse: bool
    plan: Plan | None
    approach: CartesianMove | None
    retract: CartesianMove | None
    untimed: UntimedSeam | None = None

    @property
    def branch(self) -> int:
        return self.untimed.branch if self.plan is None else self.plan.joints.branch

    @property
    def q_in(self) -> np.ndarray:
        if self.approach:
            return self.approach.q[0]
        if self.plan is None:
            return self.untimed.q_ends[0]
        return (self.plan.lead_in or self.plan.joints).q[0]

    @property
    def q_out(self) -> np.ndarray:
        if self.retract:
            return self.retract.q[-1]
        if self.plan is None:
            return self.untimed.q_ends[1]
        return (self.plan.lead_out or self.plan.joints).q[-1]

    @property
    def label(self) -> str:
        direction = "reverse" if self.reverse else "forward"
        return f"{self.name} {direction} branch {self.branch}"


@dataclasses.dataclass
class JobPlan:
    """A whole job: the seams as run (each a :class:`Plan`), the links, and the job's
    samples with named segments, process I/O and the whole job's collision check."""

    cell_file: Path
    cell: Cell
    robot: RobotModel
    q_home: np.ndarray  # (6,) [rad]
    options: list[list[SeamOption]]  # every seam option planned, by seam
    chosen: list[SeamOption]  # the options run, in order
    order: JobOrder
    links: list[LinkMotion]  # in order (home → first, …, last → home)
    samples: JobSamples
    X_BE: np.ndarray  # (N, 4, 4) the flange E in the robot base B on every row [m]
    tcp_speed: np.ndarray  # (N,) speed of the tool along the part [m/s]
    io: IoColumns
    collisions: CollisionResult
    timings_s: dict[str, float]
    # (t_k, {pair group: smallest distance [m]}) over the whole job (clearance.csv).
    clearance_profile: tuple | None = None
    # The process quality along the job (process.quality; None: no process model).
    quality: ProcessQuality | None = None

    avoidance = None  # per seam, in each seam's report

    @property
    def seams(self) -> list[Plan]:
        return [option.plan for option in self.chosen]

    @property
    def feasible(self) -> bool:
        return (
            self.collisions.collision_free
            and all(p.feasible for p in self.seams)
            and all(link.ok for link in self.links)
        )

    @property
    def failure(self) -> str:
        failed = next((link for link in self.links if not link.ok), None)
        if failed is not None:
            return failed.failure.reason
        if self.collisions.collision_free:
            failed = (o for o in self.chosen if not o.plan.feasible)
            return next((f"seam {o.name}: {o.plan.failure}" for o in failed), "")
        at = self.collisions.first_contact or self.collisions.closest
        where = "" if at is None else f"{self.samples.segment_at(at.t_s).label}: "
        return where + self.collisions.message

    @property
    def failure_kind(self) -> Failure | None:
        return None if self.feasible else Failure.COLLISION
