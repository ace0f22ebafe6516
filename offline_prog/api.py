"""The Python API for scripts and notebooks: load a cell, plan it, write the plan folder,
export programs, search a placement; what ``offline-prog`` does, without a shell.

    import offline_prog as op

    plan = op.plan("cells/seal_plate_kr16.yaml")
    print(plan.cycle_time_s, plan.feasible)
    plan.write("out/seal_plate_kr16")  # the plan folder, as `offline-prog plan --out`
    plan.export("krl", "out/krl")  # the programs, as `offline-prog export --format krl`
    op.export_programs("out/seal_plate_kr16", "krl")  # from a plan folder written before
    op.calibrate("cells/seal_plate_kr16.yaml", "out/calibrated.yaml", touches="t.csv")

Errors are the exception types the command turns into exit codes:
:class:`~offline_prog.errors.InputError` (bad input; exit 2),
:class:`~offline_prog.errors.PlanFailedError` (a seam the robot cannot do, a link not
found; exit 1), :class:`~offline_prog.export.formats.ExportRefusedError` and
``ValueError`` from :meth:`Plan.export` (exit 2). A plan that collides is returned, not
raised: ``plan.feasible`` is False and ``plan.failure`` says where.

Frames: I inertial, B robot base, E flange, P part, F process frame, T fixed tool.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from offline_prog.config.cell import Cell
from offline_prog.config.cell import load_cell as _read_cell
from offline_prog.config.checks import check_cell
from offline_prog.job.records import JobPlan
from offline_prog.plan import plan_job
from offline_prog.results.job_folder import FinishedJob, write_job_outputs
from offline_prog.robot.model import ROBOTS_DIR

PathLike = str | os.PathLike


def load_cell(path: PathLike) -> Cell:
    """Read a cell file and check it as ``offline-prog plan`` does before planning.

    Args:
        path: the cell YAML.

    Returns:
        The typed cell (``offline_prog.config.cell.Cell``): lengths in metres, poses as
        ``{translation, rotation}`` records, as the file gives them.

    Raises:
        InputError: a key, value or file the cell names is wrong (one line).
    """
    path = Path(path)
    cell = _read_cell(path)
    check_cell(path, cell, ROBOTS_DIR)
    return cell


class Plan:
    """A planned job: what ``offline-prog plan`` prints and writes, as Python values.

    Attributes:
        job: the pipeline's whole record (``offline_prog.job.records.JobPlan``).
    """

    def __init__(self, job: JobPlan):
        self.job = job

    @functools.cached_property
    def _finished(self) -> FinishedJob:
        return FinishedJob(self.job, Path(self.job.cell_file).stem)

    @property
    def report(self) -> dict:
        """report.json's content (the same dict the plan folder holds)."""
        return self._finished.report

    @property
    def cycle_time_s(self) -> float:
        """The job's cycle time, home to home [s]."""
        return float(self.job.samples.t[-1])

    @property
    def feasible(self) -> bool:
        """True when every seam, every link and the whole job's collision check pass."""
        return self.job.feasible

    @property
    def failure(self) -> str:
        """Why the plan is not feasible ("" when it is)."""
        return "" if self.feasible else self.job.failure

    @property
    def seams(self) -> list[dict]:
        """Each seam as run, in order: report.json's ``seams`` records (path, fit,
        motion, trajectory, robot motion, collision verdict)."""
        return self.report["seams"]

    @property
    def links(self) -> list[dict]:
        """Each link (home → first seam, …, last seam → home): method, duration [s],
        clearance [m], failure."""
        return self.report["links"]

    @property
    def quality(self) -> dict | None:
        """The process quality along the job (None: the cell has no ``process:``)."""
        return self.report.get("quality")

    @property
    def collision_free(self) -> bool:
        """The whole job's collision verdict (every sample and every step)."""
        return bool(self.job.collisions.collision_free)

    @property
    def min_distance_m(self) -> float:
        """The smallest distance between any two checked shapes over the job [m]."""
        return float(self.report["min_distance_m"])

    @property
    def t(self) -> np.ndarray:
        """(N,) sample times from home [s]."""
        return self.job.samples.t

    @property
    def q(self) -> np.ndarray:
        """(N, nq) joint positions [rad] on every sample."""
        return self.job.samples.q

    @property
    def qd(self) -> np.ndarray:
        """(N, nq) joint velocities [rad/s] on every sample."""
        return self.job.samples.qd

    @property
    def X_BE(self) -> np.ndarray:
        """(N, 4, 4) the flange E in the robot base B on every sample [m]."""
        return self.job.X_BE

    @property
    def tcp_speed(self) -> np.ndarray:
        """(N,) speed of the tool along the part [m/s] on every sample."""
        return self.job.tcp_speed

    def write(self, out_dir: PathLike) -> dict[str, Path]:
        """Write the plan folder (report.json, trajectory.csv, report.html, programs/,
        ...), exactly as ``offline-prog plan --out out_dir``.

        Returns:
            The files written, by name (``report``, ``trajectory``, ``report_html``...).

        Raises:
            InputError: out_dir is a file, or a folder holding files we did not write.
        """
        files, _ = write_job_outputs(self.job, Path(out_dir), finished=self._finished)
        return files

    def export(
        self,
        format: str,
        out_dir: PathLike,
        *,
        force: bool = False,
        no_payload: bool = False,
        **options,
    ) -> list[Path]:
        """Write one program format, as ``offline-prog export --format format``.

        Args:
            format: ``krl``, ``rapid``, ``urscript``, ``fanuc`` (the robot's controller
                language) or a joint-trajectory file (``csv``, ``ros-json``).
            out_dir: the folder the files go to (created; files we wrote before there
                are replaced).
            force: export a plan that failed (its header says so).
            no_payload: state no load in a controller program (the controller's active
                load is used, as its header says); without it a cell without masses is
                refused.
            options: the format's options (``chord_tol_m``, ``angle_tol_rad``,
                ``tcp_pose_convention``, ``line_limit``, ``mode``; SI units).

        Returns:
            The files written.

        Raises:
            ExportRefusedError: the plan failed and ``force`` is False.
            ValueError: unknown format or option, another controller's language.
        """
        from offline_prog.export.formats import export

        return export(
            self._finished.programs,
            format,
            Path(out_dir),
            force=force,
            no_payload=no_payload,
            **options,
        )

    def __repr__(self) -> str:
        verdict = "feasible" if self.feasible else f"failed: {self.failure}"
        return f"Plan({self.job.cell_file}, cycle {self.cycle_time_s:.2f} s, {verdict})"


