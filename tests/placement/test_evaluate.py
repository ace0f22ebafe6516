"""A candidate is judged by plan's own pipeline: the cell as given evaluates to the plan
of the cell; an infeasible candidate says how far it is from feasible, growing the
farther it is; the tool's stand moves with the tool; the cell travels whole."""

import dataclasses
import math

import numpy as np
import pytest
from pydrake.math import RollPitchYaw

from offline_prog.config.cell import load_cell, transform
from offline_prog.joints.path_ik import reach_excess
from offline_prog.placement.context import context, placed_cell
from offline_prog.placement.evaluate import evaluate
from offline_prog.placement.objective import CANNOT_FOLLOW, COLLIDES, FEASIBLE, STAND, Evaluation
from offline_prog.placement.payload import cell_payload, unpack
from offline_prog.placement.screen import screen
from offline_prog.placement.space import Candidate, check_place
from offline_prog.robot.model import load_robot

from conftest import CELLS

DEMO = CELLS / "placement" / "seal_out_of_reach_kr16.yaml"


@pytest.fixture(scope="module")
def seal():
    file = CELLS / "seal_plate_kr16.yaml"
    return context(cell_payload(file, load_cell(file)))


def test_the_cell_as_given_evaluates_to_its_plan(seal, planned_job):
    """A path: cell is a one-seam job: the candidate's cycle time is the job's, home to
    home, and its clearance the whole job's."""
    job, _ = planned_job("seal_plate_kr16")
    plan, cell = job.seams[0], job.cell
    X_IT = (tuple(cell.tool.X_IT.translation), (90.0, 0.0, 0.0))
    X_PE = (tuple(cell.part.X_PE.translation), (180.0, 0.0, 0.0))
    e = evaluate(seal, Candidate((), -1, X_IT, X_PE))
    assert e.tier == FEASIBLE and e.reason == ""
    assert e.cycle_time_s == pytest.approx(job.samples.t[-1], abs=1e-9)
    assert e.air_time_s == pytest.approx(job.samples.t[-1] - plan.trajectory.duration, abs=1e-9)
    assert e.joint_limit_margin_deg == pytest.approx(np.rad2deg(plan.joints.margin_rad.min()))
    assert e.clearance_mm == pytest.approx(job.collisions.min_distance_m * 1e3)
    assert e.process_bound_s == pytest.approx(plan.nominal_duration_s)
    assert e.quality_share == pytest.approx(job.quality.job.share_within_band, abs=1e-12)
    assert screen(seal, Candidate((), -1, X_IT, X_PE)).tier == FEASIBLE


def test_with_a_process_model_the_share_within_the_band_comes_before_cycle_time():
    """A feasible candidate with more of its bead within the band ranks first, however
    much faster the other is; without a model (NaN) the cycle time decides; feasibility
    still comes before the quality."""
    base = Evaluation(
        Candidate((), -1, ((0, 0, 0), (0, 0, 0)), ((0, 0, 0), (0, 0, 0))), "plan", FEASIBLE, 0.0, ""
    )
    better = dataclasses.replace(base, quality_share=0.98, cycle_time_s=40.0)
    faster = dataclasses.replace(base, quality_share=0.90, cycle_time_s=20.0)
    assert min([faster, better], key=Evaluation.key) is better
    no_model = [dataclasses.replace(x, quality_share=math.nan) for x in (better, faster)]
    assert min(no_model, key=Evaluation.key).cycle_time_s == 20.0
    tie = dataclasses.replace(faster, quality_share=0.98 + 1e-5)  # within the resolution
    assert min([better, tie], key=Evaluation.key) is tie
    colliding = dataclasses.replace(better, tier=COLLIDES, violation=1e-3, quality_share=1.0)
    assert min([colliding, faster], key=Evaluation.key) is faster


def test_out_of_reach_grows_with_the_distance(seal):
    X_PE = ((0.0, 0.0, 0.1), (180.0, 0.0, 0.0))
    screened = [
        screen(seal, Candidate((), -1, ((x, 0.0, 0.5), (90.0, 0.0, 0.0)), X_PE))
        for x in (1.75, 1.9, 2.2, 2.6)
    ]
    assert all(e.tier == CANNOT_FOLLOW and e.reason == "out of reach" for e in screened)
    violations = [e.violation for e in screened]
    assert violations == sorted(violations) and violations[0] < violations[-1], violations
    far = evaluate(seal, Candidate((), -1, ((2.2, 0.0, 0.5), (90.0, 0.0, 0.0)), X_PE))
    assert far.tier == CANNOT_FOLLOW and "out of reach" in far.reason and far.violation > 0


