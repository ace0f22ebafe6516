"""Bad ``process:`` input ends with one line naming the file and the key, exit 2, and
nothing written (issue 28's acceptance): a negative or zero parameter, an inverted
band, a model without its section, a bead without its flow output, and (issue 36)
physics no process has, each named by its key where the speed band check named only
the speed before, or planned to a report of 100 % in band; and a bead lag the approach
leaves no room for names ``process.bead.lag_s`` (the key that sets it)."""

import re

import pytest

from offline_prog.cli import main

from conftest import CELLS, with_own_io

SEAL = (CELLS / "seal_plate_kr16.yaml").read_text()
TAPE = (CELLS / "tape_cylinder_ur10e.yaml").read_text()
WELD = (CELLS / "weld_seam_irb2400.yaml").read_text()


def plan(capsys, tmp_path, text: str) -> tuple[int, list[str]]:
    cell = tmp_path / "cell.yaml"
    cell.write_text(text.replace(": data/", f": {CELLS}/data/"))
    capsys.readouterr()
    try:
        code = main(["plan", str(cell), "--out", str(tmp_path / "out")])
    except SystemExit as exit:
        code = exit.code
    return code, capsys.readouterr().err.strip().splitlines()


BAD = [
    (SEAL, "area_mm2: 12.0", "area_mm2: -12.0", "process.bead.area_mm2"),
    (
        SEAL,
        "flow_mm3_s_per_unit: 250.0",
        "flow_mm3_s_per_unit: 0",
        "process.bead.flow_mm3_s_per_unit",
    ),
    (SEAL, "tolerance_pct: 5", "tolerance_pct: 0", "process.bead.tolerance_pct"),
    (SEAL, "lag_s: 0.08", "lag_s: -0.08", "process.bead.lag_s"),
    (WELD, "voltage_v: 12.0", "voltage_v: 0", "process.heat_input.voltage_v"),
    (WELD, "current_a: 120.0", "current_a: -120", "process.heat_input.current_a"),
    (WELD, "[0.095, 0.125]", "[0.125, 0.095]", "process.heat_input.target_kj_mm"),
    (TAPE, "[380, 420]", "[420, 380]", "process.tape_heating.target_c"),
    (TAPE, "thickness_mm: 0.2", "thickness_mm: -0.2", "process.tape_heating.thickness_mm"),
    (TAPE, "max_power_w: 3000", "max_power_w: 0", "process.tape_heating.max_power_w"),
    (TAPE, "w_per_unit: 300", "w_per_unit: 0", "process.tape_heating.power_output.w_per_unit"),
    # The model is checked before the flow keys it decides (not "flow.per_mps missing").
    # A UR has standard analog outputs 0 and 1: the heater's output is checked like the flow's.
    (
        TAPE,
        "analog_output: 1, w_per_unit",
        "analog_output: 2, w_per_unit",
        "process.tape_heating.power_output.analog_output",
    ),
    (SEAL, "model: bead", "model: beads", "process.model"),
    (SEAL, "model: bead", "model: heat_input", "process.heat_input"),
    (SEAL, "area_mm2: 12.0", "area_mm2: .nan", "process.bead.area_mm2"),
]
# Physical bounds (issue 36: a 1 m² bead, an 864 MW arc, ambient −300 °C, a band up to
# 10⁷ °C were planned; units slipped by 1000 too).
PHYSICS = [
    (SEAL, "area_mm2: 12.0", "area_mm2: 1000000.0", "process.bead.area_mm2"),
    (
        SEAL,
        "flow_mm3_s_per_unit: 250.0",
        "flow_mm3_s_per_unit: 2.5e+08",
        "process.bead.flow_mm3_s_per_unit",
    ),
    (WELD, "current_a: 120.0", "current_a: 1.2e+08", "process.heat_input.current_a"),
    (WELD, "voltage_v: 12.0", "voltage_v: 12000.0", "process.heat_input.voltage_v"),
    (WELD, "[0.095, 0.125]", "[95.0, 125.0]", "process.heat_input.target_kj_mm"),
    (TAPE, "ambient_c: 20", "ambient_c: -300", "process.tape_heating.ambient_c"),
    (TAPE, "[380, 420]", "[380, 1.0e+07]", "process.tape_heating.target_c"),
    (TAPE, "width_mm: 25.0", "width_mm: 25000.0", "process.tape_heating.width_mm"),
    (TAPE, "thickness_mm: 0.2", "thickness_mm: 200.0", "process.tape_heating.thickness_mm"),
    (TAPE, "density_kg_m3: 1550", "density_kg_m3: 1.55", "process.tape_heating.density_kg_m3"),
    (TAPE, "density_kg_m3: 1550", "density_kg_m3: 1.55e+05", "process.tape_heating.density_kg_m3"),
    (
        TAPE,
        "specific_heat_j_kg_k: 1200",
        "specific_heat_j_kg_k: 1.2",
        "process.tape_heating.specific_heat_j_kg_k",
    ),
    (
        TAPE,
        "specific_heat_j_kg_k: 1200",
        "specific_heat_j_kg_k: 1.2e+05",
        "process.tape_heating.specific_heat_j_kg_k",
    ),
    (TAPE, "max_power_w: 3000", "max_power_w: 3.0e+06", "process.tape_heating.max_power_w"),
    (
        TAPE,
        "w_per_unit: 300",
        "w_per_unit: 3.0e+06",
        "process.tape_heating.power_output.w_per_unit",
    ),
]


