"""A process speed at which the process model's output cannot hold the target is bad
input (issue 28): one line naming the speed's key, why, with the figures; exit 2 and
nothing written. The demo sealing job with a bead model whose flow keys the bead sets."""

import numpy as np
import pytest
from bead_job import bead_job
from config.test_cell_errors import BASE
from test_job_errors import run

from conftest import CELLS

JOB = (CELLS / "seal_job_kr16.yaml").read_text()
BEAD_JOB = bead_job()
# The one-seam cell of the cell-file tests, on a 200 mm line at SPEED.
PATH = (
    BASE.replace("name: test", "name: one_seam")
    .replace(
        "  points: path.csv\n  units: mm\n  closed: false\n",
        "  analytic: {kind: line, start: [-100, 0, 0], end: [100, 0, 0]}\n  units: mm\n",
    )
    .replace("speed: 0.1", "speed: SPEED")
)
assert "analytic" in PATH and "SPEED" in PATH
TAPE = """\
process:
  model: tape_heating
  tape_heating:
    width_mm: 25.0
    thickness_mm: 0.2
    density_kg_m3: 1550
    specific_heat_j_kg_k: 1200
    absorbed_fraction: 0.6
    ambient_c: 20
    target_c: [380, 420]
    max_power_w: 3000
    power_output: {analog_output: 2, w_per_unit: 300}
"""
WELD = """\
process:
  model: heat_input
  heat_input: {voltage_v: 24.0, current_a: 180.0, efficiency: 0.8, target_kj_mm: [0.5, 0.7]}
"""


@pytest.mark.parametrize(
    "text, key, reason",
    [
        (  # the flow at its max 10 lays 12 mm² up to 250 · 10 / 12 mm/s
            BEAD_JOB.replace("speed: 0.1 ", "speed: 0.3 "),
            "motion.speed",
            "0.3 m/s is above the 0.2083 m/s at which the flow output at its max 10 "
            "(tool.process_io.flow.max; 250 mm³/s per unit) lays process.bead.area_mm2 12 mm²",
        ),
        (  # the stripe's own speed
            BEAD_JOB.replace("speed: 0.15", "speed: 0.25"),
            "seams[3].speed",
            "0.25 m/s is above the 0.2083 m/s",
        ),
        (  # a flow that cannot go below 5 lays more than 12 mm² under 250 · 5 / 12 mm/s
            BEAD_JOB.replace("min: 0.0, max: 10.0", "min: 5.0, max: 10.0"),
            "motion.speed",
            "0.1 m/s is below the 0.1042 m/s at which the flow output at its min 5 "
            "(tool.process_io.flow.min) lays process.bead.area_mm2 12 mm²: the bead is too large",
        ),
        (  # η·P_max / (ρ c w h (T_low − T_0)) = 0.6 · 3000 / (9.3 · 360) m/s
            PATH.replace("SPEED", "0.6") + TAPE,
            "motion.speed",
            "0.6 m/s is above the 0.5376 m/s at which the heater "
            "(process.tape_heating.max_power_w 3000 W) reaches target_c's low end 380 °C",
        ),
        (  # k·U·I / H_low = 3456 W / 0.5 kJ/mm
            PATH.replace("SPEED", "0.01") + WELD,
            "motion.speed",
            "0.01 m/s is above the 0.006912 m/s at which the heat input",
        ),
        (  # k·U·I / H_high = 3456 W / 0.7 kJ/mm
            PATH.replace("SPEED", "0.004") + WELD,
            "motion.speed",
            "0.004 m/s is below the 0.004937 m/s under which the heat input k·U·I/v = "
            "3456 W / v exceeds process.heat_input.target_kj_mm's high end 0.7 kJ/mm",
        ),
    ],
)
def test_speed_outside_the_band_is_one_line_exit_2(tmp_path, capsys, text, key, reason):
    code, stderr, out = run(tmp_path, text, capsys)
    lines = stderr.strip().splitlines()
    assert code == 2, stderr
    assert len(lines) == 1 and "Traceback" not in stderr
    assert f": {key}: " in lines[0] and reason in lines[0], lines[0]
    assert not out.exists()


