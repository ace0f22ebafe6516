"""What calibrate writes and prints: ``calibrated.yaml``, ``calibration.json`` beside
it, and one summary line per frame.

- ``calibrated.yaml``: the cell file's text with ``tool.X_IT`` and ``part.X_PE``
  replaced (only their numbers: comments, layout and every other value kept;
  ``config.cell_text``), its data files re-pointed when it lies in another folder. It
  is loaded again and must give the calibrated frames, else nothing is kept.
- ``calibration.json`` (issue 38): the frames written; each estimate with its standard
  deviation (``estimates``); every touch's residual [mm] (``touches``); ``rms_mm``,
  ``noise_mm``, ``condition_number``; the outlier left out; ``path_shift``, how far
  the planned path on the part moves (mm, the worst σ per seam). From a controller:
  the data read (``controller``) instead of the estimates.

Nothing is written outside the folder of ``--out``; the cell file itself is never
replaced.
"""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.calibration.measurement import axis_derivative
from offline_prog.config.cell import load_cell, transform
from offline_prog.config.cell_text import relocated_text
from offline_prog.config.checks import check_cell
from offline_prog.errors import InputError

JSON_NAME = "calibration.json"
SAME_TOLERANCE = 1e-9  # the written file's frames equal the calibrated ones [m, rad]


def check_out(cell_file: Path, out: Path) -> None:
    """``--out`` is a new or replaceable .yaml file, not the cell file itself.

    Raises:
        InputError: one line naming the flag.
    """
    out = Path(out)
    if out.suffix not in (".yaml", ".yml"):
        raise InputError(out, "--out", "the calibrated cell is a .yaml file")
    if out.is_dir():
        raise InputError(out, "--out", "is a folder; name the calibrated cell file")
    if out.resolve() == Path(cell_file).resolve():
        raise InputError(
            out, "--out", "is the cell file itself; write the calibrated cell beside it"
        )


def _pose(pose: tuple) -> dict:
    return {"translation": list(pose[0]), "rpy_deg": list(pose[1])}


def _list(values, digits: int = 6) -> list[float]:
    return [round(float(v), digits) + 0.0 for v in values]


def _angle_deg(R: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))))


def estimates(inputs, calibration) -> dict:
    """Each estimate with its standard deviation (module docstring)."""
    e = calibration.estimate
    v, at, n = e.values, e.problem.layout(), e.problem.nominal
    out = {
        "tool_tip": {
            "p_IT_mm": _list(v.p_IT),
            "sigma_mm": _list(e.sigma("p_IT")),
            "moved_mm": float(np.linalg.norm(v.p_IT - n.p_IT)),
        },
        "pointer": None,
        "tool_axis": None,
        "grasp": None,
    }
    if "pointer" in at:
        given = inputs.cell.calibration.pointer_mm
        out["pointer"] = {
            "p_EQ_mm": _list(v.pointer),
            "sigma_mm": _list(e.sigma("pointer")),
            "from_pointer_mm": None if given is None else float(np.linalg.norm(v.pointer - given)),
        }
    if "axis" in at:
        dz = axis_derivative(n.R_IT, e.x[at["axis"]])  # the tilt's covariance as the axis'
        C_z = dz @ e.block_covariance("axis") @ dz.T
        out["tool_axis"] = {
            "z_T": _list(v.R_IT[:, 2], 9),
            "sigma_deg": float(np.degrees(np.sqrt(np.trace(C_z)))),
            "tilted_deg": _angle_deg(n.R_IT.T @ v.R_IT),
        }
    if "grasp_translation" in at:
        sigma_r = np.degrees(e.sigma("grasp_rotation"))
        out["grasp"] = {
            "p_PE_mm": _list(v.p_PE),
            "sigma_mm": _list(e.sigma("grasp_translation")),
            "rotation_sigma_deg": _list(sigma_r),  # about E's x, y, z
            "turn_sigma_deg": float(np.sqrt(np.sum(sigma_r**2))),
            "moved_mm": float(np.linalg.norm(v.p_PE - n.p_PE)),
            "turned_deg": _angle_deg(n.R_PE.T @ v.R_PE),
        }
    return out


def calibration_json(inputs, calibration, files: dict, source: dict) -> dict:
    """The content of calibration.json (module docstring)."""
    shifts = calibration.shifts
    worst = max(shifts, key=lambda s: s.max_mm)
    data = {
        "cell": str(inputs.file),
        "calibrated": str(files["calibrated"]),
        **source,
        "X_IT": _pose(calibration.pose_IT),
        "X_PE": _pose(calibration.pose_PE),
        "path_shift": {
            "max_mm": worst.max_mm,
            "seam": worst.seam,
            "sigma_mm": worst.sigma_mm,
            "seams": [dataclasses.asdict(s) for s in shifts],
        },
    }
    if calibration.controller is not None:
        c = calibration.controller
        data["controller"] = {"tool": c.tool_source, "part": c.part_source, "notes": list(c.notes)}
        return data
    e, outlier = calibration.estimate, calibration.outlier
    touches = [
        {"line": line, "target": target, "residual_mm": _list(r), "used": True}
        for line, target, r in zip(
            e.problem.touches.lines, e.problem.touches.targets, e.residuals, strict=True
        )
    ]
    if outlier is not None:
        touches.append(
            {
                "line": outlier.line,
                "target": outlier.target,
                "residual_mm": _list(outlier.residual),
                "used": False,
            }
        )
        touches.sort(key=lambda touch: touch["line"])
    distances = np.linalg.norm(e.residuals, axis=1)
    data.update(
        estimates=estimates(inputs, calibration),
        touches=touches,
        rms_mm=float(np.sqrt(np.mean(distances**2))),
        noise_mm=e.noise,
        condition_number=e.condition,
        outlier=None
        if outlier is None
        else {
            "line": outlier.line,
            "target": outlier.target,
            "distance_mm": outlier.distance_mm,
            "sigmas": outlier.sigmas,
        },
    )
    return data


