"""report.html: the summary table shows report.json's numbers, the page is
self-contained and escaped, and in a real browser it renders non-empty plots."""

import json
import re
import shutil
from html.parser import HTMLParser

import matplotlib.image
import numpy as np
import pytest

from offline_prog.atomic import write_atomic
from offline_prog.plan import plan_cell
from offline_prog.results import plan_folder as outputs
from offline_prog.results.program_data import seam_program_data
from offline_prog.results.report import report
from offline_prog.viz.report_html import REPORT_FILE, render_report_html, write_report_html
from offline_prog.viz.report_summary import lookup

from browser import keep_artifact, layout, require_chromium, screenshot
from conftest import CELLS, ONE_SEAM_CELLS

DEMO_CELLS = ONE_SEAM_CELLS  # whole jobs (seams:) have their own tests in tests/job
# What the brief asks the table to show, as report.json keys.
REQUIRED_KEYS = [
    "name",
    "robot",
    "tool",
    "part",
    "path.length_m",
    "fit.max_error_mm",
    "fit.rms_error_mm",
    "trajectory.duration_s",
    "trajectory.tcp_speed_max_error_rel",
    "cusps",
    "robot_motion.min_joint_limit_margin_deg",
    "robot_motion.largest_joint_step.step_deg",
    "robot_motion.speed_reductions",
]
# (key suffix, unit on the page) -> factor from report.json's unit to the page's.
SCALES = {("_m", "mm"): 1e3, ("_rel", "%"): 100.0, ("_use", "%"): 100.0}
NUMBER = re.compile(r"^[−-]?\d[\d,]*(?:\.(\d+))?(?:e([+-]?\d+))?")


def n_plots(plan_dir):
    """Charts the page must draw: pose, speed, joints, joint rates, and the distance
    chart when clearance.csv exists (the SVG views come on top)."""
    return 4 + (plan_dir / "clearance.csv").is_file()


def plot_data(page):
    """The page's plot JSON (columns and chart specs)."""
    match = re.search(r'<script type="application/json" id="plot-data">(.*?)</script>', page)
    assert match, "no plot data in the page"
    return json.loads(match.group(1))


def make_plan_folder(cell_file, out):
    """A plan folder as `offline-prog plan` writes it (report, CSV, plan.npz), plus
    one stand-in program file: the exporters are tested on their own."""
    plan = plan_cell(cell_file)
    summary = report(plan)
    write_atomic(out / "trajectory.csv", outputs.trajectory_csv(plan))
    write_atomic(out / "report.json", json.dumps(summary, indent=2) + "\n")
    seam_program_data(plan, summary).save(out)
    write_atomic(out / "programs" / "stand_in.src", "; program\n")
    return out


@pytest.fixture(scope="module", params=DEMO_CELLS, ids=lambda p: p.stem)
def plan_dir(request, tmp_path_factory):
    return make_plan_folder(request.param, tmp_path_factory.mktemp(request.param.stem))


@pytest.fixture(scope="module")
def tape_dir(tmp_path_factory):
    return make_plan_folder(CELLS / "tape_cylinder_ur10e.yaml", tmp_path_factory.mktemp("tape"))


class SummaryTable(HTMLParser):
    """The data-key spans of table#summary, and its text outside them, headers,
    joint labels, file names and verdict reasons (where digits are not numbers)."""

    SKIP = ("num", "lbl", "files", "reason")

    def __init__(self, page):
        super().__init__()
        self.spans, self.rest, self.stack = [], [], []
        self.inside = self.capture = False
        self.feed(page)

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        self.inside |= tag == "table" and attrs.get("id") == "summary"
        classes = (attrs.get("class") or "").split()
        self.stack.append((tag, tag == "th" or any(c in classes for c in self.SKIP)))
        self.capture = self.inside and "data-key" in attrs
        if self.capture:
            self.spans.append([attrs["data-key"], attrs["data-value"], ""])

    def handle_endtag(self, tag):
        self.inside &= tag != "table"
        self.capture = False
        while self.stack and self.stack.pop()[0] != tag:
            pass

    def handle_data(self, data):
        if self.capture:
            self.spans[-1][2] += data
        elif self.inside and not any(skip for _, skip in self.stack):
            self.rest.append(data)


def shown_matches(key, value, text):
    """The number a person reads in ``text`` equals ``value`` to the digits shown."""
    match = NUMBER.match(text)
    assert match, f"{key}: no number in {text!r}"
    unit = text[match.end() :].strip()
    stem = re.sub(r"(\.\d+)+$", "", key)
    scale = next((f for (s, u), f in SCALES.items() if stem.endswith(s) and unit == u), 1.0)
    shown = float(match.group(0).replace(",", "").replace("−", "-"))
    decimals = len(match.group(1) or "")
    exponent = int(match.group(2) or 0)
    return abs(shown - value * scale) <= 0.5 * 10.0 ** (exponent - decimals) * (1 + 1e-9)


