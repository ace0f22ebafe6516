"""Each pair's motion bound: seen from one side, the other moves no farther than the
joints between them allow (its span), the last of them by the outer side's own reach
from its axis."""

import numpy as np
import pytest

from offline_prog.collision.pairs import Pairs, chain_links
from offline_prog.config.cell import load_cell
from offline_prog.robot.model import load_robot
from offline_prog.scene.drake_cell import build_cell_model
from offline_prog.scene.exact_distance import bounding_radius

from conftest import CELLS


@pytest.fixture(scope="module", params=["seal_plate_kr16", "tape_cylinder_ur10e"])
def scene(request):
    file = CELLS / f"{request.param}.yaml"
    cell = load_cell(file)
    return build_cell_model(cell, file, load_robot(cell.robot.model))


def test_a_pair_moves_within_its_own_bound(scene, rng):
    """For random joint steps, every point of each pair's outer side (on its geometry's
    bounding sphere) moves, seen from the inner side's body, by at most |Δq| @ its row
    of ``pair_radii``, which is at most its span's row and the global bound."""
    pairs, rho = Pairs(scene), scene.motion_radii()
    rows, spans = pairs.pair_radii(rho), pairs.span_radii(rho)[pairs.span_of]
    assert np.all(rows <= spans + 1e-15) and np.all(spans <= rho + 1e-15)
    plant, context = scene.plant, scene.plant.CreateDefaultContext()
    inspector = scene.diagram.scene_graph().model_inspector()
    link = chain_links(scene)
    assert link["gripper"] == link["part"] == 6 and link["tool"] == link["world"] == 0
    picked = rng.choice(len(pairs.ids), size=min(60, len(pairs.ids)), replace=False)
    for _ in range(40):
        q_a = rng.uniform(-np.pi, np.pi, 6)
        q_b = q_a + rng.normal(scale=0.2, size=6) * (rng.uniform(size=6) < 0.5)
        for g in picked:
            ids = pairs.ids[g]
            outer = pairs.outer[g]
            inner = ids[1] if outer == ids[0] else ids[0]
            body_in, body_out = (
                plant.GetBodyFromFrameId(inspector.GetFrameId(i)) for i in (inner, outer)
            )
            directions = rng.normal(size=(8, 3))
            directions /= np.linalg.norm(directions, axis=1, keepdims=True)
            X_BG = inspector.GetPoseInFrame(outer)
            p_BQ = X_BG @ (bounding_radius(inspector.GetShape(outer)) * directions.T)
            seen = []
            for q in (q_a, q_b):
                plant.SetPositions(context, q)
                X_AB = plant.CalcRelativeTransform(
                    context, body_in.body_frame(), body_out.body_frame()
                )
                seen.append(X_AB @ p_BQ)
            moved = np.linalg.norm(seen[1] - seen[0], axis=0).max()
            bound = np.abs(q_b - q_a) @ rows[g]
            assert moved <= bound + 1e-12, (pairs.names[pairs.shape_of[g]], moved, bound)
