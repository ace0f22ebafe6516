"""Shared fixtures: seeded random paths, frames and cell files."""

import signal
from pathlib import Path

import numpy as np
import pytest
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RigidTransform, RotationMatrix
from replay_jobs import with_own_io  # noqa: F401  (the tests' shared cell edit)

from offline_prog.path.arc_length import ArcLengthPath
from offline_prog.path.bspline_fit import fit_bspline
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.path.process_frames import constant_normal

REPO = Path(__file__).resolve().parents[1]
CELLS = REPO / "cells"

# The commands the tests start and stop with Ctrl-C (a session, a preview, place) must
# get SIGINT as a terminal's foreground command does. A run started in the background by
# a shell without job control (a CI script, `cmd &`) ignores SIGINT, and an ignored
# signal stays ignored across exec: the session then never stopped (30 s, killed). A
# handler is reset to the default on exec, so the commands get Ctrl-C again.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


# Pose comparison tolerances.
POSITION_TOL_M = 1e-9
ANGLE_TOL_RAD = 1e-9


def planned_text(text: str, folder: Path, *, name: str = "cell.yaml"):
    """A demo cell's ``text`` (its ``data/`` paths the repository's) written as
    ``folder/name``, planned (asserted feasible) and its outputs written to
    ``folder/plan``: (the job, its JobProgramData)."""
    from offline_prog.export.job_program import JobProgramData
    from offline_prog.plan import plan_job
    from offline_prog.results.job_folder import write_job_outputs

    cell = folder / name
    cell.write_text(text.replace(": data/", f": {CELLS}/data/"), encoding="utf-8")
    job = plan_job(cell)
    assert job.feasible, job.failure
    write_job_outputs(job, folder / "plan")
    return job, JobProgramData.load(folder / "plan")


def random_curve_points(rng, *, closed: bool, n: int = 300, scale: float = 0.2) -> np.ndarray:
    """(n, 3) points on a smooth random Fourier curve that stays far from straight."""
    phase = np.linspace(0.0, 2 * np.pi, n, endpoint=not closed) * (1.0 if closed else 0.7)
    coefficients = rng.normal(scale=0.25, size=(3, 3, 2))
    base = np.stack([np.cos(phase), np.sin(phase), 0.1 * np.sin(2 * phase)], axis=1)
    wobble = np.zeros_like(base)
    for k in range(3):
        wobble += (
            np.outer(np.cos((k + 2) * phase), coefficients[k, :, 0])
            + np.outer(np.sin((k + 2) * phase), coefficients[k, :, 1])
        ) / (k + 2) ** 2
    return scale * (base + 0.3 * wobble)


def random_transform(rng, reach: float = 1.0) -> RigidTransform:
    """A uniformly random rotation and a translation in [−reach, reach]³ [m]."""
    q = rng.normal(size=4)
    return RigidTransform(
        RotationMatrix(Quaternion(q / np.linalg.norm(q))), rng.uniform(-reach, reach, 3)
    )


def random_flange_path(rng, *, closed: bool, planar: bool = False) -> FlangePath:
    """A random curved path with a normal roughly perpendicular to its plane
    (exactly perpendicular, into the plane z = 0 of P, when planar)."""
    points = random_curve_points(rng, closed=closed)
    normal = [0.1, -0.2, -1.0]
    if planar:
        points[:, 2], normal = 0.0, [0.0, 0.0, -1.0]
    path = ArcLengthPath(fit_bspline(points, closed=closed, tolerance_m=1e-5))
    return FlangePath(
        path, constant_normal(normal), X_IT=random_transform(rng), X_PE=random_transform(rng, 0.3)
    )


def rotation_log(R: np.ndarray) -> np.ndarray:
    """(N, 3) rotation vectors of (N, 3, 3) rotation matrices."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(R).as_rotvec()


def _planned_once(tmp_path_factory, plan, write):
    """name ↦ (plan, folder): cells/<name>.yaml planned and written once per session."""
    cache = {}

    def get(name: str):
        if name not in cache:
            out = tmp_path_factory.mktemp(name)
            result = plan(CELLS / f"{name}.yaml")
            write(result, out)
            cache[name] = (result, out)
        return cache[name]

    return get


@pytest.fixture(scope="session")
def planned_folder(planned_job):
    """name ↦ (plan, folder): a one-seam demo cell (``path:``) planned once per session as
    the job it is, with all its outputs: its seam's Plan and the job's plan folder
    (tests read the folder; they write anything of their own elsewhere)."""

    def get(name: str):
        job, folder = planned_job(name)
        return job.seams[0], folder

    return get


@pytest.fixture
def rng():
    return np.random.default_rng(0)


@pytest.fixture(scope="session")
def planned_job(tmp_path_factory):
    """name ↦ (job plan, folder): a demo job planned once per session with its outputs."""
    from offline_prog.plan import plan_job
    from offline_prog.results.job_folder import write_job_outputs

    return _planned_once(tmp_path_factory, plan_job, write_job_outputs)


@pytest.fixture(scope="session")
def planned_with_moves(tmp_path_factory):
    """name ↦ (job plan, its JobProgramData): a demo cell planned once per session with
    ``motion.approach_speed: 0.05``, so that its seams have straight approach and
    retract moves (at the default, the process speed, a flying seam's leads take them
    over and the programs write none)."""
    cache = {}

    def get(name: str):
        if name not in cache:
            text = (CELLS / f"{name}.yaml").read_text(encoding="utf-8")
            text = text.replace("\nmotion:\n", "\nmotion:\n  approach_speed: 0.05\n", 1)
            cache[name] = planned_text(text, tmp_path_factory.mktemp(f"{name}_moves"))
        return cache[name]

    return get


def _one_seam(file: Path) -> bool:
    from offline_prog.config.cell import load_cell

    return not load_cell(file).seams


# The demo cells of one seam (path:, a one-seam job), and those of several (seams:).
ONE_SEAM_CELLS = [c for c in sorted(CELLS.glob("*.yaml")) if _one_seam(c)]
JOB_CELLS = [c for c in sorted(CELLS.glob("*.yaml")) if not _one_seam(c)]
