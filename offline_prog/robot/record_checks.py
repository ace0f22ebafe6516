"""Checks of the values read from a robot record (robot.yaml): one-line ValueErrors
naming the file, the key, what was expected and what was found."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


class RecordChecker:
    """Validates values read from one record file; failures are one-line ValueErrors."""

    def __init__(self, path: Path):
        self.path = path

    def fail(self, key: str, value: Any, expected: str) -> None:
        raise ValueError(f"{self.path}: key '{key}': expected {expected}, got {value!r}")

    def keys(self, mapping: Any, where: str, *, required: set[str], allowed: set[str]) -> None:
        if not isinstance(mapping, dict):
            self.fail(where or "<top level>", mapping, "a mapping")
        prefix = f"{where}." if where else ""
        for key in sorted(required - mapping.keys()):
            raise ValueError(f"{self.path}: key '{prefix}{key}': missing")
        for key in sorted(mapping.keys() - allowed):
            raise ValueError(
                f"{self.path}: key '{prefix}{key}': unknown (allowed: {', '.join(sorted(allowed))})"
            )

    def numbers(
        self, value: Any, key: str, *, shape: tuple[int, ...] = (6,), positive: bool = False
    ) -> np.ndarray:
        expected = "a number" if shape == () else f"finite numbers of shape {list(shape)}"
        if positive:
            expected = expected.replace("finite", "positive finite")
        try:
            array = np.array(value, dtype=float)
            ok = not _has_bool_or_str(value) and array.shape == shape
        except (TypeError, ValueError):
            ok = False
        if not ok or not np.all(np.isfinite(array)) or (positive and not np.all(array > 0)):
            self.fail(key, value, expected)
        return array


def _has_bool_or_str(value: Any) -> bool:
    """True if value (possibly nested lists) holds a bool or a string."""
    if isinstance(value, list):
        return any(_has_bool_or_str(v) for v in value)
    return isinstance(value, (bool, str))
