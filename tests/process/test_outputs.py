"""The process quality in the plan folder: trajectory.csv's column (named after the
model, in its unit, empty where the gun is closed: on links and where the output is off
on the approach and retract), report.json's ``quality`` and report.html's
plot with the band shaded, all saying the same as the plan."""

import csv
import json
import re

import numpy as np
import pytest

from browser import layout

DEMOS = {  # demo cell ↦ (model, column)
    "seal_plate_kr16": ("bead", "bead_area_mm2"),
    "tape_cylinder_ur10e": ("tape_heating", "nip_temp_c"),
    "weld_seam_irb2400": ("heat_input", "heat_input_kj_mm"),
}


@pytest.mark.parametrize("name", DEMOS)
def test_the_column_and_the_report_say_the_same(planned_job, name):
    job, folder = planned_job(name)
    model, column = DEMOS[name]
    report = json.loads((folder / "report.json").read_text())["quality"]
    assert (report["model"], report["column"]) == (model, column)
    with open(folder / "trajectory.csv") as stream:
        rows = list(csv.DictReader(stream))
    values = np.array([float(r[column]) if r[column] else np.nan for r in rows])
    on_process = np.array([r["segment"].startswith("process:") for r in rows])
    on_seam = np.array([r["segment"] != "link" for r in rows])  # approach, seam, retract
    assert np.all(np.isnan(values[~on_seam]))  # only where the gun can be open
    assert np.isfinite(values[on_process]).mean() > 0.99
    assert np.nanmin(values) == pytest.approx(report["min"], rel=1e-9)
    assert np.nanmax(values) == pytest.approx(report["max"], rel=1e-9)
    np.testing.assert_allclose(values, job.quality.column, rtol=1e-9)  # CSV: 10 digits
    # Each stretch outside lies on a seam's moves, and its worst value is outside.
    low, high = report["band"]
    t = np.array([float(r["t"]) for r in rows])
    for stretch in report["stretches_outside"]:
        inside = (t >= stretch["t_start_s"]) & (t <= stretch["t_end_s"])
        assert on_seam[inside].all()
        assert stretch["worst"] is None or not low <= stretch["worst"] <= high
    assert report["seams"]["seam"]["share_within_band"] == report["share_within_band"]
    assert 0.95 < report["share_within_band"] <= 1.0  # the demos' process models fit them


def test_report_page_plots_the_quality_with_its_band(planned_job):
    _, folder = planned_job("seal_plate_kr16")
    report = json.loads((folder / "report.json").read_text())["quality"]
    page = (folder / "report.html").read_text()
    data = json.loads(re.search(r'id="plot-data">(.*?)</script>', page)[1])
    (plot,) = [p for p in data["plots"] if p["id"] == "plot-quality"]
    (panel,) = plot["panels"]
    assert panel["series"][0]["col"] == "bead_area_mm2"
    (band,) = panel["ybands"]
    assert [band["y0"], band["y1"]] == report["band"]
    low, high = panel["yrange"]
    assert low < report["band"][0] and high > report["band"][1]
    assert f"{100 * report['share_within_band']:.1f} %" in page
    assert f"{100 * report['share_within_band_uncompensated']:.1f} %" in page
    causes = re.findall(
        r"<td>(standstill|output saturated|approach|retract|start ramp|end ramp|lag|slowdown"
        r"|process speed)</td></tr>",
        page,
    )
    assert causes == [s["cause"] for s in report["stretches_outside"]]
    boxes = layout(folder / "report.html")
    panels = {p["id"]: p["panels"] for p in boxes["plots"]}
    assert panels["plot-quality"] == 1  # drawn in Chromium
