"""The pivot method: the fixed tool's tip and the pointer's tip on the flange, both
unknown, from touches of the one on the other at varied flange orientations.

Each ``tool_tip`` touch i puts the pointer's tip Q on the tool's tip T:
``p_IE_i + R_IE_i p_EQ = p_IT``, three equations linear in the six unknowns
(p_IT, p_EQ). Stacked, ``[−I  R_IE_i] [p_IT; p_EQ] = −p_IE_i`` is solved by linear
least squares; it starts the joint estimate (``estimate``), which refines it together
with the other frames.

The pointer's offset is separable from the tip only if the flange turns about two
independent axes: with R̄ the mean of the R_IE_i, the spread matrix
``M = Σ (R_IE_i − R̄)ᵀ (R_IE_i − R̄)`` (3 × 3, in E) is the normal matrix of p_EQ once
p_IT is eliminated, and ``sqrt(λ_min(M) / N)`` is the rms turn [rad] about the
least-turned axis; its eigenvector is the direction in E along which the pointer's
offset is not determined when that turn is small.
"""

from __future__ import annotations

import numpy as np

from offline_prog.calibration.limits import MIN_PIVOT_SPREAD_DEG, MIN_TOOL_TIP_TOUCHES
from offline_prog.errors import InputError


def pivot(X_IE: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(p_IT, p_EQ) [mm]: the tool's tip in I and the pointer's tip in E from the
    flange poses X_IE (N, 4, 4) [m] of ``tool_tip`` touches (linear least squares)."""
    R, p = X_IE[:, :3, :3], X_IE[:, :3, 3] * 1e3
    A = np.concatenate([np.broadcast_to(-np.eye(3), R.shape), R], axis=2).reshape(-1, 6)
    x = np.linalg.lstsq(A, -p.reshape(-1), rcond=None)[0]
    return x[:3], x[3:]


def orientation_spread(R_IE: np.ndarray) -> tuple[float, np.ndarray]:
    """(rms turn about the least-turned axis [rad], that direction in E (3,)) of
    flange rotations R_IE (N, 3, 3) (module docstring)."""
    D = R_IE - R_IE.mean(axis=0)
    M = np.einsum("nki,nkj->ij", D, D)
    eigenvalues, vectors = np.linalg.eigh(M)
    return float(np.sqrt(max(eigenvalues[0], 0.0) / len(R_IE))), vectors[:, 0]


def check_pivot(file: str, X_IE: np.ndarray) -> None:
    """Enough ``tool_tip`` touches (X_IE (N, 4, 4)), turned enough to separate the
    tool's tip from the pointer.

    Raises:
        InputError: one line saying what to add.
    """
    n = len(X_IE)
    if n < MIN_TOOL_TIP_TOUCHES:
        raise InputError(
            file,
            "",
            f"{n} tool_tip touch(es): the pivot needs at least {MIN_TOOL_TIP_TOUCHES} "
            f"with varied flange orientation; add {MIN_TOOL_TIP_TOUCHES - n}",
        )
    spread, direction = orientation_spread(X_IE[:, :3, :3])
    if np.degrees(spread) < MIN_PIVOT_SPREAD_DEG:
        shown = ", ".join(
            f"{v:.2f}" for v in direction * np.sign(direction[np.abs(direction).argmax()])
        )
        raise InputError(
            file,
            "",
            f"tool_tip touches: orientations too alike to separate the tool's tip from the "
            f"pointer (the flange turns {np.degrees(spread):.1f}° rms about its least-turned "
            f"axis, need ≥ {MIN_PIVOT_SPREAD_DEG:g}°; the pointer's offset along [{shown}] "
            "of E is not determined): add tool_tip touches with the flange tilted about "
            "other axes",
        )
