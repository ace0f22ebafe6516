"""Touches a known ("true") cell would give: the joint angles of a robot that puts a
pointer's tip on the tool's tip, on its axis point, and the gripped part's points on
the tool's tip, each with Gaussian touch noise, found by the robot's analytic IK.

Frames as in offline_prog.calibration.measurement: X_IE = X_IB · X_BE(q); the pointer's
tip p_EQ in E; the part point p_PK in P.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.calibration.touches import HEADER
from offline_prog.job.seams import seam_inputs
from offline_prog.path.fixed_tcp import FlangePath
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import fit_path, load_inputs

CELLS = Path(__file__).resolve().parents[2] / "cells"
# The ROS-Industrial FANUC support packages (README: robots import), or None.
SHARED_FANUC = next(
    (
        p
        for p in (
            CELLS.parents[1] / "shared/robots/ros-industrial-fanuc",
            Path("/work/shared/robots/ros-industrial-fanuc"),
        )
        if p.is_dir()
    ),
    None,
)
# calibration: blocks for the demo cells without one (points of each part, in P [mm]).
BLOCKS = {
    "weld_seam_irb2400": "{a: [-150, -40, 0], b: [150, -35, 0], c: [0, 30, 0]}",
    "tape_cylinder_ur10e": "{a: [-150, 0, 0], b: [150, 0, 0], c: [0, 60, -6]}",
}


def import_fanuc(robots_dir: Path) -> None:
    """The FANUC M-20iA imported from SHARED_FANUC into ``robots_dir`` (~15 s)."""
    from offline_prog.robot_import.run import import_robot

    import_robot(
        SHARED_FANUC / "fanuc_m20ia_support/urdf/m20ia.xacro",
        name="fanuc_m20ia",
        out=robots_dir,
        package_paths=[SHARED_FANUC],
        vendor="fanuc",
        samples=100,
    )


def calibration_cell(folder: Path, name: str, *, model: str = "", robots_dir: str = "") -> Path:
    """A copy of demo cell ``name`` in ``folder`` with a calibration: block (its data
    files named by absolute path; ``model``/``robots_dir`` put another robot in)."""
    text = (CELLS / f"{name}.yaml").read_text(encoding="utf-8")
    text = text.replace(": data/", f": {CELLS}/data/")
    if name in BLOCKS:
        text += (
            "calibration:\n  pointer_mm: [0, 0, 250]\n  tool_axis_point_mm: 50\n"
            f"  part_points: {BLOCKS[name]}\n"
        )
    if model:
        old = text[text.index("  model: ") : text.index("\n", text.index("  model: ")) + 1]
        text = text.replace(old, f"  model: {model}\n  robots_dir: {robots_dir}\n")
    file = folder / f"{name}.yaml"
    file.write_text(text, encoding="utf-8")
    return file


@dataclasses.dataclass(frozen=True)
class TrueCell:
    """The cell as it really is: X_IT, X_PE (4, 4) [m], the pointer's tip p_EQ [mm]."""

    X_IT: np.ndarray
    X_PE: np.ndarray
    pointer_mm: np.ndarray


@dataclasses.dataclass(frozen=True)
class Touched:
    """The synthetic touches: targets (N,), URDF joints (N, 6) [rad], the CSV text."""

    targets: list[str]
    q: np.ndarray
    text: str


def start_pose(cell_file: Path, robots_dir: Path = ROBOTS_DIR):
    """(inputs, X_IE (4, 4) [m]) of the cell's first seam at σ = 0: the flange
    orientation its touches are turned from."""
    inputs = load_inputs(Path(cell_file), robots_dir)
    seam = seam_inputs(inputs, 0)
    fit = fit_path(seam)
    flange = FlangePath(fit.path, fit.normal, X_IT=inputs.X_IT, X_PE=inputs.X_PE)
    p, R = flange.poses(np.array([0.0]))
    X = np.eye(4)
    X[:3, :3], X[:3, 3] = R[0], p[0]
    return inputs, X


def perturbed(X: np.ndarray, rng, *, mm: float, deg: float) -> np.ndarray:
    """X (4, 4) [m] moved by up to ``mm`` and turned by ``deg`` about a random axis."""
    axis = rng.normal(size=3)
    turn = Rotation.from_rotvec(axis / np.linalg.norm(axis) * np.radians(deg)).as_matrix()
    out = X.copy()
    out[:3, :3] = turn @ X[:3, :3]
    shift = rng.normal(size=3)
    out[:3, 3] += shift / np.linalg.norm(shift) * mm * 1e-3
    return out


