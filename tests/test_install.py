"""`pip install .` (not editable) carries everything a plan needs: robots, meshes, assets."""

import os
import subprocess
import sys

import pytest

from conftest import CELLS, REPO


@pytest.mark.slow
def test_installed_package_plans_a_demo_cell_from_another_directory(tmp_path):
    target = tmp_path / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-deps",
         "--target", str(target), str(REPO)],
        check=True, capture_output=True, timeout=600,
    )  # fmt: skip
    assert not (target / "offline_prog" / "robots" / "__init__.py").exists()
    assert (target / "offline_prog" / "robots" / "package.xml").is_file()
    work = tmp_path / "elsewhere"
    work.mkdir()
    env = {**os.environ, "PYTHONPATH": str(target)}
    done = subprocess.run(
        [sys.executable, "-m", "offline_prog", "plan", str(CELLS / "seal_plate_kr16.yaml"),
         "--out", "out"],
        cwd=work, env=env, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    probe = subprocess.run(
        [sys.executable, "-c", "import offline_prog; print(offline_prog.__file__)"],
        cwd=work, env=env, capture_output=True, text=True, check=True,
    )  # fmt: skip
    assert probe.stdout.startswith(str(target)), "the test must run the installed copy"
    for name in ("report.json", "preview.html", "report.html", "programs/offline_prog.src"):
        assert (work / "out" / name).is_file(), name
    assert "uPlot" in (work / "out" / "report.html").read_text()