CASES = [(*case, False) for case in BAD] + [(*case, True) for case in PHYSICS]


@pytest.mark.parametrize(
    ("text", "old", "new", "key", "physics"), CASES, ids=[c[3] + ":" + c[2] for c in CASES]
)
def test_a_bad_parameter_is_one_line_naming_its_key(capsys, tmp_path, text, old, new, key, physics):
    """A physical bound's line names the key, the value, the bound and why (the
    physics, or the unit that likely slipped)."""
    assert old in text
    code, err = plan(capsys, tmp_path, text.replace(old, new, 1))
    assert code == 2 and len(err) == 1, err
    assert "cell.yaml" in err[0] and f": {key}: " in err[0], err
    if physics:
        assert " is above " in err[0] or " is below " in err[0], err
    assert not (tmp_path / "out").exists()


def test_a_model_without_its_section(capsys, tmp_path):
    text = re.sub(r"(?m)^  bead: \{.*\}\n", "", SEAL)
    code, err = plan(capsys, tmp_path, text)
    assert code == 2 and len(err) == 1 and ": process.bead: " in err[0], err
    assert "needs its section" in err[0]


def test_a_bead_without_its_flow_output(capsys, tmp_path):
    """The bead model sets the flow output's gain and lead: without the output there is
    nothing to program (the model must not be ignored)."""
    text = re.sub(r"(?m)^  process_io:\n(    .*\n)*", "", SEAL)
    code, err = plan(capsys, tmp_path, text)
    assert code == 2 and len(err) == 1 and ": tool.process_io.flow: " in err[0], err


def test_a_bead_lag_longer_than_the_approach_names_the_bead_key(capsys, tmp_path):
    """The flow leads by the bead's lag_s: a lag the approach cannot hold names the key
    the user set (process.bead.lag_s), not the flow's own lag_s (not given with a bead)."""
    text = SEAL.replace("lag_s: 0.08", "lag_s: 1.0", 1)
    # At rest: a flying seam's lead-in is sized to hold the lag, so only a seam that
    # starts standing has an approach too short for it.
    text = text.replace("  closed: true\n", "  closed: true\n  entry: rest\n", 1)
    code, err = plan(capsys, tmp_path, text)
    assert code == 2 and len(err) == 1, err
    assert ": process.bead.lag_s: " in err[0] and "approach" in err[0], err


def test_the_flows_own_lag_is_named_without_a_bead(capsys, tmp_path):
    io = "tool:\n  process_io:\n    flow: {analog_output: 1, per_mps: 40.0, lag_s: 1.0}\n"
    code, err = plan(capsys, tmp_path, with_own_io(SEAL, io))
    assert code == 2 and len(err) == 1 and ": tool.process_io.flow.lag_s: " in err[0], err


@pytest.mark.parametrize(
    ("written", "hint"),
    [("nan", "not a finite number"), ("1e400", "not a finite number"), ("1e3", "write 1.0e+03")],
)
def test_a_number_yaml_reads_as_text_gets_a_true_hint(capsys, tmp_path, written, hint):
    """YAML 1.2 reads nan, 1e400 and 1e3 as text: the line says what to write, and never
    suggests writing the same text again."""
    code, err = plan(capsys, tmp_path, SEAL.replace("area_mm2: 12.0", f"area_mm2: {written}", 1))
    assert code == 2 and len(err) == 1 and hint in err[0], err
    assert f"write {written})" not in err[0]