def _stand(cell):
    return next(o for o in cell.obstacles if o.name == "nozzle_stand")


def test_the_stand_stands_with_the_tool_its_foot_on_the_floor():
    """The stand's top keeps its place under the tool (turned with the tool's yaw), its
    foot stays on the floor and its length makes up the difference; the other
    obstacles stay where they are."""
    cell = load_cell(DEMO)
    _, space = check_place(DEMO, cell)
    ctx = context(cell_payload(DEMO, cell))
    stand = _stand(cell)
    X_IO = transform(stand.pose)
    X_IT = transform(cell.tool.X_IT)
    p_TO_top = X_IT.inverse().multiply(X_IO.translation() + [0.0, 0.0, 0.25])  # its top in T
    for x in ([0.3, 0.7, 0.5, 0.4], [0.0, 0.0, 0.0, 1.0], [1.0, 1.0, 1.0, 0.0]):
        candidate = space.candidate(x, 1)
        moved = placed_cell(ctx, candidate)
        placed = _stand(moved)
        X_IO_new, X_IT_new = transform(placed.pose), transform(moved.tool.X_IT)
        length = 1e-3 * placed.size_mm[2]
        top = X_IO_new.translation() + [0.0, 0.0, length / 2]
        foot = X_IO_new.translation()[2] - length / 2
        assert foot == pytest.approx(0.0, abs=1e-6)  # on the floor, as given
        assert np.allclose(X_IT_new.inverse().multiply(top), p_TO_top, atol=2e-6)
        assert length == pytest.approx(0.5 + X_IT_new.translation()[2] - 0.7, abs=2e-6)
        yaw = candidate.X_IT[1][2]
        assert RollPitchYaw(X_IO_new.rotation()).vector() == pytest.approx(
            [0.0, 0.0, np.deg2rad(yaw)], abs=1e-8
        )
        others = [repr(o) for o in moved.obstacles if o.name != "nozzle_stand"]
        assert others == [repr(o) for o in cell.obstacles if o.name != "nozzle_stand"]
    assert moved.part.X_PE.rotation.value.deg.tolist() == [180.0, 0.0, 90.0]


def test_a_stand_beyond_its_limit_makes_the_candidate_infeasible():
    """A tool 2.4 m above the floor needs a 2.2 m stand, beyond the default 2 m; one
    below the stand's foot, a stand shorter than none: both screened out and
    infeasible, before any plan."""
    cell = load_cell(DEMO)
    ctx = context(cell_payload(DEMO, cell))
    X_PE = ((0.0, 0.0, 0.1), (180.0, 0.0, 0.0))
    for z, words in ((2.4, "beyond place.stand_max_length_mm (2000 mm)"), (0.1, "too low")):
        candidate = Candidate((), -1, ((1.0, 0.0, z), (90.0, 0.0, 0.0)), X_PE)
        screened, planned = screen(ctx, candidate), evaluate(ctx, candidate)
        for e in (screened, planned):
            assert e.tier == STAND and e.failure == "stand" and words in e.reason
        assert screened.screened_out == "stand" and screened.violation > 0


def test_the_payload_carries_the_cell_and_its_data_files():
    file = CELLS / "weld_seam_irb2400.yaml"
    payload = cell_payload(file, load_cell(file))
    names = dict(payload.files)
    assert set(names) == {"weld_seam_irb2400.yaml", "data/weld_seam.dxf"}
    copy = unpack(payload)
    assert copy.read_bytes() == file.read_bytes()
    assert (copy.parent / "data/weld_seam.dxf").read_bytes() == (
        CELLS / "data/weld_seam.dxf"
    ).read_bytes()
    again = cell_payload(file, dataclasses.replace(load_cell(file)))
    assert again.digest == payload.digest


@pytest.mark.parametrize("name", ["kuka_kr16_2", "abb_irb2400", "ur10e"])
def test_reach_excess_is_zero_wherever_the_robot_reaches_and_grows_outside(name, rng):
    robot = load_robot(name)
    X_BE = robot.forward(rng.uniform(robot.q_lower, robot.q_upper, size=(1000, 6)))
    assert reach_excess(robot, X_BE).max() == 0.0
    out = X_BE.copy()
    out[:, :3, 3] *= 3.0  # three times as far from the base: beyond reach
    far = out.copy()
    far[:, :3, 3] *= 2.0
    beyond = reach_excess(robot, out) > 0  # most, not the poses near the base
    assert beyond.mean() > 0.8
    assert np.all(reach_excess(robot, far)[beyond] > reach_excess(robot, out)[beyond])


