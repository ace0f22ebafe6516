"""placement.html, read as a user reads it: the top view to scale with its axes in mm,
the robot base and its reach, the stand, the colour scale; the best distinct
candidates; yes and no, not True and False."""

import dataclasses
import re

import numpy as np

from offline_prog.placement.objective import CANNOT_FOLLOW, FEASIBLE, Evaluation
from offline_prog.placement.outputs import _top, terms
from offline_prog.placement.search import Placement
from offline_prog.placement.search_map import render_placement_html
from offline_prog.placement.space import Candidate
from offline_prog.placement.top_view import Layout

GRASP = ((0.0, 0.0, 0.1), (180.0, 0.0, 0.0))


def _evaluation(x_mm, y_mm, cycle, stage="plan", yaw=0.0, **more):
    candidate = Candidate((), 0, ((x_mm / 1e3, y_mm / 1e3, 0.7), (90.0, 0.0, yaw)), GRASP)
    values = dict(cycle_time_s=cycle, joint_limit_margin_deg=20.0, bound_s=cycle - 1.5)
    return Evaluation(candidate, stage, FEASIBLE, 0.0, "", **{**values, **more})


def _result():
    planned = [_evaluation(1000 + 10 * k, 0.0, 16.64 + 0.001 * k) for k in range(12)]
    planned += [_evaluation(1300, 200, 17.5), _evaluation(900, -300, 18.2)]
    base = dataclasses.replace(
        _evaluation(2200, 400, np.nan),
        tier=CANNOT_FOLLOW,
        violation=1.0,
        reason="out of reach",
        failure="out_of_reach",
    )
    screened = [
        _evaluation(700 + 300 * i, -400 + 200 * j, 17.0, "screen")
        for i in range(5)
        for j in range(5)
    ]
    fates = ["reach" if i % 3 == 0 else "rank" for i in range(25)]
    best = min(planned, key=Evaluation.key)
    return Placement(best, base, [base, *planned], screened, fates, 1.0)


def test_the_page_reads_as_a_report():
    result = _result()
    top = _top(result.evaluated, 10)
    data = {
        "best": terms(result.best),
        "cycle_time_cut": {"percent": None, "why_not_more": ""},
        "candidates": [terms(e) for e in top],
        "screening": {"fates": {"reach": 9, "rank": 16}},
        "engine": {"candidates_evaluated": 15, "screened": 25, "wall_time_s": 1.0}
        | {"workers": 2, "scheduler": "LocalCluster"},
    }
    stand = np.array([[900.0, -100.0], [1100.0, -100.0], [1100.0, 100.0], [900.0, 100.0]])
    page = render_placement_html(result, data, None, Layout((0.0, 0.0), 1610.0, [("stand", stand)]))
    svg = re.search(r'<svg id="search-map".*?</svg>', page, re.S).group(0)
    ticks = [int(t) for t in re.findall(r'class="tick"[^>]*>(-?\d+)</text>', svg)]
    assert {-1000, 0, 1000, 2000} <= set(ticks)  # axes ticked in mm
    assert "x of I [mm]" in svg and "y of I [mm]" in svg
    assert "robot base B" in svg and "reach at the shoulder" in svg
    reach = re.search(r'<circle cx="[\d.]+" cy="[\d.]+" r="([\d.]+)" fill="none"', svg)
    left, right = (
        float(x) for x in re.findall(r'<text class="tick" x="([\d.]+)"[^>]*>(?:0|1000)<', svg)[:2]
    )
    assert abs(float(reach.group(1)) - 1.61 * (right - left)) < 1.0  # to scale: 1610 mm
    assert "stand (best placement)" in svg
    assert 'id="cycle"' in svg and "16.64 s" in svg and "18.20 s" in svg  # colour scale
    table = page[page.index('<table id="candidates"') :]
    rows = re.findall(r"<tr><td>", table)
    assert len(rows) == 10
    assert "True" not in table and "False" not in table and "<td>yes</td>" in table


def test_the_best_ten_are_distinct():
    """Candidates closer than 5 mm and 1° (the same grasp) count once."""
    result = _result()
    near = [_evaluation(1000.0 + 0.1 * k, 0.0, 16.60, yaw=0.1 * k) for k in range(5)]
    top = _top([*near, *result.evaluated], 10)
    assert sum(e.cycle_time_s == 16.60 for e in top) == 1
    positions = [e.candidate.X_IT for e in top]
    assert len(set(positions)) == len(positions) == 10
