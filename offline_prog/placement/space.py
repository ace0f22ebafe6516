"""The search space of ``offline-prog place``: the ``place:`` block checked, and the
map from unit coordinates x ∈ [0, 1]^d to a candidate tool pose X_IT and grasp X_PE.

Each named range is one axis of x: ``X_IT.translation_mm.{x,y,z}`` [mm at the edge,
m inside], ``X_IT.rpy_deg.{roll,pitch,yaw}`` [deg, as the cell file keeps them], and
the same under ``X_PE`` (applied to every grasp). An axis not named keeps the cell's
value (tool.X_IT, or the grasp's own). Grasps are discrete: ``X_PE.candidates``, or
part.X_PE alone.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from pathlib import Path

import numpy as np

from offline_prog.config.cell import Cell, PlaceConfig
from offline_prog.config.edits import rpy_deg_of
from offline_prog.constants import MAX_PLACE_BUDGET, MAX_PLACE_SEED
from offline_prog.errors import InputError
from offline_prog.placement.stand import check_stands

MAX_SCREEN_POINTS = 100_000  # per grasp
MAX_OFFSET_MM = 10_000.0  # a tool stand 10 m from the robot is a typo
MAX_ANGLE_DEG = 360.0
TRANSLATION_AXES = ("x", "y", "z")
RPY_AXES = ("roll", "pitch", "yaw")
# Candidates are rounded to these steps, so placed.yaml holds the numbers evaluated.
DECIMALS_M, DECIMALS_DEG = 4, 3

Pose = tuple[tuple[float, float, float], tuple[float, float, float]]  # (p [m], rpy [deg])


@dataclasses.dataclass(frozen=True)
class Axis:
    """One searched coordinate.

    Attributes:
        key: the cell file's dotted key, e.g. ``place.X_IT.translation_mm.x``.
        pose: "X_IT" or "X_PE"; kind: "translation" [m] or "rpy" [deg]; index: 0..2.
        low, high: the range, low < high [m or deg].
    """

    key: str
    pose: str
    kind: str
    index: int
    low: float
    high: float


@dataclasses.dataclass(frozen=True)
class Candidate:
    """One placement to evaluate.

    Attributes:
        x: (d,) unit coordinates of the searched axes; grasp: index into the grasps.
        X_IT: tool T in I as (p [m], rpy [deg]); X_PE: flange E in part P, the same.
    """

    x: tuple[float, ...]
    grasp: int
    X_IT: Pose
    X_PE: Pose


@dataclasses.dataclass(frozen=True)
class SearchSpace:
    """The axes, the grasps and the cell's own poses they start from."""

    axes: tuple[Axis, ...]
    grasps: tuple[Pose, ...]
    X_IT: Pose  # tool.X_IT as given
    X_PE: Pose  # part.X_PE as given

    @property
    def baseline(self) -> Candidate:
        """The cell as given (grasp −1: part.X_PE)."""
        return Candidate((), -1, self.X_IT, self.X_PE)

    @property
    def dimensions(self) -> int:
        return len(self.axes)

    def candidate(self, x, grasp: int) -> Candidate:
        """The candidate at unit coordinates x (d,) (clipped to [0, 1]) with a grasp."""
        x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
        poses = {
            "X_IT": [list(v) for v in self.X_IT],
            "X_PE": [list(v) for v in self.grasps[grasp]],
        }
        for axis, u in zip(self.axes, x, strict=True):
            value = axis.low + float(u) * (axis.high - axis.low)
            poses[axis.pose][0 if axis.kind == "translation" else 1][axis.index] = value
        X_IT, X_PE = (_rounded(poses[k]) for k in ("X_IT", "X_PE"))
        return Candidate(tuple(float(u) for u in x), int(grasp), X_IT, X_PE)

    def grid(self, points_per_grasp: int, seed: int = 0) -> list[Candidate]:
        """A regular grid of about ``points_per_grasp`` points (k levels per axis,
        k^d ≤ points, k ≥ 2) for every grasp: cell-centred for seed 0, the whole
        lattice shifted within its cell by a seeded offset (each axis its own, up to
        half a cell) for another seed, so seeds sample other placements."""
        d = self.dimensions
        if d == 0:
            return [self.candidate([], g) for g in range(len(self.grasps))]
        k = max(2, int(math.floor(points_per_grasp ** (1.0 / d) + 1e-9)))
        shift = np.zeros(d) if seed == 0 else np.random.default_rng(seed).uniform(-0.5, 0.5, d)
        levels = (np.arange(k)[:, None] + 0.5 + shift[None, :]) / k  # (k, d)
        return [
            self.candidate(levels[list(index), range(d)], g)
            for g in range(len(self.grasps))
            for index in itertools.product(range(k), repeat=d)
        ]


