"""The place: block: bad input is one line naming file and key with exit 2, before any
work; a candidate's unit coordinates map onto the named ranges and nothing else."""

import numpy as np
import pytest

from offline_prog.cli import main
from offline_prog.config.cell import load_cell
from offline_prog.placement.space import check_place

from conftest import CELLS

DEMO = CELLS / "placement" / "seal_out_of_reach_kr16.yaml"


def _variant(tmp_path, old: str, new: str):
    text = DEMO.read_text()
    assert old in text
    file = tmp_path / "cell.yaml"
    file.write_text(text.replace(old, new))
    return file


@pytest.mark.parametrize(
    ("old", "new", "key", "reason"),
    [
        ("x: [700, 1900]", "x: [1900, 700]", "place.X_IT.translation_mm.x", "inverted range"),
        ("x: [700, 1900]", "x: [700, 700]", "place.X_IT.translation_mm.x", "empty range"),
        ("x: [700, 1900]", "x: []", "place.X_IT.translation_mm.x", "expected [low, high]"),
        ("yaw: [0, 60]", "yaw: [60, 0]", "place.X_IT.rpy_deg.yaw", "inverted range"),
        ("yaw: [0, 60]", "spin: [0, 60]", "place.X_IT.rpy_deg.spin", "unknown key"),
        ("budget: 16", "budget: 0", "place.budget", "outside 1..100,000"),
        # numpy takes seeds below 2³²
        ("seed: 0", "seed: 4294967295", "place.seed", "outside 0..2,147,483,647"),
        ("seed: 0", "seed: -1", "place.seed", "outside 0..2,147,483,647"),
        (
            "moves_with_tool: [nozzle_stand]",
            "moves_with_tool: [stand]",
            "place.moves_with_tool[0]",
            "'stand' is not an obstacle",
        ),
        (
            "moves_with_tool: [nozzle_stand]",
            "moves_with_tool: [fence_post]\n  stand_max_length_mm: 1000",
            "place.stand_max_length_mm",
            "1000 mm is shorter than 'fence_post' as given (2000 mm)",
        ),
        (
            "moves_with_tool: [nozzle_stand]",
            "moves_with_tool: [nozzle_stand]\n  stand_max_length_mm: 0",
            "place.stand_max_length_mm",
            "outside (0, 10000] mm",
        ),
        (
            "size_mm: [200, 200, 500], pose: {translation: [2.2, 0.4, 0.250]}",
            "size_mm: [200, 200, 500], pose: {translation: [2.2, 0.4, 0.250], "
            "rotation: !Rpy {deg: [5, 0, 0]}}",
            "place.moves_with_tool[0]",
            "'nozzle_stand' is not upright",
        ),
        (
            "{name: nozzle_stand, shape: box, size_mm: [200, 200, 500],",
            "{name: nozzle_stand, shape: sphere, radius_mm: 100,",
            "place.moves_with_tool[0]",
            "'nozzle_stand' is a sphere: a stand keeps its foot on the floor by its length",
        ),
        (
            "  X_PE:   ",
            "  X_PE:\n    rpy_deg: {yaw: [-10, 10]}\n  ",
            "place.X_PE.rpy_deg.yaw",
            "the grasps differ on this axis",
        ),
    ],
)
def test_bad_place_input_is_one_line_exit_2_nothing_written(
    tmp_path, capsys, old, new, key, reason
):
    file = _variant(tmp_path, old, new)
    out = tmp_path / "out"
    code = main(["place", str(file), "--out", str(out), "--workers", "0"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert str(file) in err[0] and key in err[0] and reason in err[0], err[0]
    assert not out.exists()


@pytest.mark.parametrize(
    ("flag", "value", "reason"),
    [
        ("--budget", "200000", "'200000': need an integer >= 1 and <= 100000"),
        ("--budget", "2.5", "'2.5' is not an integer"),
        ("--seed", "4294967295", "'4294967295': need an integer >= 0 and <= 2147483647"),
    ],
)
def test_a_bad_flag_is_blamed_on_the_flag(tmp_path, capsys, flag, value, reason):
    """Not on the cell's place.budget / place.seed, which the flag overrides."""
    with pytest.raises(SystemExit) as stop:
        main(["place", str(DEMO), flag, value, "--out", str(tmp_path / "o"), "--workers", "0"])
    err = capsys.readouterr().err.strip().splitlines()
    assert stop.value.code == 2 and len(err) == 1, err
    assert err[0] == f"error: argument {flag}: {reason} (see offline-prog place --help)"
    assert not (tmp_path / "o").exists()


def test_a_cell_without_place_and_a_budget_flag_of_0_are_refused(tmp_path, capsys):
    code = main(["place", str(CELLS / "seal_plate_kr16.yaml"), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "place: missing" in err[0], err
    with pytest.raises(SystemExit) as stop:
        main(["place", str(DEMO), "--budget", "0", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert stop.value.code == 2 and len(err) == 1 and "--budget" in err[0], err
    assert not (tmp_path / "o").exists()


def test_unit_coordinates_map_onto_the_named_ranges_only(rng):
    cell = load_cell(DEMO)
    place, space = check_place(DEMO, cell)
    assert [a.key for a in space.axes] == [
        "place.X_IT.translation_mm.x",
        "place.X_IT.translation_mm.y",
        "place.X_IT.translation_mm.z",
        "place.X_IT.rpy_deg.yaw",
    ]
    low, high = space.candidate([0, 0, 0, 0], 1), space.candidate([1, 1, 1, 1], 1)
    assert low.X_IT == ((0.7, -0.4, 0.4), (90.0, 0.0, 0.0))
    assert high.X_IT == ((1.9, 0.4, 0.9), (90.0, 0.0, 60.0))
    assert low.X_PE == ((0.0, 0.0, 0.1), (180.0, 0.0, 90.0))  # the second grasp as given
    for x in rng.uniform(0, 1, size=(50, 4)):
        c = space.candidate(x, 0)
        p, rpy = c.X_IT
        expected = [0.7 + 1.2 * x[0], -0.4 + 0.8 * x[1], 0.4 + 0.5 * x[2]]
        assert np.allclose(p, expected, atol=5e-5)  # rounded to 0.1 mm
        assert rpy[:2] == (90.0, 0.0) and abs(rpy[2] - 60 * x[3]) <= 5e-4
    grid = space.grid(place.screen_points)
    assert len(grid) == 2 * 5**4  # 5 levels of 4 axes ≤ 1000 points, per grasp
    assert len({c.X_IT for c in grid}) == 5**4
    levels = np.unique(np.round(np.array([c.x for c in grid]), 9))
    assert np.allclose(levels, [0.1, 0.3, 0.5, 0.7, 0.9])  # cell-centred for seed 0
    shifted = space.grid(place.screen_points, seed=7)
    steps = np.array([c.x for c in shifted]) - np.array([c.x for c in grid])
    assert np.allclose(steps, steps[0]) and 0 < np.abs(steps[0]).max() <= 0.1  # one shift
    assert [c.X_IT for c in space.grid(place.screen_points, seed=7)] == [c.X_IT for c in shifted]


@pytest.mark.parametrize("file", sorted((CELLS / "placement").glob("*.yaml")), ids=lambda f: f.stem)
def test_every_placement_demo_is_valid_and_its_stands_stand(file):
    from offline_prog.placement.stand import stands

    cell = load_cell(file)
    place, space = check_place(file, cell)
    assert space.dimensions >= 4 and place.budget <= 16
    for stand in stands(cell):
        assert stand.foot_z == pytest.approx(0.0, abs=1e-9)  # on the floor (z = 0 of I)
