"""The checks a process model's keys share: a positive number, a number within physical
bounds, a [low, high] band; each failure is one line naming the file, key and reason."""

from __future__ import annotations

import math
from pathlib import Path

from offline_prog.errors import InputError


def positive(file: Path, key: str, value: float) -> None:
    """``value`` is a finite number > 0."""
    if not (math.isfinite(value) and value > 0):
        raise InputError(file, key, f"must be a positive number, got {value:g}")


def at_most(file: Path, key: str, value: float, high: float, unit: str, why: str) -> None:
    """``value`` is at most ``high`` [unit]; ``why``: the physics or practice behind it."""
    if value > high:
        raise InputError(file, key, f"{value:g} {unit} is above {high:g} {unit}: {why}")


def at_least(file: Path, key: str, value: float, low: float, unit: str, why: str) -> None:
    """``value`` is at least ``low`` [unit]; ``why``: the physics or practice behind it."""
    if value < low:
        raise InputError(file, key, f"{value:g} {unit} is below {low:g} {unit}: {why}")


def band(file: Path, key: str, values: list[float], *, positive: bool) -> None:
    """``values`` is [low, high], two finite numbers, low < high (and low > 0 with
    ``positive``)."""
    if len(values) != 2 or not all(math.isfinite(x) for x in values):
        raise InputError(file, key, "must be [low, high], two numbers")
    if not values[0] < values[1]:
        raise InputError(file, key, f"low {values[0]:g} must be below high {values[1]:g}")
    if positive and values[0] <= 0:
        raise InputError(file, key, f"must be positive, got {values[0]:g}")
