"""The two ways a plan ends early, named once.

- :class:`InputError`: the user's input is wrong (a cell file key, a flag, a plan
  folder). One line ``file: key: reason``; the CLI exits with 2.
- :class:`PlanFailure`: the input is valid but the robot cannot do it (out of reach,
  a joint limit, a singularity, a collision). A result, not a crash: it says where
  (σ [m], t [s]) and why, with a :class:`Failure` kind set where the failure is found
  (never read back from the reason's words); the CLI exits with 1.
  :class:`PlanFailedError` carries one out of a stage that cannot go on.

The CLI maps both to exit codes in one place (``cli.EXIT_CODES``).

Every error class of the package whose ``__init__`` takes other arguments than its
message derives from :class:`TravellingError`: it pickles as its class, its ``args``
and its fields, not through ``__init__``, so it reaches the parent of a forked process
(``offline_prog.forked``) as it was raised there.
"""

from __future__ import annotations

import dataclasses
import enum
from pathlib import Path


def _rebuilt(cls: type, args: tuple, fields: dict) -> BaseException:
    """The error ``cls`` with ``args`` and ``fields``, made without its ``__init__``."""
    error = cls.__new__(cls, *args)
    error.args = args
    error.__dict__.update(fields)
    return error


class TravellingError:
    """A mixin for exceptions: pickled as class, ``args`` and fields (``__dict__``),
    whatever its ``__init__`` takes (``BaseException``'s own pickling calls
    ``cls(*args)``, which fails or loses the fields when ``__init__`` builds the
    message from other arguments)."""

    def __reduce__(self):
        return _rebuilt, (type(self), self.args, dict(self.__dict__))


class InputError(TravellingError, ValueError):
    """Bad input; str() is one line: ``file: key: reason`` (key may be empty)."""

    def __init__(self, file: Path | str, key: str, reason: str):
        self.file, self.key, self.reason = str(file), key, reason
        super().__init__(f"{file}: {key}: {reason}" if key else f"{file}: {reason}")


class Failure(enum.Enum):
    """Why a valid cell cannot be done."""

    OUT_OF_REACH = "out_of_reach"
    JOINT_LIMIT = "joint_limit"
    JOINT_RATE_LIMIT = "joint_rate_limit"  # speed/acceleration even at reduced speed
    SINGULARITY = "singularity"
    COLLISION = "collision"


@dataclasses.dataclass(frozen=True)
class PlanFailure:
    """Where and why a plan fails: σ [m] along the path, t [s], the reason."""

    kind: Failure
    sigma_m: float
    t_s: float
    reason: str

    def __str__(self) -> str:
        return f"cannot follow the path at σ = {self.sigma_m:.4f} m, t = {self.t_s:.3f} s: " + (
            self.reason
        )


class PlanFailedError(TravellingError, Exception):
    """A stage found a :class:`PlanFailure` it cannot go on from (no plan to write)."""

    def __init__(self, failure: PlanFailure):
        self.failure = failure
        super().__init__(str(failure))
