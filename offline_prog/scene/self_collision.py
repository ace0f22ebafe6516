"""The robot's self-collision matrix, computed by sampling and explained pair by pair.

Like MoveIt's Setup Assistant, configurations are sampled uniformly within the joint
limits (the controller's axes, so the ABB J2/J3 coupling is respected) and every pair of
links with collision geometry is measured with SceneGraph's signed distance; unlike it,
each pair keeps the distances that decided its class:

- ``adjacent``: joined by a joint (Drake filters such pairs; they meet at the joint);
- ``always``: in contact in every sample (the meshes overlap by design);
- ``constant``: distance spread under CONSTANT_SPREAD_M over all samples (a model
  artefact, not a hazard);
- ``never``: never closer than NEVER_MARGIN_M in any sample (sampling can miss a rare
  pose, so the margin is far above any clearance);
- ``check``: everything else; the planner checks only these for self-collision.

The result is YAML (deterministic for a seed); the planner reads the robot folder's
``robots/<robot>/self_collision.yaml`` with :func:`read_matrix`.
"""

from __future__ import annotations

import dataclasses
import datetime
from pathlib import Path

import numpy as np
import yaml
from pydrake.planning import RobotDiagramBuilder

from offline_prog.robot.model import RobotModel

MATRIX_FILE = "self_collision.yaml"
CLASSES = ("adjacent", "always", "constant", "never", "check")
NEVER_MARGIN_M = 0.05
CONSTANT_SPREAD_M = 1e-4
DEFAULT_SAMPLES = 10_000


@dataclasses.dataclass(frozen=True)
class LinkPair:
    """One link pair's verdict: class, the distances measured [m] (None if not
    measured) and why."""

    a: str
    b: str
    kind: str
    min_distance_m: float | None
    max_distance_m: float | None
    reason: str


def compute_matrix(robot: RobotModel, *, samples: int = DEFAULT_SAMPLES, seed: int = 0):
    """Classify every link pair of ``robot`` by sampling ``samples`` configurations.

    Returns:
        list[LinkPair], sorted by (a, b) in the URDF's link order.
    """
    builder = RobotDiagramBuilder(time_step=0.0)
    plant = builder.plant()
    (model,) = builder.parser().AddModels(str(robot.urdf_path))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("base_link", model))
    plant.Finalize()
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    scene_graph = diagram.scene_graph()
    inspector = scene_graph.model_inspector()
    query_port = scene_graph.get_query_output_port()
    sg_context = scene_graph.GetMyContextFromRoot(context)
    bodies = [plant.get_body(b) for b in plant.GetBodyIndices(model)]
    geometries = {b.name(): plant.GetCollisionGeometriesForBody(b) for b in bodies}
    links = [b.name() for b in bodies if geometries[b.name()]]
    joints = [plant.get_joint(j) for j in plant.GetJointIndices(model)]
    adjacent = {
        frozenset((j.parent_body().name(), j.child_body().name())): j.name()
        for j in joints
        if j.num_positions() == 1
    }
    pairs = [(a, b) for i, a in enumerate(links) for b in links[i + 1 :]]
    measured = [p for p in pairs if frozenset(p) not in adjacent]
    rng = np.random.default_rng(seed)
    q_c = rng.uniform(robot.q_lower, robot.q_upper, size=(samples, len(robot.q_lower)))
    q = robot.urdf_joints(q_c)
    distances = np.empty((samples, len(measured)))
    for i, q_i in enumerate(q):
        plant.SetPositions(plant_context, model, q_i)
        query = query_port.Eval(sg_context)
        for k, (a, b) in enumerate(measured):
            distances[i, k] = min(
                (
                    query.ComputeSignedDistancePairClosestPoints(g, h).distance
                    for g in geometries[a]
                    for h in geometries[b]
                    if not inspector.CollisionFiltered(g, h)
                ),
                default=np.inf,
            )
    out = [
        LinkPair(a, b, "adjacent", None, None, f"joined by {adjacent[frozenset((a, b))]}")
        for a, b in pairs
        if frozenset((a, b)) in adjacent
    ]
    for k, (a, b) in enumerate(measured):
        low, high = float(distances[:, k].min()), float(distances[:, k].max())
        out.append(LinkPair(a, b, *_classify(low, high, samples)))
    order = {name: i for i, name in enumerate(links)}
    return sorted(out, key=lambda p: (order[p.a], order[p.b]))


