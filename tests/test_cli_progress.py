"""The plan command's progress display: a bar per counted stage with its count, the
running stage's text, and nothing at all when stdout is not a terminal."""

import io
import os
import pty
import subprocess
import sys

import numpy as np
import pytest
from rich.console import Console

from offline_prog.cli_progress import PlanProgress
from offline_prog.job.order import order_job
from offline_prog.progress import Step

from conftest import CELLS

REPO = CELLS.parent
MESSAGES = [
    "reading the cell",
    Step("seam 1/3: border (forward)", stage="seams", done=0, total=3),
    "fitting the B-spline",
    Step("seam 3/3: stripe (reverse)", stage="seams", done=2, total=3),
    Step("seam order: round 4, estimated air time 8.50 s", stage="order", done=10, total=40),
    Step("link 2/4: border -> stripe", stage="links", done=1, total=4),
]


def drawn(enabled: bool) -> str:
    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=120)
    with PlanProgress(console, enabled=enabled) as progress:
        for message in MESSAGES:
            progress(message)
            progress.bar.refresh()
    return out.getvalue()


def test_each_counted_stage_draws_its_bar_and_the_running_stage_its_text():
    text = drawn(enabled=True)
    shown = ["reading the cell", "fitting the B-spline", "seam 3/3: stripe (reverse)"]
    for message in [*shown, "round 4", "link 2/4: border -> stripe"]:
        assert message in text
    assert "━" in text  # a bar


def test_nothing_is_drawn_when_disabled():
    assert drawn(enabled=False) == ""


def test_a_step_is_the_message_text_for_callbacks_that_only_show_text():
    step = MESSAGES[1]
    assert step == "seam 1/3: border (forward)" and (step.done, step.total) == (0, 3)


def test_the_order_search_tells_each_round_its_budget_spent():
    rng = np.random.default_rng(4)
    n = 25
    ends = rng.uniform(-2, 2, (n, 2, 2, 6))  # seam, option, in/out
    options = [(k, "", *ends[k, o]) for k in range(n) for o in range(2)]
    limits = np.deg2rad([156, 156, 156, 330, 330, 615])
    calls = []
    kwargs = {"qd_max": limits, "qdd_max": 2 * limits, "n_seams": n, "budget": 2_000_000}
    result = order_job(options, np.zeros(6), progress=lambda *call: calls.append(call), **kwargs)
    assert len(calls) == result.search.rounds > 0
    rounds, air, used, budget = np.array(calls).T
    assert list(rounds) == list(range(1, len(calls) + 1))
    assert np.all(np.diff(used) > 0) and used[-1] <= result.search.used <= budget[0]
    assert np.all(np.diff(air) <= 1e-12)  # the best air time so far never grows
    assert air[-1] == pytest.approx(result.air_time_s)


@pytest.mark.slow
def test_plan_shows_progress_on_a_terminal_and_not_in_a_pipe(tmp_path):
    """The demo job through the command: on a terminal (a pty) the seams and links are
    counted on screen; piped, the output is the summary alone."""
    cell = str(CELLS / "seal_job_kr16.yaml")
    primary, replica = pty.openpty()
    command = [sys.executable, "-m", "offline_prog", "plan", cell, "--out"]
    terminal = {"stdin": replica, "stdout": replica, "stderr": replica}
    env = {**os.environ, "COLUMNS": "150"}
    process = subprocess.Popen([*command, str(tmp_path / "tty")], cwd=REPO, env=env, **terminal)
    os.close(replica)
    screen = b""
    while True:
        try:
            chunk = os.read(primary, 65536)
        except OSError:  # the command ended and closed its side
            break
        if not chunk:
            break
        screen += chunk
    assert process.wait() == 0
    text = screen.decode(errors="replace")
    assert "seam 1/4: border" in text and "link 5/5" in text and "done in" in text
    piped = subprocess.run(
        [*command, str(tmp_path / "pipe")], cwd=REPO, capture_output=True, text=True
    )
    assert piped.returncode == 0
    assert "seam 1/4" not in piped.stdout + piped.stderr
    assert piped.stderr == "" and piped.stdout.startswith("seal_job_kr16")


def test_place_says_where_it_is_in_plain_lines_when_piped():
    """Piped (not a terminal), ``place``'s progress is a plain line per stage at its
    start, every LINE_INTERVAL_S while it runs and at its end, on the line console
    (stdout): a log shows it is alive; stderr keeps its one line for an error."""
    from offline_prog.cli_progress import LINE_INTERVAL_S, PlaceProgress

    bars, lines = io.StringIO(), io.StringIO()
    now = [0.0]
    progress = PlaceProgress(
        Console(file=bars, force_terminal=False),
        Console(file=lines, force_terminal=False, width=200),
        clock=lambda: now[0],
    )
    with progress:
        for done in range(1, 101):  # the screen: a candidate every 0.5 s
            now[0] += 0.5
            progress("screen", done, 100)
        progress("plan", 1, 16)
    said = lines.getvalue().splitlines()
    screen = [line for line in said if "screening" in line]
    assert screen[0].startswith("place: screening") and screen[0].endswith("1/100 (0 s)")
    assert screen[-1].endswith("100/100 (50 s)")
    assert len(screen) == 2 + int(50 / LINE_INTERVAL_S) - 1  # start, every 10 s, end
    assert said[-1].startswith("place: planning candidates in full 1/16")
    assert bars.getvalue() == ""  # no bar drawn into a pipe


def test_place_draws_bars_on_a_terminal_and_no_lines():
    from offline_prog.cli_progress import PlaceProgress

    bars, lines = io.StringIO(), io.StringIO()
    with PlaceProgress(
        Console(file=bars, force_terminal=True, width=120), Console(file=lines)
    ) as p:
        p("screen", 10, 100)
        p.bar.refresh()
    assert "screening" in bars.getvalue() and "10/100" in bars.getvalue()
    assert lines.getvalue() == ""