def _tilted(R: np.ndarray, rng, low_deg: float, high_deg: float) -> np.ndarray:
    axis = rng.normal(size=3)
    angle = np.radians(rng.uniform(low_deg, high_deg))
    return Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle).as_matrix() @ R


def _joints(robot, X_IB: np.ndarray, X_IE: np.ndarray, q_ref: np.ndarray) -> np.ndarray | None:
    """The IK solution (6,) within the limits nearest q_ref, or None."""
    X_BE = np.linalg.inv(X_IB) @ X_IE
    q = robot.inverse(X_BE[None])[0]
    q_c = robot.controller_joints(q)
    ok = ~np.isnan(q).any(axis=1) & np.all((q_c >= robot.q_lower) & (q_c <= robot.q_upper), axis=1)
    if not ok.any():
        return None
    q = q[ok]
    return q[np.abs(q - q_ref).max(axis=1).argmin()]


def synthetic_touches(
    inputs,
    X_IE0: np.ndarray,
    true: TrueCell,
    rng,
    *,
    noise_mm: float = 0.02,
    n_tip: int = 8,
    n_axis: int = 4,
    per_point: int = 3,
    tilt_deg: tuple[float, float] = (15.0, 30.0),
    controller_angles: bool = False,
) -> Touched:
    """The touches of ``true`` (see the module docstring), turned from X_IE0 (4, 4).

    The pointer touches (tool_tip, tool_axis) tilt the flange by ``tilt_deg``, the
    part touches by up to 10°; every target point gets noise N(0, noise_mm²) per axis.
    """
    robot, X_IB = inputs.robot, inputs.X_IB.GetAsMatrix4()
    calibration = inputs.cell.calibration
    q_ref = _joints(robot, X_IB, X_IE0, np.zeros(6))
    assert q_ref is not None, "the start pose is out of reach"
    p_IT, R_IT = true.X_IT[:3, 3] * 1e3, true.X_IT[:3, :3]
    X_EP = np.linalg.inv(true.X_PE)
    plan = [("tool_tip", None)] * n_tip
    if calibration.tool_axis_point_mm is not None:
        plan += [("tool_axis", None)] * n_axis
    for name, point in calibration.part_points.items():
        plan += [(name, np.asarray(point, dtype=float))] * per_point
    targets, q_rows = [], []
    for name, p_PK in plan:
        for _ in range(200):  # draw orientations until the robot reaches one
            if p_PK is None:
                R = _tilted(X_IE0[:3, :3], rng, *tilt_deg)
                target = p_IT.copy()
                if name == "tool_axis":
                    target += calibration.tool_axis_point_mm * R_IT[:, 2]
                p_E = true.pointer_mm
            else:
                R = _tilted(X_IE0[:3, :3], rng, 0.0, 10.0)
                target = p_IT
                p_E = X_EP[:3, :3] @ p_PK + X_EP[:3, 3] * 1e3
            X_IE = np.eye(4)
            X_IE[:3, :3] = R
            X_IE[:3, 3] = (target + rng.normal(scale=noise_mm, size=3) - R @ p_E) * 1e-3
            q = _joints(robot, X_IB, X_IE, q_ref)
            if q is not None:
                break
        else:
            raise AssertionError(f"no reachable touch of {name}")
        targets.append(name)
        q_rows.append(q)
    q = np.array(q_rows)
    shown = robot.controller_joints(q) if controller_angles else q
    lines = [",".join(HEADER)] + [
        f"{name}," + ",".join(f"{v:.8f}" for v in np.degrees(row))
        for name, row in zip(targets, shown, strict=True)
    ]
    return Touched(targets, q, "\n".join(lines) + "\n")


def nominal_truth(inputs, rng, *, mm: float = 2.0, deg: float = 0.5, pointer_mm=None):
    """A true cell a few mm and a fraction of a degree from the cell file's (its
    pointer ``pointer_mm`` off the nominal one by ~1 mm)."""
    X_IT = perturbed(inputs.X_IT.GetAsMatrix4(), rng, mm=mm, deg=deg)
    X_PE = perturbed(inputs.X_PE.GetAsMatrix4(), rng, mm=mm, deg=deg)
    nominal = np.asarray(inputs.cell.calibration.pointer_mm or [0.0, 0.0, 0.0], dtype=float)
    pointer = nominal + rng.normal(scale=1.0, size=3) if pointer_mm is None else pointer_mm
    return TrueCell(X_IT, X_PE, np.asarray(pointer, dtype=float))
