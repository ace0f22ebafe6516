"""Bad job input ends with one line naming the file, key and reason, exit 2, and
nothing written (the issue's list: duplicate seam names, home outside the limits or in
collision, a negative approach distance, I/O that cannot be placed)."""

import pytest

from offline_prog.cli import main

from conftest import CELLS

JOB = (CELLS / "seal_job_kr16.yaml").read_text()


def run(tmp_path, text, capsys):
    """The CLI in this process (test_cli.py runs it as a subprocess)."""
    cell = tmp_path / "job.yaml"
    cell.write_text(text)
    out = tmp_path / "out"
    code = main(["plan", str(cell), "--out", str(out)])
    return code, capsys.readouterr().err, out


@pytest.mark.parametrize(
    "change, key, reason",
    [
        (("name: hole_right", "name: hole_left"), "seams[2].name", "used twice"),
        (("name: stripe", "name: Hole_Left"), "seams[3].name", "used twice"),
        (("name: stripe", "name: 'stripe; $OUT[2]=TRUE'"), "seams[3].name", "not a seam name"),
        (
            (
                "approach: {kind: normal, distance_mm: 50}",
                "approach: {kind: normal, distance_mm: -5}",
            ),
            "seams[0].approach.distance_mm",
            "must be within",
        ),
        (
            ("direction: auto\n    speed", "direction: sideways\n    speed"),
            "seams[3].direction",
            "sideways",
        ),
        (("order: auto", "order: fastest"), "job.order", "fastest"),
        (
            ("order: auto", "order: auto\n  home: {joints_deg: [0, -90, 90, 0, 30, 400]}"),
            "job.home.joints_deg",
            "outside its limits",
        ),
        (
            ("order: auto", "order: auto\n  home: {joints_deg: [0, 20, 130, 0, 30, 0]}"),
            "job.home.joints_deg",
            "collides",
        ),
        (
            ("on:  {digital_output: 1, lead_mm: 5}", "on:  {digital_output: 1, lead_mm: 80}"),
            "tool.process_io.on.lead_mm",
            "80 mm before the start of seam border is beyond its approach (50 mm)",
        ),
        (("seams:", "path: {units: mm, points: a.csv}\nseams:"), "seams", "exactly one of"),
        (  # longer than a hole: off before on, refused before planning
            ("off: {digital_output: 1, lead_mm: 2}", "off: {digital_output: 1, lead_mm: 400}"),
            "tool.process_io",
            "the output must go on before it goes off",
        ),
        (
            ("digital_output: 1,", "digital_output: 5000,"),  # on and off
            "tool.process_io.on.digital_output",
            "not an output of the robot's krl controller (use 1..4096)",
        ),
        (
            ("digital_output: 1, lead_mm: 2}", "digital_output: 2, lead_mm: 2}"),
            "tool.process_io.off.digital_output",
            "must equal on's",
        ),
        (
            ("flow: {analog_output: 1,", "flow: {analog_output: 40,"),
            "tool.process_io.flow.analog_output",
            "use 1..32",
        ),
        (("order: auto", "order: auto\n  link_time_s: 0"), "job.link_time_s", "must be within"),
        (("motion:\n", "motion:\n  lead_mm: -5\n"), "motion.lead_mm", "must be within [0, 500]"),
        (
            ("direction: auto\n    speed", "direction: auto\n    entry: glide\n    speed"),
            "seams[3].entry",
            "'glide' is not an entry (use rest or flying)",
        ),
    ],
)
def test_bad_job_input_is_one_line_exit_2_nothing_written(tmp_path, capsys, change, key, reason):
    old, new = change
    assert old in JOB
    code, stderr, out = run(tmp_path, JOB.replace(old, new), capsys)
    lines = stderr.strip().splitlines()
    assert code == 2, stderr
    assert len(lines) == 1 and "Traceback" not in stderr
    assert f": {key}: " in lines[0] and reason in lines[0], lines[0]
    assert not out.exists()