def plan(
    cell_or_path: Cell | PathLike,
    *,
    file: PathLike | None = None,
    progress: Callable[[str], None] | None = None,
) -> Plan:
    """Plan a cell as ``offline-prog plan`` does (every cell is a job).

    Args:
        cell_or_path: a cell file, or a :class:`Cell` (from :func:`load_cell`, edited).
        file: for a :class:`Cell`: the file it stands for; its folder resolves the
            cell's relative paths and its stem names the programs (default:
            ``<cell name>.yaml`` in the current folder). Not with a path.
        progress: called with each stage's description as it starts.

    Raises:
        InputError: bad input (exit 2 on the command line).
        PlanFailedError: a seam the robot cannot do, a link not found (exit 1).
    """
    progress = progress or (lambda stage: None)
    if isinstance(cell_or_path, Cell):
        path = Path(file) if file is not None else Path(f"{cell_or_path.name or 'cell'}.yaml")
        return Plan(plan_job(path, progress=progress, cell=cell_or_path))
    if file is not None:
        raise TypeError("file= is for a Cell; a path names its own file")
    return Plan(plan_job(Path(cell_or_path), progress=progress))


def place(
    cell_file: PathLike,
    out_dir: PathLike,
    *,
    budget: int | None = None,
    seed: int | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[str, int, int], None] | None = None,
) -> dict:
    """Search where the tool (and grasp) go, as ``offline-prog place``; writes the
    placement folder into ``out_dir``.

    Args:
        budget, seed: override the cell's ``place.budget`` / ``place.seed``.
        workers: Dask workers on this machine (None: one per core; 0: this process).
        scheduler: the address of an existing Dask scheduler.
        progress: called with (stage, done, total) as candidates finish.

    Returns:
        placement.json's content: ``best`` (its ``X_IT``, ``cycle_time_s``,
        ``feasible``), ``cycle_time_cut``, ``screening``, ``engine``.

    Raises:
        InputError: bad input, an unreachable scheduler, a bad ``out_dir``.
    """
    from offline_prog.placement.run import place_cell

    return place_cell(
        Path(cell_file),
        Path(out_dir),
        budget=budget,
        seed=seed,
        workers=workers,
        scheduler=scheduler,
        progress=progress or (lambda stage, done, total: None),
    )