def write_outputs(inputs, calibration, out: Path, *, source: dict, robots_dir: Path) -> dict:
    """Write calibrated.yaml (checked by loading it) and calibration.json.

    Returns:
        {"calibrated": path, "json": path}.

    Raises:
        RuntimeError: the written cell does not load to the calibrated frames (removed).
    """
    out = Path(out)
    poses = {"tool.X_IT": calibration.pose_IT, "part.X_PE": calibration.pose_PE}
    text = relocated_text(inputs.file, inputs.cell, out.parent, poses)
    write_atomic(out, text)
    try:
        cell = load_cell(out)
        check_cell(out, cell, robots_dir)
        same = all(
            transform(written).IsNearlyEqualTo(expected, SAME_TOLERANCE)
            for written, expected in (
                (cell.tool.X_IT, calibration.X_IT),
                (cell.part.X_PE, calibration.X_PE),
            )
        )
    except InputError:
        same = False
    if not same:
        os.unlink(out)
        raise RuntimeError(f"{out}: the written cell did not load to the calibrated frames")
    files = {"calibrated": out, "json": out.parent / JSON_NAME}
    data = calibration_json(inputs, calibration, files, source)
    write_atomic(files["json"], json.dumps(data, indent=1, allow_nan=False) + "\n")
    return files


def _xyz(values, sigmas=None, digits: int = 2) -> str:
    if sigmas is None:
        return ", ".join(f"{v:.{digits}f}" for v in values)
    return ", ".join(f"{v:.{digits}f} ±{s:.{digits}f}" for v, s in zip(values, sigmas, strict=True))


def summary(inputs, calibration, files: dict | None = None) -> list[str]:
    """One line per frame (X_IT, the pointer, X_PE), the touches, the path shift (and
    the files written)."""
    p_IT, rpy_IT = np.array(calibration.pose_IT[0]) * 1e3, calibration.pose_IT[1]
    p_PE, rpy_PE = np.array(calibration.pose_PE[0]) * 1e3, calibration.pose_PE[1]
    old_IT, old_PE = inputs.X_IT.translation() * 1e3, inputs.X_PE.translation() * 1e3
    worst = max(calibration.shifts, key=lambda s: s.max_mm)
    seam = f"seam {worst.seam} " if len(calibration.shifts) > 1 else ""
    tail = (
        f"the planned path on the part moves up to {worst.max_mm:.2f} mm ({seam}at σ = "
        f"{worst.sigma_mm:.1f} mm)"
    )
    if files is not None:
        tail += f"; wrote {files['calibrated']} and {files['json']}"
    turned = {
        key: _angle_deg(old.rotation().inverse().multiply(new.rotation()).matrix())
        for key, old, new in (
            ("IT", inputs.X_IT, calibration.X_IT),
            ("PE", inputs.X_PE, calibration.X_PE),
        )
    }
    if calibration.estimate is None:
        c = calibration.controller
        return [
            f"X_IT  tool [mm] {_xyz(p_IT)}, rpy [deg] {_xyz(rpy_IT, digits=3)} "
            f"(from {c.tool_source or 'the cell: not read'}; moved "
            f"{np.linalg.norm(p_IT - old_IT):.2f} mm, turned {turned['IT']:.3f}°)",
            f"X_PE  grasp [mm] {_xyz(p_PE)}, rpy [deg] {_xyz(rpy_PE, digits=3)} "
            f"(from {c.part_source or 'the cell: not read'}; moved "
            f"{np.linalg.norm(p_PE - old_PE):.2f} mm, turned {turned['PE']:.3f}°)",
            *(f"note: {note}" for note in c.notes),
            tail,
        ]
    found = estimates(inputs, calibration)
    tip, pointer, axis, grasp = (found[k] for k in ("tool_tip", "pointer", "tool_axis", "grasp"))
    axis_text = (
        "axis as in the cell (no tool_axis touches)"
        if axis is None
        else f"axis tilted {axis['tilted_deg']:.3f}° ±{axis['sigma_deg']:.3f}°"
    )
    lines = [
        f"X_IT  tool tip [mm] {_xyz(tip['p_IT_mm'], tip['sigma_mm'])} (moved "
        f"{tip['moved_mm']:.2f} mm); {axis_text}"
    ]
    if pointer is not None:
        given = pointer["from_pointer_mm"]
        lines.append(
            f"pointer tip in E [mm] {_xyz(pointer['p_EQ_mm'], pointer['sigma_mm'])}"
            + ("" if given is None else f" ({given:.2f} mm from calibration.pointer_mm)")
        )
    if grasp is None:
        lines.append("X_PE  as in the cell (no part points touched)")
    else:
        lines.append(
            f"X_PE  grasp [mm] {_xyz(grasp['p_PE_mm'], grasp['sigma_mm'])}, rpy [deg] "
            f"{_xyz(rpy_PE, digits=3)} ±{grasp['turn_sigma_deg']:.3f} (moved "
            f"{grasp['moved_mm']:.2f} mm, turned {grasp['turned_deg']:.3f}°)"
        )
    e, outlier = calibration.estimate, calibration.outlier
    distances = np.linalg.norm(e.residuals, axis=1)
    lines.append(
        f"touches: {len(distances)} used, RMS {np.sqrt(np.mean(distances**2)):.3f} mm, "
        f"condition number {e.condition:.1f}; "
        + (
            "no outlier"
            if outlier is None
            else f"left out line {outlier.line} ({outlier.target}), {outlier.distance_mm:.2f} mm "
            "off the others"
        )
    )
    return [*lines, tail]
