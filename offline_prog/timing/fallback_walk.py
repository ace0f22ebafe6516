"""The walk over a flying seam's leads and their fallbacks, one check at a time.

A flying seam's leads (``path.lead``) may miss their purpose: no IK branch or joint
timing runs them, or the joint limits slow a led seam end (``timing.lead_length``'s
``lead_failure``, ``slowed_end``). The seam then tries the leads' fallbacks in order
(``timing.lead_length.fallbacks``: leads with their own lift, then both ends at rest)
until one serves. The path IK before the time law (``job.untimed``) and the timed plan
(``stages.plan_motion``) walk the same fallbacks with different checks: the walk is
written once here and takes the check as an argument.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from offline_prog.errors import PlanFailedError
from offline_prog.timing.lead_length import fallbacks, lead_failure


@dataclasses.dataclass(frozen=True)
class Walk:
    """What a walk tried, in order: ``tried[i]`` = (the run, its check's outcome or None
    where the check raised, why its leads miss their purpose: "" where they serve).
    The walk ends at the first run that serves, or after the last fallback."""

    tried: list[tuple[Any, Any, str]]

    @property
    def served(self) -> bool:
        """Whether the last run tried serves."""
        return not self.tried[-1][2]

    @property
    def last(self) -> tuple[Any, Any]:
        """(the last run tried, its outcome)."""
        return self.tried[-1][:2]


def walk_fallbacks(
    first,
    check: Callable[[Any], tuple[Any, str]],
    *,
    setup: Callable[[Any], Any],
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