def _classify(low: float, high: float, samples: int) -> tuple[str, float, float, str]:
    if high <= 0.0:
        return "always", low, high, f"in contact in all {samples} samples (meshes overlap)"
    if high - low < CONSTANT_SPREAD_M:
        return (
            "constant",
            low,
            high,
            (
                f"distance varies by {(high - low) * 1e3:.3f} mm < "
                f"{CONSTANT_SPREAD_M * 1e3:.1f} mm: a model artefact, not a hazard"
            ),
        )
    if low > NEVER_MARGIN_M:
        return (
            "never",
            low,
            high,
            (
                f"never closer than {low * 1e3:.0f} mm in {samples} samples "
                f"(margin {NEVER_MARGIN_M * 1e3:.0f} mm)"
            ),
        )
    return "check", low, high, f"as close as {low * 1e3:.1f} mm: checked"


def matrix_yaml(robot: RobotModel, pairs: list[LinkPair], *, samples: int, seed: int) -> str:
    """The matrix as YAML text (one mapping per pair; distances in metres)."""
    record = {
        "robot": robot.name,
        "samples": samples,
        "seed": seed,
        "never_margin_m": NEVER_MARGIN_M,
        "constant_spread_m": CONSTANT_SPREAD_M,
        "pairs": [
            {
                "a": p.a,
                "b": p.b,
                "class": p.kind,
                "min_distance_m": None if p.min_distance_m is None else round(p.min_distance_m, 6),
                "max_distance_m": None if p.max_distance_m is None else round(p.max_distance_m, 6),
                "reason": p.reason,
            }
            for p in pairs
        ],
    }
    header = (
        f"# Self-collision matrix of {robot.name}: written by "
        f"`offline-prog robots self-collision {robot.name} --samples {samples} --seed {seed}`"
        f" ({datetime.date.today().isoformat()}).\n# The planner checks only the pairs of "
        "class `check` for self-collision; the others are listed in each report.\n"
    )
    return header + yaml.safe_dump(record, sort_keys=False, width=100)


def read_matrix(robot_folder: Path) -> list[LinkPair] | None:
    """The pairs of ``robot_folder/self_collision.yaml``, or None if there is none.

    Raises:
        ValueError: one line naming the file when it is unreadable or malformed.
    """
    file = Path(robot_folder) / MATRIX_FILE
    if not file.is_file():
        return None
    text = file.read_text(encoding="utf-8")
    key = (str(file.resolve()), text)
    pairs = _matrices.get(key)  # a plan (a session's re-plan) builds its cell each time
    if pairs is None:
        pairs = _parse_matrix(file, text)
        _matrices.clear()  # the last file read only: one robot per cell
        _matrices[key] = pairs
    return list(pairs)


_matrices: dict[tuple[str, str], tuple[LinkPair, ...]] = {}


def _parse_matrix(file: Path, text: str) -> tuple[LinkPair, ...]:
    try:
        record = yaml.safe_load(text)
        pairs = [
            LinkPair(
                str(p["a"]),
                str(p["b"]),
                str(p["class"]),
                p["min_distance_m"],
                p["max_distance_m"],
                str(p["reason"]),
            )
            for p in record["pairs"]
        ]
    except (yaml.YAMLError, KeyError, TypeError) as error:
        raise ValueError(f"{file}: not a self-collision matrix ({error})") from None
    for p in pairs:
        if p.kind not in CLASSES:
            raise ValueError(f"{file}: pairs: class {p.kind!r} is not one of {', '.join(CLASSES)}")
    return tuple(pairs)


def write_matrix(robot: RobotModel, file: Path, *, samples: int, seed: int):
    """Compute the matrix and write it to ``file`` (atomically); returns the pairs.

    The planner reads the robot folder's own ``self_collision.yaml``
    (:func:`read_matrix`); the command line writes where the user says and tells how
    to put it there, never over the file shipped with the package unasked.
    """
    from offline_prog.atomic import write_atomic

    pairs = compute_matrix(robot, samples=samples, seed=seed)
    write_atomic(Path(file), matrix_yaml(robot, pairs, samples=samples, seed=seed))
    return pairs
