"""Collision verdicts come from the vendor's meshes, not the stand-ins, and self-collision
is checked only for the pairs the robot's matrix marks ``check``, each at its clearance."""

import dataclasses

import numpy as np
import pytest
from pydrake.math import RigidTransform

from offline_prog.collision.check import check_trajectory
from offline_prog.robot.model import load_robot
from offline_prog.scene.drake_cell import build_drake_cell
from offline_prog.scene.shapes import CellShape

# A point beside the KR 16's link_1 (at q = 0, in I = the base frame): 36 mm inside the
# stand-in's box, but more than 40 mm outside the vendor's collision mesh.
P_I_PROBE = np.array([-0.161, 0.199, 0.634])


def _check(robot, obstacles, q, **clearances):
    cell = build_drake_cell(
        robot,
        X_IB=RigidTransform(),
        X_IT=RigidTransform([3.0, 0, 0]),
        X_PE=RigidTransform([0, 0, -0.1]),
        obstacles=obstacles,
    )
    q = np.asarray(q, dtype=float)
    t = np.arange(len(q), dtype=float)
    return cell, check_trajectory(cell, q, t, t, **{"clearance": 0.005, **clearances})


def test_the_vendor_mesh_decides_where_the_stand_in_would_not():
    probe = CellShape("probe", "sphere", RigidTransform(P_I_PROBE), (0.005,))
    mesh_robot = load_robot("kuka_kr16_2")
    stand_in = dataclasses.replace(
        mesh_robot, urdf_path=mesh_robot.urdf_path.with_name("kuka_kr16_2_primitives.urdf")
    )
    q = np.zeros((2, 6))
    _, with_meshes = _check(mesh_robot, [probe], q)
    _, with_stand_ins = _check(stand_in, [probe], q)
    near = {(p.a, p.b): p for p in with_meshes.pairs}
    assert with_meshes.collision_free and near[("link_1", "probe")].distance_m > 0.03
    assert not with_stand_ins.collision_free
    assert with_stand_ins.message.startswith("collision: link_1 vs probe")
    # FCL on the vendor's triangles agrees with Drake's convex pieces.
    worst = [p for p in with_meshes.worst if (p.a, p.b) == ("link_1", "probe")]
    for pair in worst:
        assert abs(pair.exact_distance_m - pair.drake_distance_m) < 5e-4


def test_only_check_pairs_are_checked_and_skipped_pairs_are_listed():
    robot = load_robot("abb_irb2400")
    cell, result = _check(robot, [], np.zeros((2, 6)))
    skipped = {frozenset((p.a, p.b)): p for p in cell.skipped_self_pairs}
    assert skipped[frozenset(("link_4", "link_6"))].kind == "always"  # overlap by design
    checked = {frozenset((p.a, p.b)) for p in result.pairs}
    assert checked and not checked & set(skipped)
    assert frozenset(("link_2", "link_4")) in checked  # class "check"
    assert result.collision_free  # the always-overlapping pair does not fail the plan
    assert result.skipped_self_pairs == cell.skipped_self_pairs


def test_self_pairs_are_held_to_the_self_clearance():
    """UR10e: at q with the wrist folded, link_3 and link_5 come within ~10 mm."""
    robot = load_robot("ur10e")
    cell, probe = _check(robot, [], np.zeros((2, 6)))
    pairs = {(p.a, p.b): p.distance_m for p in probe.pairs}
    closest = min(pairs.values())
    assert all(a.startswith(("link", "base")) for a, _ in pairs)
    # The self-clearance alone decides: just above the closest self distance fails,
    # just below passes, whatever the (robot vs world) clearance is.
    _, strict = _check(robot, [], np.zeros((2, 6)), clearance=0.0, self_clearance=closest + 1e-3)
    _, loose = _check(robot, [], np.zeros((2, 6)), clearance=1.0, self_clearance=closest - 1e-3)
    assert not strict.collision_free and strict.message.startswith("clearance:")
    assert loose.collision_free


@pytest.mark.slow  # a full plan on a changed cell (~8 s)
def test_the_fixed_layout_is_checked_a_duct_through_the_base_fails(tmp_path):
    """Drake filters pairs of bodies welded together (robot base, tool, obstacles); a
    cable duct through the KR 16's base must still fail the plan, while the base
    resting on the floor (1 mm above it) and the tool on its stand do not."""
    from offline_prog.plan import plan_cell

    from conftest import CELLS

    text = (CELLS / "seal_plate_kr16.yaml").read_text().replace(": data/", f": {CELLS}/data/")
    assert "obstacles:   # in I" in text
    file = tmp_path / "duct.yaml"
    file.write_text(
        text.replace(
            "obstacles:   # in I",
            "obstacles:   # in I\n"
            "  - {name: cable_duct, shape: box, size_mm: [200, 200, 150], "
            "pose: {translation: [-0.25, 0.0, 0.25]}}",
        )
    )
    plan = plan_cell(file)
    assert not plan.feasible and plan.failure.startswith("collision: base_link vs cable_duct")
    pairs = {(p.a, p.b): p.distance_m for p in plan.collisions.pairs}
    assert pairs[("base_link", "cable_duct")] < -0.05  # overlapping by centimetres
    clear = plan_cell(CELLS / "seal_plate_kr16.yaml")
    fixed = {(p.a, p.b): p.distance_m for p in clear.collisions.pairs}
    assert clear.feasible and 0.0 <= fixed[("base_link", "floor")] < 0.005  # held to contact
    assert clear.collisions.closest.a != "base_link"  # the closest approach is of what moves


def test_pruned_pair_minima_are_labelled_as_bounds():
    """A pair certified far away is not measured at every sample, so its reported
    minimum is an upper bound of the true one: collisions.json says so."""
    from offline_prog.plan import plan_cell

    from conftest import CELLS

    plan = plan_cell(CELLS / "seal_plate_kr16.yaml")
    bounded = [p for p in plan.collisions.pairs if p.lower_bound_m is not None]
    exact = [p for p in plan.collisions.pairs if p.lower_bound_m is None]
    assert bounded and exact
    clearance = plan.cell.motion.clearance
    for pair in bounded:  # certified: the true minimum is above clearance + margin
        # (to rounding: on the seam the tool body is 25 mm under the plate, which is just
        # clearance + margin; a flying seam's leads lift it farther, so it is pruned there)
        assert pair.lower_bound_m > clearance
        assert pair.distance_m >= pair.lower_bound_m - 1e-12