def test_summary_numbers_equal_report_json(plan_dir):
    report = json.loads((plan_dir / "report.json").read_text())
    table = SummaryTable(render_report_html(plan_dir))
    keys = {key for key, _, _ in table.spans}
    assert set(REQUIRED_KEYS) <= keys, set(REQUIRED_KEYS) - keys
    for key, raw, text in table.spans:
        value = lookup(report, key)
        value = len(value) if isinstance(value, list) else value
        assert json.loads(raw) == value, key
        if isinstance(value, str):
            assert text == value, key
        else:
            assert shown_matches(key, value, text), f"{key}: {text!r} shows {value!r}"
    n_joints = len(report["robot_motion"]["joint_limit_margin_deg"])
    assert {f"robot_motion.joint_limit_margin_deg.{j}" for j in range(n_joints)} <= keys
    stray = re.findall(r"[0-9]", "".join(table.rest))
    assert not stray, f"numbers in the table that are not report.json's: {table.rest}"


COLLISION_KEYS = ("collision", "collision_free", "min_distance_m", "closest_pair", "clearance_m")


def test_programs_listed_and_distance_not_checked(tape_dir, tmp_path):
    folder = tmp_path / "plan"
    shutil.copytree(tape_dir, folder)
    report = json.loads((folder / "report.json").read_text())
    unchecked = {k: v for k, v in report.items() if k not in COLLISION_KEYS}
    (folder / "report.json").write_text(json.dumps(unchecked))
    page = render_report_html(folder)
    assert "programs/stand_in.src" in page
    assert re.search(r"<th>Minimum distance</th><td>not checked</td>", page)
    assert "PASS" in page and "collisions and clearances were not checked" in page


def test_self_contained_and_deterministic(plan_dir):
    file = write_report_html(plan_dir)
    assert file == plan_dir / REPORT_FILE
    page = file.read_text()
    # Nothing loaded from elsewhere: no src/href attributes, no url(), no script src.
    assert not re.search(r"<[^>]+\s(?:src|href)\s*=|url\(|<script[^>]+src", page)
    data = plot_data(page)
    assert len(data["plots"]) == n_plots(plan_dir)
    assert len(re.findall(r'<div class="plot" id=', page)) == n_plots(plan_dir)
    table = np.loadtxt(plan_dir / "trajectory.csv", delimiter=",", skiprows=1)
    n = len(table)
    for plot in data["plots"]:
        for panel in plot["panels"]:
            x = data["columns"][panel.get("x", "t")]
            for series in panel["series"]:
                assert "col" in series or "const" in series
                if "col" in series:
                    assert len(data["columns"][series["col"]]) == len(x)
    # Every sample is plotted (zoomable), at the page's units: x in mm, joint 1 in °.
    assert len(data["columns"]["t"]) == n
    np.testing.assert_allclose(data["columns"]["x_mm"], table[:, 2] * 1e3, rtol=1e-5, atol=1e-3)
    q1 = np.rad2deg(table[:, 21])
    np.testing.assert_allclose(data["columns"]["q1_deg"], q1, rtol=1e-5, atol=1e-3)
    assert render_report_html(plan_dir) == page


# The collision check as outputs.collision_summary puts it at report.json's top level,
# and as a nested record shaped like collision.CollisionResult.
COLLISION_TOP = {
    "collision_free": False,
    "min_distance_m": 0.0123,
    "closest_pair": {"pair": ["link_6", "<fixture>"], "t_s": 1.25, "sigma_m": 0.2},
    "clearance_m": 0.015,
}
COLLISION_NESTED = {
    "collision": {
        "clearance_m": 0.015,
        "collision_free": False,
        "min_distance_m": 0.0123,
        "closest": {"a": "link_6", "b": "<fixture>", "t_s": 1.25, "sigma_m": 0.2},
        "message": "clearance: link_6 vs <fixture> at t = 1.250 s",
    }
}


