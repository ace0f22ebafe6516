"""One gross outlier (a mistyped angle, the pointer beside the tip) is found, named by
its line and left out, and the estimate stays within the acceptance tolerances; two
are refused in one line naming both; clean touches have none."""

import numpy as np
import pytest
from synthetic_touches import calibration_cell, nominal_truth, start_pose, synthetic_touches
from test_estimate import GRASP_DEG, GRASP_MM, POINTER_MM, TIP_MM, errors

from offline_prog.calibration.outliers import robust_fit
from offline_prog.calibration.run import touch_problem
from offline_prog.calibration.touches import parse_touches
from offline_prog.errors import InputError


@pytest.fixture(scope="module")
def seal(tmp_path_factory):
    inputs, X_IE0 = start_pose(calibration_cell(tmp_path_factory.mktemp("c"), "seal_plate_kr16"))
    rng = np.random.default_rng(5)
    true = nominal_truth(inputs, rng)
    return inputs, true, synthetic_touches(inputs, X_IE0, true, rng).text


def with_error(text: str, line: int, joint: int, deg: float) -> str:
    """The touches with ``deg`` added to joint ``joint`` (1-based) of file line ``line``."""
    lines = text.splitlines()
    fields = lines[line - 1].split(",")
    fields[joint] = f"{float(fields[joint]) + deg:.8f}"
    lines[line - 1] = ",".join(fields)
    return "\n".join(lines) + "\n"


def fitted(inputs, text: str):
    touches = parse_touches("t.csv", text, inputs.robot, inputs.cell.calibration)
    return robust_fit(touch_problem(inputs, touches))


def test_clean_touches_have_no_outlier(seal):
    inputs, _, text = seal
    assert fitted(inputs, text)[1] is None


@pytest.mark.parametrize(("line", "target"), [(4, "tool_tip"), (11, "tool_axis"), (17, "corner_b")])
def test_one_gross_outlier_is_named_and_left_out(seal, line, target):
    inputs, true, text = seal
    assert text.splitlines()[line - 1].startswith(target + ",")
    estimate, outlier = fitted(inputs, with_error(text, line, 1, 0.2))  # A1 0.2° off: mm
    assert outlier is not None and (outlier.line, outlier.target) == (line, target)
    assert outlier.distance_mm > 1.0 and outlier.sigmas > 20
    assert line not in estimate.problem.touches.lines
    e = errors(estimate, true)
    assert e["tip_mm"] < TIP_MM and e["pointer_mm"] < POINTER_MM, e
    assert e["grasp_mm"] < GRASP_MM and e["grasp_deg"] < GRASP_DEG, e


def test_two_gross_outliers_are_refused_naming_both(seal):
    inputs, _, text = seal
    bad = with_error(with_error(text, 4, 1, 0.2), 17, 2, -0.3)
    with pytest.raises(InputError) as error:
        fitted(inputs, bad)
    message = str(error.value)
    assert "more than one touch is off the others" in message
    assert "line 4 (tool_tip)" in message and "line 17 (corner_b)" in message
