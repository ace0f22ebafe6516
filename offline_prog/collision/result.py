"""The result of a trajectory collision check, its one-line message and its JSON.

Kept apart from the checker (``collision``) so that reports and tests can read
results without the query machinery. Distances in metres, σ in metres, t in s.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic


@dataclasses.dataclass
class PairMinimum:
    """A shape pair at one point of the trajectory.

    Attributes:
        a, b: shape names (robot geometry: the link's name); group: e.g. "part-obstacle".
        distance_m: the deciding signed distance [m] (FCL's for refined mesh pairs).
        sigma_m, t_s: σ [m] and t [s] there; sample: fractional sample index.
        drake_distance_m: SceneGraph's (convex pieces); exact_distance_m: FCL's on the
            original shapes where computed (0.0 for meshes in contact: depth unknown).
        depth_m: penetration depth, max(0, −distance_m).
        lower_bound_m: None when distance_m is the pair's minimum over every sample and
            step; else the pair was not evaluated where it was certified farther than
            this [m] (pruning): its true minimum lies in [min(lower_bound_m, distance_m),
            distance_m].
    """

    a: str
    b: str
    group: str
    distance_m: float
    sigma_m: float
    t_s: float
    sample: float
    drake_distance_m: float
    depth_m: float = 0.0
    exact_distance_m: float | None = None
    note: str = ""
    lower_bound_m: float | None = None


@dataclasses.dataclass
class CollisionStretch:
    """Consecutive checked points where one pair is closer than the clearance."""

    a: str
    b: str
    group: str
    sample_start: float
    sample_end: float
    sigma_start_m: float
    sigma_end_m: float
    t_start_s: float
    t_end_s: float
    worst: PairMinimum


@dataclasses.dataclass
class CollisionResult:
    """The check of one trajectory.

    Attributes:
        collision_free: no checked pair closer than clearance_m [m] anywhere.
        min_distance_m, closest: the smallest distance [m] and its pair, σ and t.
        pairs: every checked pair at its minimum, closest first; worst: the first few,
            with FCL's exact distance.
        collisions: the stretches closer than the clearance, by pair, in path order.
        samples_in_collision: indices i of samples (or of steps i → i+1) below clearance.
        first_contact: where the first overlap (distance < −TOUCH_TOL_M) starts, or None.
        allowed: the allowed_contact pairs (filtered out, not checked).
        message: one line for a failed plan ("" when collision_free).
        notes: Drake vs FCL differences; stats: counts and time [s].
    """

    clearance_m: float
    collision_free: bool
    min_distance_m: float
    closest: PairMinimum | None
    pairs: list[PairMinimum]
    worst: list[PairMinimum]
    collisions: list[CollisionStretch]
    samples_in_collision: list[int]
    first_contact: PairMinimum | None
    allowed: list[tuple[str, str]]
    message: str
    notes: list[str]
    stats: dict
    self_clearance_m: float | None = None  # robot link vs robot link [m] (None: clearance_m)
    # Robot link pairs not checked, with class and reason (robots/<robot>/self_collision.yaml);
    # None: the robot has no matrix, every pair was checked.
    skipped_self_pairs: list | None = None
    # (a, b, reason) of the pairs not checked because one holds the other (the gripper
    # on the flange link, the part in the gripper): DrakeCell.held_contacts.
    held_contacts: list | None = None


def pair_names(pair: PairMinimum) -> str:
    """ "a vs b", a shape of the gripper named so ("finger (gripper) vs stand"): the
    gripper's shapes are named by the user, and it is the body nobody expects to hit."""
    owners = pair.group.split("-")  # "part-obstacle", ..., "robot-self"
    return " vs ".join(
        f"{name} (gripper)" if owner == "gripper" and name != "gripper" else name
        for name, owner in zip((pair.a, pair.b), owners, strict=True)
    )


def failure_message(first, stretch, closest, clearance) -> str:
    """One line: where the first overlap starts and the largest depth of that stretch,
    else the closest approach below the clearance; "" when clear."""
    if first is not None:
        return (
            f"collision: {pair_names(first)} at σ = {first.sigma_m:.4f} m, "
            f"t = {first.t_s:.3f} s, depth {stretch.worst.depth_m * 1e3:.2f} mm"
        )
    if closest is not None and closest.distance_m < clearance:
        return (
            f"clearance: {pair_names(closest)} at σ = {closest.sigma_m:.4f} m, "
            f"t = {closest.t_s:.3f} s: {max(closest.distance_m, 0.0) * 1e3:.2f} mm < "
            f"{clearance * 1e3:.2f} mm"
        )
    return ""


def _jsonable(value):
    if isinstance(value, float):
        return value if np.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    return value


def write_collisions_json(result: CollisionResult, path: Path) -> None:
    """Write the result as JSON (SI units; infinite distances as null), atomically."""
    text = json.dumps(_jsonable(dataclasses.asdict(result)), indent=2, ensure_ascii=False)
    write_atomic(Path(path), text + "\n")