@pytest.mark.parametrize("collision", [COLLISION_TOP, COLLISION_NESTED], ids=["top", "nested"])
def test_escaped_failed_plan_with_distance(tape_dir, tmp_path, collision):
    folder = tmp_path / "plan"
    shutil.copytree(tape_dir, folder)
    report = json.loads((folder / "report.json").read_text())
    report["name"] = '<script>alert("x")</script>'
    report["tool"] = "nozzle & <b>"
    report["fit"]["max_error_mm"] = 0.25
    report.update(collision)
    (folder / "report.json").write_text(json.dumps(report))
    t = np.loadtxt(folder / "trajectory.csv", delimiter=",", skiprows=1)[:, 0]
    distance = 0.05 + 0.02 * np.cos(t)
    np.savetxt(
        folder / "clearance.csv",
        np.column_stack([t, distance, distance + 0.1]),
        delimiter=",",
        header="t_s,part-obstacle_m,robot-self_m",
        comments="",
        fmt="%.10g",
    )
    page = render_report_html(folder)
    assert "<script>alert" not in page and "&lt;script&gt;" in page
    assert "nozzle &amp; &lt;b&gt;" in page
    assert '<span class="fail">FAIL</span>' in page and "fit error 0.2500 mm above" in page
    assert "vs &lt;fixture&gt; at t = 1.250 s" in page or "below the clearance 15.00 mm" in page
    assert len(plot_data(page)["plots"]) == n_plots(folder) == 5  # the distance plot joins
    spans = {key: (raw, text) for key, raw, text in SummaryTable(page).spans}
    prefix = "collision." if "collision" in collision else ""
    assert spans[f"{prefix}min_distance_m"] == ("0.0123", "12.30 mm")
    assert spans[f"{prefix}clearance_m"] == ("0.015", "15.00 mm")
    assert ('"<fixture>"', "<fixture>") in spans.values()
    assert any(key.endswith(".t_s") and text == "1.250 s" for key, (_, text) in spans.items())


def test_missing_files_name_the_file(tmp_path):
    with pytest.raises(ValueError, match="report.json"):
        render_report_html(tmp_path)


@pytest.mark.slow
def test_browser_shows_the_plots(plan_dir, tmp_path_factory):
    require_chromium()
    file = write_report_html(plan_dir)
    png = screenshot(file, tmp_path_factory.mktemp("screens") / f"{plan_dir.name}.png")
    keep_artifact(png, f"report_{plan_dir.name}.png")
    print(f"screenshot: {png}")
    boxes = layout(file)
    shot = matplotlib.image.imread(png)[..., :3]
    assert boxes["height"] <= shot.shape[0], "the window is too short for the page"
    page = shot[: int(boxes["height"])]
    assert (page.std(axis=2) + np.abs(page.mean(axis=2) - 1)).mean() > 0.01, "blank page"
    assert len(boxes["plots"]) == n_plots(plan_dir) and boxes["tables"][0]["h"] > 400
    panels = {"pose": 6, "speed": 1, "joints": 6, "rates": 6, "distance": 1}
    for plot in boxes["plots"]:
        assert plot["panels"] == panels[plot["id"]], plot
        x, y, w, h = (int(round(plot[k])) for k in "xywh")
        assert w > 900 and h > 200, plot["id"]
        region = shot[y : y + h, x : x + w]
        ink = (region.min(axis=2) < 0.6).mean()  # lines, text and axes drawn
        colour = (region.max(axis=2) - region.min(axis=2) > 0.3).mean()  # coloured lines
        assert 0.005 < ink < 0.6 and colour > 0.001, (plot["id"], ink, colour)
    assert len(boxes["svgs"]) == 4 and all(s["w"] > 300 for s in boxes["svgs"])


@pytest.mark.slow  # a time-optimal plan of the seal demo and a browser screenshot
def test_speed_plot_shades_each_time_optimal_slowdown_with_its_joint(tmp_path):
    cell = tmp_path / "seal_time_optimal.yaml"
    # The nozzle's turn fixed (no tool.turn_smoothing_mm): the wrist's jerk binds.
    text = re.sub(r"\n  turn_smoothing_mm: .*", "", (CELLS / "seal_plate_kr16.yaml").read_text())
    cell.write_text(
        text.replace(
            "  speed_reference: tcp\n", "  speed_reference: tcp\n  time_law: time_optimal\n"
        )
    )
    plan_dir = make_plan_folder(cell, tmp_path / "plan")
    slowdowns = json.loads((plan_dir / "report.json").read_text())["robot_motion"]["slowdowns"]
    assert any(s["joint"] is not None for s in slowdowns), slowdowns  # the corners
    file = write_report_html(plan_dir)
    specs = {spec["id"]: spec for spec in plot_data(file.read_text())["plots"]}
    bands = specs["speed"]["panels"][0]["bands"]
    assert [(b["t0"], b["t1"]) for b in bands] == [
        (s["t_start_s"], s["t_end_s"]) for s in slowdowns
    ]
    assert [b["label"] for b in bands] == [
        (f"J{s['joint']} " if s["joint"] is not None else "") + s["constraint"] for s in slowdowns
    ]
    require_chromium()
    png = screenshot(file, tmp_path / "speed.png")
    keep_artifact(png, "report_speed_bands.png")
    boxes = layout(file)
    speed = next(p for p in boxes["plots"] if p["id"] == "speed")
    assert speed["panels"] == 1
    shot = matplotlib.image.imread(png)[..., :3]
    x, y, w, h = (int(round(speed[k])) for k in "xywh")
    region = shot[y : y + h, x : x + w]
    # The band's tint over white: rgba(255, 160, 0, 0.15) → (1.0, 0.944, 0.85).
    tint = (np.abs(region - [1.0, 0.944, 0.85]).max(axis=2) < 0.03).mean()
    assert tint > 0.01, tint


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
