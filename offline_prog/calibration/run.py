"""What ``offline-prog calibrate`` and the session call: touches or a controller file
in, the calibrated frames (with the path shift they cause) out.

- :func:`solve_touches`: the touches of a loaded cell → :class:`Calibration`
  (estimate, its one outlier, the calibrated X_IT and X_PE, the path shift);
- :func:`calibrate_touches` / :func:`calibrate_controller`: the commands, writing
  ``calibrated.yaml`` and ``calibration.json`` (``outputs``).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix

from offline_prog.calibration.controller_frames import FromController, from_controller
from offline_prog.calibration.estimate import Estimate
from offline_prog.calibration.limits import WRITE_DEG_DIGITS, WRITE_M_DIGITS
from offline_prog.calibration.measurement import Nominal, Problem, flange_poses
from offline_prog.calibration.outliers import Outlier, robust_fit
from offline_prog.calibration.path_shift import SeamShift, path_shift
from offline_prog.calibration.touches import Touches, read_touches
from offline_prog.errors import InputError
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import Inputs, load_inputs


@dataclasses.dataclass(frozen=True)
class Calibration:
    """A calibrated cell.

    Attributes:
        X_IT, X_PE: the calibrated frames, as written into the cell file (rounded to
            ``limits.WRITE_M_DIGITS`` / ``WRITE_DEG_DIGITS``).
        pose_IT, pose_PE: the same as (translation [m], rpy [deg]) tuples.
        shifts: how far the planned path on the part moves, per seam.
        estimate: the least-squares estimate (touches), or None (controller).
        outlier: the touch left out, or None.
        controller: the controller's frames read, or None (touches).
    """

    X_IT: RigidTransform
    X_PE: RigidTransform
    pose_IT: tuple
    pose_PE: tuple
    shifts: list[SeamShift]
    estimate: Estimate | None = None
    outlier: Outlier | None = None
    controller: FromController | None = None


def written_pose(X: np.ndarray) -> tuple[tuple, tuple]:
    """(translation [m], rpy [deg]) of X (4, 4), rounded as the cell file gets them."""
    rpy = RollPitchYaw(RotationMatrix(X[:3, :3])).vector()
    return (
        tuple(round(float(v), WRITE_M_DIGITS) + 0.0 for v in X[:3, 3]),
        tuple(round(float(np.degrees(a)), WRITE_DEG_DIGITS) + 0.0 for a in rpy),
    )


def _transform(pose: tuple) -> RigidTransform:
    return RigidTransform(RollPitchYaw(np.radians(pose[1])), np.array(pose[0]))


def touch_problem(inputs: Inputs, touches: Touches) -> Problem:
    """The least-squares problem of ``touches`` in the cell of ``inputs``."""
    calibration = inputs.cell.calibration
    X_IE = flange_poses(inputs.robot, inputs.X_IB.GetAsMatrix4(), touches.q)
    nominal = Nominal(
        p_IT=inputs.X_IT.translation() * 1e3,
        R_IT=inputs.X_IT.rotation().matrix(),
        pointer=np.array(calibration.pointer_mm or [0.0, 0.0, 0.0], dtype=float),
        axis_mm=calibration.tool_axis_point_mm,
        p_PE=inputs.X_PE.translation() * 1e3,
        R_PE=inputs.X_PE.rotation().matrix(),
    )
    return Problem.of(touches, X_IE, calibration, nominal)


def _calibration(inputs: Inputs, X_IT: np.ndarray, X_PE: np.ndarray, **kwargs) -> Calibration:
    pose_IT, pose_PE = written_pose(X_IT), written_pose(X_PE)
    new_IT, new_PE = _transform(pose_IT), _transform(pose_PE)
    shifts = path_shift(inputs, new_IT, new_PE)
    return Calibration(new_IT, new_PE, pose_IT, pose_PE, shifts, **kwargs)


def solve_touches(inputs: Inputs, touches: Touches) -> Calibration:
    """The calibrated cell of the touches (see the package docstring).

    Raises:
        InputError: degenerate touches, or more than one gross outlier.
    """
    estimate, outlier = robust_fit(touch_problem(inputs, touches))
    v = estimate.values
    X_IT, X_PE = np.eye(4), np.eye(4)
    X_IT[:3, :3], X_IT[:3, 3] = v.R_IT, v.p_IT * 1e-3
    X_PE[:3, :3], X_PE[:3, 3] = v.R_PE, v.p_PE * 1e-3
    return _calibration(inputs, X_IT, X_PE, estimate=estimate, outlier=outlier)


def calibrate_touches(
    cell_file: Path,
    touches_file: Path,
    out: Path,
    *,
    controller_angles: bool = False,
    robots_dir: Path = ROBOTS_DIR,
):
    """``offline-prog calibrate CELL --touches FILE --out calibrated.yaml``.

    Returns:
        (Calibration, the summary lines printed, the files written).

    Raises:
        InputError: bad input (the cell, the touches, ``out``).
    """
    from offline_prog.calibration.outputs import check_out, summary, write_outputs

    check_out(cell_file, out)
    inputs = load_inputs(Path(cell_file), robots_dir)
    if inputs.cell.calibration is None:
        raise InputError(
            cell_file,
            "calibration",
            "missing: the touches refer to calibration.pointer_mm and calibration.part_points",
        )
    touches = read_touches(
        touches_file, inputs.robot, inputs.cell.calibration, controller_angles=controller_angles
    )
    calibration = solve_touches(inputs, touches)
    source = {"touches_file": str(touches_file), "controller_angles": controller_angles}
    files = write_outputs(inputs, calibration, out, source=source, robots_dir=robots_dir)
    return calibration, summary(inputs, calibration, files), files


def calibrate_controller(
    cell_file: Path, controller_file: Path, out: Path, *, robots_dir: Path = ROBOTS_DIR
):
    """``offline-prog calibrate CELL --from-controller FILE --out calibrated.yaml``.

    Returns:
        (Calibration, the summary lines printed, the files written).

    Raises:
        InputError: bad input (the cell, the controller file, ``out``).
    """
    from offline_prog.calibration.outputs import check_out, summary, write_outputs

    check_out(cell_file, out)
    inputs = load_inputs(Path(cell_file), robots_dir)
    read = from_controller(Path(controller_file), inputs)
    calibration = _calibration(inputs, read.X_IT, read.X_PE, controller=read)
    source = {"controller_file": str(controller_file)}
    files = write_outputs(inputs, calibration, out, source=source, robots_dir=robots_dir)
    return calibration, summary(inputs, calibration, files), files
