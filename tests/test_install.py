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
        [sys.executable, "-m", "pip", "install", "--no-deps", "--target", str(target), str(REPO)],
        check=True,
        capture_output=True,
        timeout=600,
    )
    assert not (target / "offline_prog" / "robots" / "__init__.py").exists()
    assert (target / "offline_prog" / "robots" / "package.xml").is_file()
    work = tmp_path / "elsewhere"
    work.mkdir()
    env = {**os.environ, "PYTHONPATH": str(target)}
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "plan",
            str(CELLS / "seal_plate_kr16.yaml"),
            "--out",
            "out",
        ],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    probe = subprocess.run(
        [sys.executable, "-c", "import offline_prog; print(offline_prog.__file__)"],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    assert probe.stdout.startswith(str(target)), "the test must run the installed copy"
    for name in ("report.json", "preview.html", "report.html", "programs/offline_prog.src"):
        assert (work / "out" / name).is_file(), name
    assert "uPlot" in (work / "out" / "report.html").read_text()


def _requirements():
    """Every requirement pyproject.toml declares: the package's and the test extra's."""
    import tomllib

    from packaging.requirements import Requirement

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    declared = project["dependencies"] + project["optional-dependencies"]["test"]
    return [Requirement(text) for text in declared]


def _pins():
    """constraints.txt as {normalized name: version}."""
    from packaging.utils import canonicalize_name

    pins = {}
    for line in (REPO / "constraints.txt").read_text().splitlines():
        line = line.split("#")[0].strip()
        if line:
            name, version = line.split("==")
            pins[canonicalize_name(name)] = version
    return pins


def test_constraints_pin_every_declared_requirement_inside_its_range():
    """The README's installs use constraints.txt: a requirement added to pyproject.toml
    without a tested pin, or a pin outside the declared range, would give a fresh
    machine versions the suite never ran with."""
    from packaging.utils import canonicalize_name

    pins = _pins()
    for requirement in _requirements():
        name = canonicalize_name(requirement.name)
        assert name in pins, f"{requirement.name} has no pin in constraints.txt"
        assert requirement.specifier.contains(pins[name], prereleases=True), (
            f"constraints.txt pins {requirement.name}=={pins[name]}, outside {requirement}"
        )
