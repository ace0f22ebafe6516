"""The demo sealing job (cells/seal_job_kr16.yaml) with a bead model: 12 mm² ± 5 %,
250 mm³/s per unit of the flow output, a dispenser lag of 0.08 s. The bead sets the
flow's gain, offset and lead, so the flow output keeps only its number and limits; a
process model the demo may already have is replaced by this one."""

import re

from conftest import CELLS

BEAD = (
    "process:\n  model: bead\n  bead: {area_mm2: 12.0, tolerance_pct: 5, "
    "flow_mm3_s_per_unit: 250.0, lag_s: 0.08}\n"
)


def bead_job() -> str:
    """The cell's text."""
    text = (CELLS / "seal_job_kr16.yaml").read_text()
    text = re.sub(r"(?ms)^process:.*?(?=^\S|\Z)", "", text)
    text, n = re.subn(
        r"(?m)^    flow: \{.*\}$", "    flow: {analog_output: 1, min: 0.0, max: 10.0}", text
    )
    assert n == 1, "the demo's flow output"
    return text + BEAD
