"""The SVG views of report.html (``viz.report_plots.views_svg``): the gripper's outline
on the part and at the flange, and every seam of a job named on the part."""

import json
import re

import numpy as np
import pytest

from offline_prog.viz.job_report_html import REPORT_FILE


def test_the_views_draw_the_gripper(planned_folder):
    """report.json keeps the gripper's shapes in E; the page's four views draw each
    shape's outline (on the part in P, at the flange in I), and the outline of a shape
    lies on it."""
    from offline_prog.viz.outline import outline_in, shape_outline
    from offline_prog.viz.report_plots import GRIPPER_COLOR

    plan, folder = planned_folder("seal_plate_kr16")
    shapes = json.loads((folder / "report.json").read_text())["gripper"]
    assert [s["name"] for s in shapes] == [s.name for s in plan.cell.gripper.geometry]
    cup = next(s for s in shapes if s["name"] == "gripper_cup_1")
    assert cup["kind"] == "cylinder" and cup["size_m"] == pytest.approx([0.02, 0.03])
    np.testing.assert_allclose(np.array(cup["X_OG"])[:3, 3], [0.035, 0.04, 0.08])
    page = (folder / REPORT_FILE).read_text()
    lines = sum(len(shape_outline(s["kind"], s["size_m"])) for s in shapes)
    assert page.count(f'stroke="{GRIPPER_COLOR}"') == 4 * lines  # top and side, P and I
    # In P the cup's outline is on the plate's top face (z = 5 mm) and 20 mm around its axis.
    X_PE = plan.flange.X_PE.GetAsMatrix4()
    p_P = np.vstack(outline_in(X_PE, [cup]))
    p_PC = X_PE[:3, :3] @ [0.035, 0.04, 0.08] + X_PE[:3, 3]
    assert p_P[:, 2].min() == pytest.approx(0.005)
    assert np.linalg.norm(p_P[:, :2] - p_PC[:2], axis=1).max() == pytest.approx(0.02)


def test_a_jobs_views_draw_every_seam_on_the_part(planned_job):
    """A job of four seams: the part's two views name each seam (at its start), and
    the cell's views draw the flange path of the whole job."""
    job, folder = planned_job("seal_job_kr16")
    page = (folder / REPORT_FILE).read_text()
    views = re.findall(r"<svg class=\"view\".*?</svg>", page, re.S)
    assert len(views) == 4 and "Part P: seams' paths and frames F, top" in views[0]
    names = [o.name for o in job.chosen]
    for view in views[:2]:
        assert sorted(re.findall(r"<text x=\"[\d.]+\" y=\"[\d.]+\">(\w+)</text>", view)) == sorted(
            ["P", *names]
        )
    assert "Cell I: flange path, seams' paths at t=0, top" in views[2]
