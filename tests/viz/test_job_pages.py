"""The job's pages: report.html shows the order, every seam, link and I/O switch of
report.json and draws its plots in Chromium; preview.html carries the whole job's motion
with one highlight per seam, shown only while that seam runs."""

import json
import re

import numpy as np
import pytest

from browser import layout

JOB = "seal_job_kr16"


@pytest.fixture(scope="module")
def folder(planned_job):
    return planned_job(JOB)[1]


def test_report_page_lists_what_report_json_says(folder):
    report = json.loads((folder / "report.json").read_text())
    page = (folder / "report.html").read_text()
    for seam in report["seams"]:
        assert f"<td>{seam['seam']}</td><td>{seam['path']['length_m'] * 1e3:.1f}</td>" in page
    for link in report["links"]:
        name = link["name"].replace(">", "&gt;")
        assert f"<td>{name}</td><td>{link['method']}</td>" in page
    switches = re.findall(r"<td>(on|off)</td><td>(-?[\d.]+)</td>", page)
    expected = [(e["state"], f"{e['path_m'] * 1e3:.2f}") for e in report["process_io"]]
    assert switches == expected
    assert f"{report['job']['cycle_time_s']:.2f} s: process" in page


def test_report_page_draws_its_plots(folder):
    boxes = layout(folder / "report.html")
    panels = {plot["id"]: plot["panels"] for plot in boxes["plots"]}
    assert panels == {"plot-speed": 2, "plot-joints": 1}  # speed + I/O timeline, joints


def test_preview_highlights_each_seam_only_while_it_runs(folder, planned_job):
    job = planned_job(JOB)[0]
    page = (folder / "preview.html").read_text()
    commands = [json.loads(m) for m in re.findall(r"viewer\.handle_command\((\{.*?\})\);", page)]
    animation = next(c for c in commands if c["type"] == "set_animation")
    scale_tracks = {
        a["path"].rsplit("/", 1)[-1]: a["clip"]["tracks"][0]["keys"]
        for a in animation["animations"]
        if "/active/" in a["path"]
    }
    assert set(scale_tracks) == {o.name for o in job.chosen}
    fps = animation["animations"][0]["clip"]["fps"]
    for segment in job.samples.segments:
        if segment.kind != "process":
            continue
        keys = scale_tracks[segment.seam]
        shown = [k["time"] / fps for k in keys if k["value"][0] == 1.0]
        assert min(shown) == pytest.approx(segment.t_start, abs=1.0 / fps)
        assert max(shown) == pytest.approx(segment.t_stop, abs=2.0 / fps)
        assert np.all(np.diff([k["time"] for k in keys]) > 0)


def test_live_preview_draws_every_seam_and_records_the_whole_job(planned_job):
    from pydrake.geometry import Meshcat, MeshcatParams

    from offline_prog.viz.job_preview import show_job

    job = planned_job(JOB)[0]
    params = MeshcatParams()
    params.port = 0  # any free port
    meshcat = Meshcat(params)
    info = show_job(job, meshcat)
    fps = info["frames_per_second"]
    assert info["frames"] == int(np.floor(job.samples.t[-1] * fps + 1e-9)) + 1
    part = "/drake/visualizer/part/part"
    for option in job.chosen:
        assert meshcat.HasPath(f"{part}/seams/{option.name}")
        assert meshcat.HasPath(f"{part}/active/{option.name}")