def test_a_job_is_screened_seam_by_seam():
    file = CELLS / "seal_job_kr16.yaml"
    ctx = context(cell_payload(file, load_cell(file)))
    assert [s.inputs.cell.path.analytic.kind for s in ctx.seams] == [
        "rounded_rectangle",
        "arc",
        "arc",
        "line",
    ]
    X_PE = ((0.0, 0.0, 0.1), (180.0, 0.0, 0.0))
    given = screen(ctx, Candidate((), -1, ((1.0, 0.0, 0.5), (90.0, 0.0, 0.0)), X_PE))
    assert given.tier == FEASIBLE
    one = context(
        cell_payload(CELLS / "seal_plate_kr16.yaml", load_cell(CELLS / "seal_plate_kr16.yaml"))
    )
    border = screen(one, Candidate((), -1, ((1.0, 0.0, 0.5), (90.0, 0.0, 0.0)), X_PE))
    assert given.cycle_time_s > border.cycle_time_s  # the border and three more seams
    far = screen(ctx, Candidate((), -1, ((2.4, 0.0, 0.5), (90.0, 0.0, 0.0)), X_PE))
    assert far.tier == CANNOT_FOLLOW and far.failure == "out_of_reach"
    assert far.violation > 3.0  # all four seams out of reach, each adding its share


def test_the_payload_keeps_symlinked_and_absolute_data_files(tmp_path):
    """A data file behind a symlink (the path as written, not its target) and one given
    by an absolute path both travel: the unpacked cell names its own copies."""
    shared, data, cells = (tmp_path / n for n in ("shared", "data", "cells"))
    for folder in (shared, data, cells):
        folder.mkdir()
    dxf = CELLS / "data" / "weld_seam.dxf"
    (shared / "weld_seam.dxf").write_bytes(dxf.read_bytes())
    (data / "weld_seam.dxf").symlink_to(shared / "weld_seam.dxf")
    text = (CELLS / "weld_seam_irb2400.yaml").read_text()
    for name, source in (
        ("linked", "../data/weld_seam.dxf"),
        ("absolute", str(shared / "weld_seam.dxf")),
    ):
        file = cells / f"{name}.yaml"
        file.write_text(text.replace("dxf: data/weld_seam.dxf", f"dxf: {source}"))
        copy = unpack(cell_payload(file, load_cell(file)))
        named = load_cell(copy).path.dxf
        assert not named.startswith("/") and (copy.parent / named).read_bytes() == dxf.read_bytes()
        assert str(tmp_path) not in copy.read_text()  # nothing read from the user's disk


def test_why_not_more_names_the_fixed_tool_turn():
    """A small cut whose cause is the wrist's turn at the corners says so, and names
    tool.turn_smoothing_mm when the round tool's turn is fixed."""
    import dataclasses

    from offline_prog.config.cell import ToolConfig
    from offline_prog.placement.objective import FEASIBLE, Evaluation
    from offline_prog.placement.outputs import cycle_time_cut
    from offline_prog.placement.search import Placement
    from offline_prog.placement.space import Candidate

    pose = ((1.0, 0.0, 0.5), (90.0, 0.0, 0.0))
    run = Evaluation(
        Candidate((), -1, pose, pose),
        "plan",
        FEASIBLE,
        0.0,
        "",
        cycle_time_s=14.0,
        process_bound_s=12.0,
        slowed_share=0.2,
        limiting_axis=6,
    )
    base = dataclasses.replace(run, cycle_time_s=14.5)
    result = Placement(run, base, [base, run], [], [], 1.0)
    fixed = ToolConfig(free_rotation_deg=90.0)
    why = cycle_time_cut(result, fixed)["why_not_more"]
    assert "limited by axis 6" in why and "tool.turn_smoothing_mm" in why
    turning = dataclasses.replace(fixed, turn_smoothing_mm=30.0)
    assert "tool.turn_smoothing_mm" not in cycle_time_cut(result, turning)["why_not_more"]
    # A slowdown at the shoulder is not the part's turn: no hint.
    shoulder = [dataclasses.replace(e, limiting_axis=2) for e in (run, base)]
    result = Placement(shoulder[0], shoulder[1], shoulder[::-1], [], [], 1.0)
    why = cycle_time_cut(result, fixed)["why_not_more"]
    assert "limited by axis 2" in why and "tool.turn_smoothing_mm" not in why
