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