def _rounded(pose) -> Pose:
    """A pose rounded as an engineer writes it (0.1 mm, 0.001°)."""
    p, rpy = pose
    return (
        tuple(round(float(v), DECIMALS_M) + 0.0 for v in p),
        tuple(round(float(v), DECIMALS_DEG) + 0.0 for v in rpy),
    )


def _range(file: Path, key: str, value, bound: float) -> tuple[float, float]:
    if len(value) != 2:
        raise InputError(file, key, f"expected [low, high], got {len(value)} numbers")
    low, high = float(value[0]), float(value[1])
    if high < low:
        raise InputError(file, key, f"inverted range [{low:g}, {high:g}]: low must be below high")
    if high == low:
        raise InputError(
            file, key, f"empty range [{low:g}, {high:g}]: leave the axis out to keep its value"
        )
    if max(abs(low), abs(high)) > bound:
        raise InputError(file, key, f"[{low:g}, {high:g}] goes beyond ±{bound:g}")
    return low, high


def _axes(file: Path, pose: str, ranges) -> list[Axis]:
    axes = []
    for kind, field, names, bound, scale in (
        ("translation", "translation_mm", TRANSLATION_AXES, MAX_OFFSET_MM, 1e-3),
        ("rpy", "rpy_deg", RPY_AXES, MAX_ANGLE_DEG, 1.0),
    ):
        for index, name in enumerate(names):
            value = getattr(getattr(ranges, field), name)
            if value is None:
                continue
            key = f"place.{pose}.{field}.{name}"
            low, high = _range(file, key, value, bound)
            axes.append(Axis(key, pose, kind, index, low * scale, high * scale))
    return axes


def _pose(value) -> Pose:
    """(p [m], rpy [deg]) of a schema Transform."""
    return tuple(float(v) for v in value.translation), rpy_deg_of(value)


def check_place(file: Path, cell: Cell, *, budget: int | None = None, seed: int | None = None):
    """The checked ``place:`` block, with the command line's budget and seed applied
    (the flags are checked by the command line's parser against the same bounds),
    and its search space.

    Returns:
        (PlaceConfig, SearchSpace).

    Raises:
        InputError: no ``place:``, an empty or inverted range, a budget out of range,
            an unknown obstacle, nothing to search (one line, exit 2).
    """
    place: PlaceConfig | None = cell.place
    if place is None:
        raise InputError(file, "place", "missing: give the search space (see README, Placement)")
    if budget is not None:
        place = dataclasses.replace(place, budget=budget)
    if seed is not None:
        place = dataclasses.replace(place, seed=seed)
    for key, value, high in (
        ("place.budget", place.budget, MAX_PLACE_BUDGET),
        ("place.screen_points", place.screen_points, MAX_SCREEN_POINTS),
        ("place.top_k", place.top_k, 1000),
    ):
        if not 1 <= value <= high:
            raise InputError(file, key, f"{value} is outside 1..{high:,}")
    if not 0 <= place.seed <= MAX_PLACE_SEED:
        raise InputError(file, "place.seed", f"{place.seed} is outside 0..{MAX_PLACE_SEED:,}")
    obstacles = {shape.name for shape in cell.obstacles}
    for i, name in enumerate(place.moves_with_tool):
        if name not in obstacles:
            raise InputError(
                file, f"place.moves_with_tool[{i}]", f"{name!r} is not an obstacle of the cell"
            )
    if not 0.0 < place.stand_max_length_mm <= MAX_OFFSET_MM:
        raise InputError(
            file,
            "place.stand_max_length_mm",
            f"{place.stand_max_length_mm:g} is outside (0, {MAX_OFFSET_MM:g}] mm",
        )
    check_stands(file, cell, place.moves_with_tool, 1e-3 * place.stand_max_length_mm)
    axes = _axes(file, "X_IT", place.X_IT)
    grasps = (_pose(cell.part.X_PE),)
    if place.X_PE is not None:
        if place.X_PE.candidates:
            grasps = tuple(_pose(value) for value in place.X_PE.candidates)
        for axis in _axes(file, "X_PE", place.X_PE):
            part = 0 if axis.kind == "translation" else 1
            if len({g[part][axis.index] for g in grasps}) > 1:  # a range sets the value
                raise InputError(
                    file,
                    axis.key,
                    "the grasps differ on this axis and a range would make "
                    "them one: give the axis by range or by candidates, not both",
                )
            axes.append(axis)
    if not axes and len(grasps) == 1:
        raise InputError(file, "place", "nothing to search: name a range or several grasps")
    return place, SearchSpace(tuple(axes), grasps, _pose(cell.tool.X_IT), _pose(cell.part.X_PE))
