"""How far the planned path on the part moves between the nominal and the calibrated
cell: what the nominal program would do wrong on the real cell.

The nominal plan puts the flange at ``X_IE(σ) = X_IT X_PF(σ)⁻¹ X_PE`` (paper eqs. 5–8,
process frame F on T). Run on the calibrated cell (X_IT', X_PE'), the same flange pose
holds the part at ``X_IP' = X_IE(σ) X_PE'⁻¹`` and the tool's tip stands at p_IT', so
the tool touches the part at

    p_P'(σ) = X_PE' X_PE⁻¹ X_PF(σ) X_IT⁻¹ p_IT'

instead of p_PF(σ): the distance between them is how far the path moves on the part,
and the angle between R_PF(σ) and the tool's real orientation on the part,
``R_PE' R_PE⁻¹ R_PF(σ) R_IT⁻¹ R_IT'``, how far the tool tilts against it. Both are
frame algebra on the fitted seams (no joints), at the cell's own tool rotation (0).

:func:`moved_flange` is the other view of the same change: the flange path the
calibrated cell asks for, ``X_IE'(σ) = X_IT' X_IT⁻¹ X_IE(σ) X_PE⁻¹ X_PE'`` (the same
process frames, tool turn included), beside the nominal one (the session draws both).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from pydrake.math import RigidTransform

from offline_prog.calibration.limits import MIN_SHIFT_POINTS, SHIFT_STEP_MM
from offline_prog.job.seams import errors_named_for, job_seams, seam_inputs, seam_key
from offline_prog.path.process_frames import process_frames
from offline_prog.stages import Inputs, fit_path


@dataclasses.dataclass(frozen=True)
class SeamShift:
    """One seam: the largest move of the path on the part [mm], where (σ [mm]), its
    rms [mm], and the largest tilt of the tool against the part [deg]."""

    seam: str
    max_mm: float
    sigma_mm: float
    rms_mm: float
    max_tilt_deg: float


def shift_along(
    p_PF: np.ndarray,
    R_PF: np.ndarray,
    *,
    X_IT: RigidTransform,
    X_PE: RigidTransform,
    X_IT_new: RigidTransform,
    X_PE_new: RigidTransform,
) -> tuple[np.ndarray, np.ndarray]:
    """(move [m] (N,), tilt [rad] (N,)) of the path points p_PF (N, 3) [m] with process
    frames R_PF (N, 3, 3) (module docstring)."""
    D = (X_PE_new @ X_PE.inverse()).GetAsMatrix4()  # the part's move, in P
    p_TQ = X_IT.inverse() @ X_IT_new.translation()  # the real tip in the nominal T
    p_P = p_PF + np.einsum("nij,j->ni", R_PF, p_TQ)
    moved = p_P @ D[:3, :3].T + D[:3, 3]
    R_TT = X_IT.rotation().inverse().multiply(X_IT_new.rotation()).matrix()
    R_real = D[:3, :3] @ R_PF @ R_TT
    cos = (np.einsum("nji,nji->n", R_PF, R_real) - 1.0) / 2.0  # (trace(R_PFᵀ R') − 1) / 2
    return np.linalg.norm(moved - p_PF, axis=1), np.arccos(np.clip(cos, -1.0, 1.0))


def path_shift(inputs: Inputs, X_IT_new: RigidTransform, X_PE_new: RigidTransform) -> list:
    """The :class:`SeamShift` of each seam of the cell (fitted as ``plan`` fits them).

    Raises:
        InputError: a seam ``plan`` would refuse (naming ``seams[k]``).
    """
    out = []
    for k, seam in enumerate(job_seams(inputs.cell)):
        with errors_named_for(seam_key(inputs.cell, k)):
            fit = fit_path(seam_inputs(inputs, k))
        length = fit.path.length
        s = np.linspace(0.0, length, max(MIN_SHIFT_POINTS, int(length * 1e3 / SHIFT_STEP_MM)))
        p_PF = fit.path(s, order=0)[0]
        R_PF = process_frames(fit.path, fit.normal, s)[0]
        move, tilt = shift_along(
            p_PF, R_PF, X_IT=inputs.X_IT, X_PE=inputs.X_PE, X_IT_new=X_IT_new, X_PE_new=X_PE_new
        )
        worst = int(move.argmax())
        out.append(
            SeamShift(
                seam.name,
                float(move[worst] * 1e3),
                float(s[worst] * 1e3),
                float(np.sqrt(np.mean(move**2)) * 1e3),
                float(np.degrees(tilt.max())),
            )
        )
    return out


def moved_flange(
    p_IE: np.ndarray,
    R_IE: np.ndarray,
    *,
    X_IT: RigidTransform,
    X_PE: RigidTransform,
    X_IT_new: RigidTransform,
    X_PE_new: RigidTransform,
) -> np.ndarray:
    """(N, 3) [m] the flange positions of the calibrated cell for the nominal flange
    poses p_IE (N, 3) [m], R_IE (N, 3, 3) (module docstring)."""
    A = (X_IT_new @ X_IT.inverse()).GetAsMatrix4()
    p_B = (X_PE.inverse() @ X_PE_new).translation()
    return (p_IE + R_IE @ p_B) @ A[:3, :3].T + A[:3, 3]