def export_programs(
    plan_dir: PathLike,
    format: str,
    out_dir: PathLike | None = None,
    *,
    force: bool = False,
    no_payload: bool = False,
    **options,
) -> list[Path]:
    """Write one program format from a plan folder written before (``plan --out``), as
    ``offline-prog export PLAN_DIR --format format [--out out_dir]``.

    Args:
        plan_dir: the plan folder (its report.json and trajectory.csv are read).
        out_dir: where the files go (default: ``plan_dir/programs``).
        force, no_payload, options: as :meth:`Plan.export`.

    Returns:
        The files written.

    Raises:
        ExportRefusedError: the plan failed and ``force`` is False.
        ValueError: plan_dir is not a plan folder of this version; unknown format or
            option, another controller's language, a controller program without masses
            and ``no_payload`` False (each one line, exit 2 on the command line).
    """
    from offline_prog.export.formats import check_export, export
    from offline_prog.export.job_program import JobProgramData

    data = JobProgramData.load(Path(plan_dir))
    check_export(data, format, force=force)  # before the options: the plan's words
    out = Path(out_dir) if out_dir is not None else Path(plan_dir) / "programs"
    return export(data, format, out, force=force, no_payload=no_payload, **options)


@dataclasses.dataclass(frozen=True)
class Calibrated:
    """What :func:`calibrate` found and wrote.

    Attributes:
        X_IT, X_PE: (4, 4) the calibrated fixed tool in I and grasp (the part in the
            flange E) [m], as written into the calibrated cell.
        files: ``calibrated`` (the cell file) and ``json`` (calibration.json).
        summary: the lines ``offline-prog calibrate`` prints (one per frame, residuals).
    """

    X_IT: np.ndarray
    X_PE: np.ndarray
    files: dict[str, Path]
    summary: list[str]

    @property
    def report(self) -> dict:
        """calibration.json's content (estimates with their σ, residuals, path shift)."""
        return json.loads(self.files["json"].read_text(encoding="utf-8"))


def calibrate(
    cell_file: PathLike,
    out: PathLike,
    *,
    touches: PathLike | None = None,
    from_controller: PathLike | None = None,
    controller_angles: bool = False,
) -> Calibrated:
    """Calibrate the cell's fixed tool and grasp, as ``offline-prog calibrate``: from
    touches measured on the robot (least squares) or from the frames a controller holds
    (KUKA ``$config.dat``, an ABB RAPID module); writes the calibrated cell ``out`` and
    calibration.json beside it. Exactly one of ``touches`` and ``from_controller``.

    Args:
        controller_angles: the touches' joint angles are the controller's (signs,
            offsets and the J2/J3 coupling), not the model's.

    Raises:
        InputError: bad input (the cell, the touches, the controller file, ``out``);
            degenerate touches or more than one gross outlier.
        TypeError: neither or both of ``touches`` and ``from_controller``.
    """
    from offline_prog.calibration.run import calibrate_controller, calibrate_touches
    from offline_prog.errors import InputError

    if (touches is None) == (from_controller is None):
        raise TypeError("calibrate: give exactly one of touches= and from_controller=")
    if controller_angles and touches is None:
        raise InputError(Path(from_controller), "--controller-angles", "applies to --touches")
    if touches is not None:
        run = calibrate_touches(
            Path(cell_file), Path(touches), Path(out), controller_angles=controller_angles
        )
    else:
        run = calibrate_controller(Path(cell_file), Path(from_controller), Path(out))
    calibration, lines, files = run
    return Calibrated(
        calibration.X_IT.GetAsMatrix4(), calibration.X_PE.GetAsMatrix4(), files, list(lines)
    )
