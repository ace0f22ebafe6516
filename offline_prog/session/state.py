"""The controls of a session's panel and the typed values they set.

A session's state is a :class:`~offline_prog.config.edits.CellValues` (cell editing
lives in ``config``). Controls speak millimetres and degrees (the edges);
:func:`with_value` parses a typed value and refuses a bad one with a one-line reason,
leaving the state as it was.
"""

from __future__ import annotations

import dataclasses
import math

from offline_prog.config.edits import CellValues
from offline_prog.constants import MAX_SPEED_M_S

MAX_OFFSET_MM = 10_000.0  # a tool stand or grasp farther than 10 m is a typo
MAX_ANGLE_DEG = 360.0
MAX_CLEARANCE_MM = 500.0
MAX_TURN_SMOOTHING_MM = 1000.0  # a Gaussian wider than a metre smooths any seam flat


@dataclasses.dataclass(frozen=True)
class Control:
    """One control of the panel: its key, label, unit and slider range (UI units)."""

    key: str
    group: str
    label: str
    unit: str
    low: float
    high: float
    step: float


def controls(state: CellValues, seam_names: list[str]) -> list[Control]:
    """The panel's controls; slider ranges around the initial values (a typed value may
    leave them, within the checks of :func:`with_value`)."""
    out = []
    for frame, group, p in (
        ("X_IT", "tool pose X_IT", state.p_IT),
        ("X_PE", "grasp X_PE", state.p_PE),
    ):
        for axis, value in zip("xyz", p, strict=True):
            mm = value * 1e3
            out.append(Control(f"{frame}.{axis}", group, axis, "mm", mm - 300, mm + 300, 1))
        for name in ("roll", "pitch", "yaw"):
            out.append(Control(f"{frame}.{name}", group, name, "°", -180, 180, 0.5))
    top = max(4 * max([state.motion_speed, *filter(None, state.seam_speeds)]) * 1e3, 10.0)
    out += [
        Control("speed", "process", "speed", "mm/s", 0.5, round(top), 0.5),
        Control("free_rotation", "process", "free tool rotation", "°", 0, 180, 1),
        Control("turn_smoothing", "process", "tool turn smoothing", "mm", 0, 100, 1),
        Control("clearance", "process", "clearance", "mm", 0, 50, 0.5),
    ]
    if len(seam_names) > 1:
        out.append(Control("seam", "process", "active seam", "", 0, len(seam_names) - 1, 1))
    return out


def values(state: CellValues) -> dict[str, float]:
    """Each control's value in its unit (mm, mm/s, deg, index)."""
    out = {}
    for frame, p, rpy in (
        ("X_IT", state.p_IT, state.rpy_IT_deg),
        ("X_PE", state.p_PE, state.rpy_PE_deg),
    ):
        out.update({f"{frame}.{a}": round(v * 1e3, 6) for a, v in zip("xyz", p, strict=True)})
        names = ("roll", "pitch", "yaw")
        out.update({f"{frame}.{n}": v for n, v in zip(names, rpy, strict=True)})
    out.update(
        speed=round(state.speed * 1e3, 6),
        free_rotation=state.free_rotation_deg,
        turn_smoothing=state.turn_smoothing_mm,
        clearance=round(state.clearance * 1e3, 6),
        seam=state.seam,
    )
    return out


def _number(text) -> float:
    try:
        value = float(str(text).strip())
    except ValueError:
        raise ValueError(f"{str(text)[:40]!r} is not a number") from None
    if not math.isfinite(value):
        raise ValueError(f"{text!r} is not a finite number")
    return value


def _within(value: float, low: float, high: float, unit: str, *, open_low=False) -> None:
    if (value <= low if open_low else value < low) or value > high:
        bound = f"> {low:g}" if open_low else f"≥ {low:g}"
        raise ValueError(f"must be {bound} and ≤ {high:g} {unit}")


def with_value(state: CellValues, key: str, text) -> CellValues:
    """The state with control ``key`` set to the typed ``text`` (in the control's unit).

    Raises:
        ValueError: an unknown key, or a value that is not a number or out of range
            (one line: the session shows it and keeps the state).
    """
    value = _number(text)
    frame, _, part = key.partition(".")
    if frame in ("X_IT", "X_PE") and part in ("x", "y", "z"):
        _within(value, -MAX_OFFSET_MM, MAX_OFFSET_MM, "mm")
        name = "p_IT" if frame == "X_IT" else "p_PE"
        p = list(getattr(state, name))
        p["xyz".index(part)] = value * 1e-3
        return dataclasses.replace(state, **{name: tuple(p)})
    if frame in ("X_IT", "X_PE") and part in ("roll", "pitch", "yaw"):
        _within(value, -MAX_ANGLE_DEG, MAX_ANGLE_DEG, "°")
        name = "rpy_IT_deg" if frame == "X_IT" else "rpy_PE_deg"
        rpy = list(getattr(state, name))
        rpy[("roll", "pitch", "yaw").index(part)] = value
        return dataclasses.replace(state, **{name: tuple(rpy)})
    if key == "speed":
        _within(value, 0.0, MAX_SPEED_M_S * 1e3, "mm/s", open_low=True)
        if state.seam_speeds[state.seam] is None:
            return dataclasses.replace(state, motion_speed=value * 1e-3)
        speeds = list(state.seam_speeds)
        speeds[state.seam] = value * 1e-3
        return dataclasses.replace(state, seam_speeds=tuple(speeds))
    if key == "free_rotation":
        _within(value, 0.0, 180.0, "°")
        return dataclasses.replace(state, free_rotation_deg=value)
    if key == "turn_smoothing":
        _within(value, 0.0, MAX_TURN_SMOOTHING_MM, "mm")
        return dataclasses.replace(state, turn_smoothing_mm=value)
    if key == "clearance":
        _within(value, 0.0, MAX_CLEARANCE_MM, "mm")
        return dataclasses.replace(state, clearance=value * 1e-3)
    if key == "seam":
        if value != int(value) or not 0 <= value < len(state.seam_speeds):
            raise ValueError(f"{value:g}: no such seam (0 to {len(state.seam_speeds) - 1})")
        return dataclasses.replace(state, seam=int(value))
    raise ValueError(f"{key!r} is not a control")
