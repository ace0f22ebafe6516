"""One least-squares estimate of every frame the touches determine, with its
uncertainty.

The residuals of all touches (``measurement``) are minimised together over the
unknowns with scipy's Levenberg-Marquardt (``least_squares(method="lm")``), started
from the pivot, the touched axis and the Kabsch grasp (``pivot``, ``tool_axis``,
``grasp``): least-squares identification from measurements as in Rameder, Gattringer,
Müller, "Geometric Robot Calibration Using a Calibration Plate", arXiv 2510.25338
(2025).

Uncertainty: with J the residuals' Jacobian at the solution (analytic, ``measurement``),
m residuals and n unknowns, the touch noise per axis is s² = ‖r‖² / (m − n) and the
covariance of the unknowns s² (JᵀJ)⁻¹ (Gauss-Markov; the reported standard deviations
are its diagonal's square roots). The condition number is that of J with unit-norm
columns, free of the units (mm, rad) of its columns: a large one means some
combination of unknowns the touches hardly see (the observability index of robot
calibration, Driels and Pathre). Above MAX_CONDITION the estimate is refused, naming
the unknown that is worst determined.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.optimize import least_squares

from offline_prog.calibration.grasp import check_grasp, grasp_start
from offline_prog.calibration.limits import MAX_CONDITION
from offline_prog.calibration.measurement import AXIS, PART, TIP, Problem, Values
from offline_prog.calibration.pivot import check_pivot, pivot
from offline_prog.calibration.tool_axis import axis_start, check_axis
from offline_prog.errors import InputError

# What to touch when an unknown is not determined.
HINTS = {
    "p_IT": "add tool_tip touches",
    "pointer": "add tool_tip touches with the flange tilted about other axes",
    "axis": "add tool_axis touches from other flange orientations",
    "grasp_translation": "touch the part points with the flange at other orientations",
    "grasp_rotation": "touch part points farther apart",
}


@dataclasses.dataclass(frozen=True)
class Estimate:
    """The least-squares estimate of one problem.

    Attributes:
        problem: what was solved.
        x: (n,) the unknowns (mm, rad; ``problem.layout()``).
        values: the frames x means.
        residuals: (N, 3) each touch's residual in I [mm].
        covariance: (n, n) of x [mm², rad²].
        noise: s, the touch noise per axis the residuals show [mm].
        condition: the condition number of the column-scaled Jacobian.
    """

    problem: Problem
    x: np.ndarray
    values: Values
    residuals: np.ndarray
    covariance: np.ndarray
    noise: float
    condition: float

    def sigma(self, block: str) -> np.ndarray:
        """Standard deviations of one block of unknowns [mm or rad]."""
        at = self.problem.layout()[block]
        return np.sqrt(np.diag(self.covariance)[at])

    def block_covariance(self, block: str) -> np.ndarray:
        at = self.problem.layout()[block]
        return self.covariance[at, at]


def check_touches(problem: Problem) -> None:
    """Enough touches of each kind, turned and spread enough (the checks of ``pivot``,
    ``tool_axis`` and ``grasp``).

    Raises:
        InputError: one line saying what to add or fix.
    """
    file, kinds = problem.touches.file, problem.kinds
    tip, axis, part = kinds == TIP, kinds == AXIS, kinds == PART
    check_axis(file, int(axis.sum()), int(tip.sum()))
    if tip.any():
        check_pivot(file, problem.X_IE[tip])
    if part.any():
        names = [t for t, is_part in zip(problem.touches.targets, part, strict=True) if is_part]
        check_grasp(file, names, problem.part_points)


def start_values(problem: Problem) -> Values:
    """The pivot, the touched axis and the Kabsch grasp (the cell's values where the
    touches say nothing): where the least-squares search starts."""
    n, kinds, X_IE = problem.nominal, problem.kinds, problem.X_IE
    p_IT, pointer = n.p_IT, n.pointer
    if (kinds == TIP).any():
        p_IT, pointer = pivot(X_IE[kinds == TIP])
    R_IT = n.R_IT
    if (kinds == AXIS).any():
        R_IT = axis_start(X_IE[kinds == AXIS], p_IT, pointer, n.R_IT, problem.touches.file)
    p_PE, R_PE = n.p_PE, n.R_PE
    if (kinds == PART).any():
        p_PE, R_PE = grasp_start(X_IE[kinds == PART], problem.p_PK[kinds == PART], p_IT)
    return Values(p_IT, R_IT, pointer, p_PE, R_PE)


def fit(problem: Problem) -> Estimate:
    """The least-squares estimate of ``problem`` (checked first).

    Raises:
        InputError: degenerate touches (see :func:`check_touches`), fewer equations
            than unknowns plus one, or an unknown the touches do not determine.
    """
    check_touches(problem)
    file = problem.touches.file
    m, n = 3 * len(problem.kinds), problem.size()
    if m <= n:
        raise InputError(
            file, "", f"{m // 3} touches give {m} equations for {n} unknowns: add touches"
        )
    x0 = problem.start(start_values(problem))
    result = least_squares(
        lambda x: problem.residuals(x).ravel(),
        x0,
        jac=problem.jacobian,
        method="lm",
        xtol=1e-12,
        ftol=1e-12,
    )
    x = result.x
    J = problem.jacobian(x)
    scale = np.linalg.norm(J, axis=0)
    scale[scale == 0.0] = 1.0
    U, singular, Vt = np.linalg.svd(J / scale, full_matrices=False)
    condition = float(singular[0] / singular[-1]) if singular[-1] > 0 else np.inf
    if condition > MAX_CONDITION:
        worst = int(np.abs(Vt[-1]).argmax())
        block = next(b for b, at in problem.layout().items() if at.start <= worst < at.stop)
        raise InputError(
            file,
            "",
            f"the touches do not determine {block} (condition number {condition:.3g}): "
            f"{HINTS[block]}",
        )
    residuals = problem.residuals(x)
    noise2 = float(np.sum(residuals**2)) / (m - n)
    inverse = (Vt.T / singular**2) @ Vt  # (Jsᵀ Js)⁻¹
    covariance = noise2 * inverse / np.outer(scale, scale)
    return Estimate(
        problem, x, problem.values(x), residuals, covariance, float(np.sqrt(noise2)), condition
    )