def test_weld_ramps_below_the_band_are_named(tmp_path):
    """A weld at 6 mm/s (band 4.94–6.91 mm/s): the time law cannot hold a minimum speed
    on the ramps from and to rest; report.json's quality.timing_bound names both
    stretches, where they are and why, and no bound was applied (no output dynamics)."""
    from offline_prog.plan import plan_job
    from offline_prog.results.timing_bound import timing_bound_report

    cell = tmp_path / "weld.yaml"
    # At rest: a flying seam (the default) has no ramp on it (they are on its leads).
    rest = PATH.replace("  units: mm\n", "  units: mm\n  entry: rest\n", 1)
    cell.write_text(rest.replace("SPEED", "0.006") + WELD)
    job = plan_job(cell)
    report = timing_bound_report(job)
    assert not report["applied"] and report["difference_s"] == 0.0
    low, high = report["speed_band_m_s"]
    assert abs(low - 3456 / 0.7e6) < 1e-12 and abs(high - 3456 / 0.5e6) < 1e-12
    stretches = report["below_speed_band"]
    assert [s["cause"] for s in stretches] == ["start ramp", "stop ramp"]
    start, stop = stretches
    process = next(g for g in job.samples.segments if g.kind == "process")
    assert start["sigma_start_m"] == 0.0 and abs(start["t_start_s"] - process.t_start) < 1e-9
    assert abs(stop["sigma_end_m"] - 0.2) < 1e-6 and start["speed_min_m_s"] < low
    for s in stretches:  # the speed is below the band inside each stretch, above outside
        rows = (job.samples.t >= s["t_start_s"]) & (job.samples.t <= s["t_end_s"])
        assert np.all(job.tcp_speed[rows] < low)
    middle = (job.samples.t > start["t_end_s"]) & (job.samples.t < stop["t_start_s"])
    assert np.all(job.tcp_speed[middle] >= low)


def test_joint_slowdowns_below_the_band_are_named_with_their_joint(tmp_path):
    """The plate demo with its nozzle's turn fixed (the wrist's jerk slows the corners
    to about 52 mm/s) and a heat input whose band needs 90–120 mm/s: the corners are
    below the band, and the report names each with the joint and limit behind it."""
    import re

    from offline_prog.plan import plan_job
    from offline_prog.results.timing_bound import timing_bound_report

    text = re.sub(r"\n  turn_smoothing_mm: .*", "", (CELLS / "seal_plate_kr16.yaml").read_text())
    text = re.sub(r"(?ms)^process:.*?(?=^\S)", "", text)  # the demo's own model, if any
    text = re.sub(r"(?m)^  process_io:\n(    .*\n)*", "", text)  # and its outputs
    cell = tmp_path / "weld_fast.yaml"
    cell.write_text(text + WELD.replace("[0.5, 0.7]", "[0.0288, 0.0384]"))
    job = plan_job(cell)
    report = timing_bound_report(job)
    plan = job.chosen[0].plan
    assert plan.entry["entry"] == "flying"  # the default: its ramps are on its leads
    slowdowns = [s for s in plan.joints.retiming.slowdowns if s.joint is not None]
    corners = [s for s in report["below_speed_band"] if s["cause"].startswith("slowdown")]
    assert len(corners) == len(slowdowns) == len(report["below_speed_band"]) == 4
    origin = plan.law_origin[0]  # the law's σ counts from the lead-in's start
    for corner, slow in zip(corners, slowdowns, strict=True):
        assert corner["cause"].startswith(f"slowdown: joint {slow.joint} {slow.constraint}")
        assert slow.sigma_m[0] + origin <= corner["sigma_start_m"] <= corner["sigma_end_m"]
        assert corner["sigma_end_m"] <= slow.sigma_m[1] + origin
        assert abs(corner["speed_min_m_s"] - slow.speed_min_m_s) < 1e-6
    low = report["speed_band_m_s"][0]
    assert all(s["speed_min_m_s"] < low for s in report["below_speed_band"])
