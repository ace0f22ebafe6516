"""The walk over a flying seam's leads and their fallbacks, one check at a time.

A flying seam's leads (``path.lead``) may miss their purpose: no IK branch or joint
timing runs them, or the joint limits slow a led seam end (``timing.lead_length``'s
``lead_failure``, ``slowed_end``). The seam then tries the leads' fallbacks in order
(``timing.lead_length.fallbacks``: leads with their own lift, then both ends at rest)
until one serves. The path IK before the time law (``job.untimed``) and the timed plan
(``stages.plan_motion``) walk the same fallbacks with different checks: the walk is
written once here and takes the check as an argument.

Where the process judges the seam's ends worse at rest than at a slowed speed (a bead:
at rest the flow's lag spoils both ends, flying the flow follows the speed), the walk
may keep the least-slowed flying run that ran instead of ending at rest (``rank``).
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable
from typing import Any

from offline_prog.errors import PlanFailedError
from offline_prog.timing.lead_length import fallbacks, held_ends, lead_failure


@dataclasses.dataclass(frozen=True)
class Walk:
    """What a walk tried, in order: ``tried[i]`` = (the run, its check's outcome or None
    where the check raised, why its leads miss their purpose: "" where they serve).
    The walk ends at the first run that serves, or after the last fallback."""

    tried: list[tuple[Any, Any, str]]
    chosen: int = -1  # the run the seam runs: the last tried, or one kept (``rank``)

    @property
    def served(self) -> bool:
        """Whether the chosen run's leads serve."""
        return not self.tried[self.chosen][2]

    @property
    def last(self) -> tuple[Any, Any]:
        """(the chosen run, its outcome)."""
        return self.tried[self.chosen][:2]

    @property
    def missed(self) -> str:
        """Why the chosen run's leads miss their purpose ("" where they serve)."""
        return self.tried[self.chosen][2]


def walk_fallbacks(
    first,
    check: Callable[[Any], tuple[Any, str]],
    *,
    setup: Callable[[Any], Any],
    rank: Callable[[Any, Any], float | None] | None = None,
) -> Walk:
    """Check ``first``, then, where its leads miss their purpose, each of their
    fallbacks until one serves.

    Args:
        first: the run of the leads as asked: anything whose ``flange`` is the
            ``path.lead.LeadPath`` it runs (``stages.MotionSetup``).
        check: run ↦ (outcome, why): why "" where the run's leads serve, else why they
            miss their purpose (a ``lead_failure`` or ``slowed_end`` reason). It raises
            ``PlanFailedError`` where the robot cannot follow the run's path: on a flying
            path that is a miss (the failure's reason, ``lead_failure``), at rest the
            seam's own failure.
        setup: LeadPath ↦ the run of a fallback (``stages.motion_setup``).
        rank: (run, outcome) ↦ how well a flying run that missed still serves (larger
            is better), None where it does not (it failed): given, the walk keeps the
            best-ranked flying run that ran rather than falling to rest; None: it
            falls to rest.

    Returns:
        The :class:`Walk`. The fallbacks are those of ``first``'s leads for the first
        miss's reason (the reason the seam names where it ends at rest); a path at rest
        has none.

    Raises:
        PlanFailedError: ``check``'s, on a path at rest.
    """
    tried = [_checked(first, check)]
    missed = tried[0][2]
    if not missed or not first.flange.flying:
        return Walk(tried)
    for leads in fallbacks(first.flange, missed):
        if rank is not None and not leads.flying:
            ranked = [
                (rank(run, out), i) for i, (run, out, _) in enumerate(tried) if out is not None
            ]
            ranked = [(r, i) for r, i in ranked if r is not None]
            if ranked:  # the best flying run, the first of equals
                return Walk(tried, chosen=max(ranked, key=lambda r_i: (r_i[0], -r_i[1]))[1])
        tried.append(_checked(setup(leads), check))
        if not tried[-1][2]:
            break
    return Walk(tried)


def _checked(run, check) -> tuple[Any, Any, str]:
    """(run, outcome, why) of ``check(run)``; a flying path that fails is a miss."""
    try:
        return (run, *check(run))
    except PlanFailedError as error:
        if not run.flange.flying:
            raise
        return run, None, lead_failure(error.failure.reason)


def led_end_speed(flange, reductions, v: float) -> float:
    """The lowest speed [m/s] at which the joints' speed ``reductions`` ((σ_start, σ_end,
    speed) [m, m, m/s] on the law's σ, 0 at the lead-in's start:
    ``PathTiming.reductions``) hold a seam end that a lead of ``flange`` (a LeadPath)
    meets (``held_ends``); the process speed v [m/s] where they hold none."""
    return min([speed for _, speed in held_ends(flange, reductions)] + [v])


def slowed_rank(model, v: float) -> Callable[[Any, Any], float] | None:
    """The ``rank`` of a timed walk (run: ``stages.MotionSetup``, outcome: its joint
    trajectory) at the process speed v [m/s]: the slowest led seam end's speed, where
    the process ``model`` (``process.registry.process_model``, or None) ``flies_slowed``;
    None (rest) otherwise."""
    if model is None or not model.flies_slowed:
        return None
    return lambda run, joints: led_end_speed(run.flange, joints.retiming.reductions, v)


def kept_slowed(flange, missed: str):
    """``flange`` (a LeadPath) kept flying although ``missed`` (a ``slowed_end`` reason)
    holds one of its seam ends below the process speed, with report.json's reason."""
    kept = copy.copy(flange)  # the same leads (their tables shared), another reason
    slowed = missed.removeprefix(lead_failure(""))
    kept.reason = (
        f"{slowed}; kept flying: the process follows the speed, at rest its ends would not"
    )
    return kept
