"""krllint (PyPI, a KRL style checker) run on a folder of KRL files, for the tests."""

import re
import subprocess
import sys
from pathlib import Path

import pytest


def assert_krllint_clean(folder: Path, work: Path) -> None:
    """krllint finds no violation, possible violation, error or fatal in ``folder``."""
    pytest.importorskip("krllint", reason="krllint (PyPI, KRL style checker) is not installed")
    config = work / "krllint_config.py"
    config.write_text(
        "from krllint.reporter import TextReporter\n"
        "INDENT_CHAR = ' '\nINDENT_SIZE = 3\nDISABLE = []\nREPORTER = TextReporter\n"
    )
    run = subprocess.run(
        [sys.executable, "-m", "krllint", "--config", str(config), str(folder)],
        capture_output=True,
        text=True,
        check=True,
    )
    counts = re.findall(r"^(\d+) (?:violated|possible|found|fatal)", run.stdout, re.M)
    assert "Error" not in run.stdout and len(counts) == 5, run.stdout
    assert all(int(c) == 0 for c in counts), run.stdout
