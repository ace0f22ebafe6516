"""How far LIN segments between pose samples pass from the samples between them, for
many segments at once (the measure of the point selection: ``export.density``,
``export.points``, and of ``export.densify``).

A segment (i, j) of a sampled pose path runs from sample i to sample j; its inner
samples are i+1 .. j-1. A controller moving LIN interpolates the position along the
chord and the orientation by slerp in proportion, so an inner sample deviates by its
distance [m] from the chord and by its angle [rad] from the slerp at the share λ of its
projection onto the chord. The functions here take the segments as index arrays (S,)
and evaluate all their inner samples in one vectorised pass (a ragged batch), so that a
selection asks for many candidate segments per numpy call instead of one.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def inner_samples(i: np.ndarray, j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The inner samples of the segments (i, j), segment after segment.

    Args:
        i, j: (S,) first and last sample of each segment (j ≥ i).

    Returns:
        (seg (K,), k (K,)): for each inner sample, its segment's position in i and its
        sample index.
    """
    counts = np.maximum(j - i - 1, 0)
    seg = np.repeat(np.arange(len(i)), counts)
    starts = np.cumsum(counts) - counts
    return seg, np.arange(len(seg)) - starts[seg] + i[seg] + 1


def segment_max(values: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """(S, ...) the largest of ``values`` (K, ...) (one row per inner sample, as
    ``inner_samples`` orders them) over each segment's inner samples; 0 for a segment
    without any."""
    counts = np.maximum(j - i - 1, 0)
    out = np.zeros((len(i), *values.shape[1:]))
    has = counts > 0
    if has.any():
        out[has] = np.maximum.reduceat(values, (np.cumsum(counts) - counts)[has], axis=0)
    return out


def _norms(x: np.ndarray) -> np.ndarray:
    """(K,) Euclidean norms of the rows of (K, 3): np.linalg.norm(x, axis=1), bit for
    bit, without its dispatch (the batched selection calls it in a loop)."""
    return np.sqrt(np.add.reduce(x * x, axis=1))


def rotation_vectors(R: np.ndarray) -> np.ndarray:
    """(S, 3) rotation vectors [rad] (axis · angle) of rotations (S, 3, 3). Near π the
    axis is ill-conditioned from the skew part, so scipy's careful branch takes over."""
    skew = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], 1)
    sin2 = _norms(skew)  # 2 sin θ
    angle = np.arctan2(0.5 * sin2, 0.5 * (np.trace(R, axis1=1, axis2=2) - 1.0))
    tiny = sin2 <= 1e-15
    out = np.where(tiny[:, None], 0.5 * skew, skew * (angle / np.where(tiny, 1.0, sin2))[:, None])
    near_pi = angle > np.pi - 1e-3
    if near_pi.any():
        out[near_pi] = Rotation.from_matrix(R[near_pi]).as_rotvec()
    return out


def rotation_matrices(rotvec: np.ndarray) -> np.ndarray:
    """(K, 3, 3) rotations of (K, 3) rotation vectors [rad] (Rodrigues, vectorized)."""
    angle = np.linalg.norm(rotvec, axis=1)
    small = angle < 1e-12
    axis = rotvec / np.where(small, 1.0, angle)[:, None]
    K = np.zeros((len(rotvec), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    K -= np.swapaxes(K, 1, 2)
    s, c = np.sin(angle)[:, None, None], (1.0 - np.cos(angle))[:, None, None]
    return np.eye(3) + s * K + c * (K @ K)


def rotation_angles(R: np.ndarray) -> np.ndarray:
    """(K,) rotation angles [rad] of (K, 3, 3) rotations, accurate near 0 and π
    (atan2 of the skew part's norm against the trace)."""
    skew = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], 1)
    return np.arctan2(0.5 * np.linalg.norm(skew, axis=1), 0.5 * (np.trace(R, axis1=1, axis2=2) - 1))


def segment_deviations(
    p: np.ndarray, R: np.ndarray, i: np.ndarray, j: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Largest position [m] and angle [rad] deviation of each segment's inner samples
    from LIN i → j (0 for j − i < 2).

    Args:
        p: (N, 3) positions; R: (N, 3, 3) orientations (same frame).
        i, j: (S,) the segments' first and last samples.

    Returns:
        ((S,) distances [m], (S,) angles [rad]).
    """
    i, j = np.asarray(i, dtype=int), np.asarray(j, dtype=int)
    seg, k = inner_samples(i, j)
    if len(k) == 0:
        return np.zeros(len(i)), np.zeros(len(i))
    a = p[i]
    chord = p[j] - a
    length2 = np.einsum("sc,sc->s", chord, chord)
    moving = length2 > 0
    inner, a_k, chord_k = p[k], a[seg], chord[seg]
    lam = np.einsum("kc,kc->k", inner - a_k, chord_k) / np.where(moving, length2, 1)[seg]
    lam = np.where(moving[seg], np.clip(lam, 0.0, 1.0), 0.0)
    distance = _norms(inner - (a_k + lam[:, None] * chord_k))
    # A pure reorientation (no chord): interpolate by sample index instead.
    if not moving.all():
        lam = np.where(moving[seg], lam, (k - i[seg]) / (j - i)[seg])
    # Slerp R(λ) = R_i·Exp(λ·θ·k) = R_i + sin(λθ)·R_i·K + (1 − cos(λθ))·R_i·K² (K = [k]×),
    # and each sample's angle from it by the trace: tr(R(λ)ᵀ R_k) = 1 + 2 cos(angle).
    R_i = R[i]
    omega = rotation_vectors(np.swapaxes(R_i, 1, 2) @ R[j])
    theta = _norms(omega)
    axis = omega / np.where(theta > 0, theta, 1.0)[:, None]  # 0 where θ = 0
    K = np.zeros((len(i), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    K -= np.swapaxes(K, 1, 2)
    A = R_i @ K
    terms = np.stack([R_i, A, A @ K], axis=1).reshape(len(i), 3, 9)  # R_i, R_i K, R_i K²
    traces = np.einsum("kf,kmf->km", R[k].reshape(-1, 9), terms[seg])
    turn = lam * theta[seg]
    trace = traces[:, 0] + np.sin(turn) * traces[:, 1] + (1.0 - np.cos(turn)) * traces[:, 2]
    angle = np.arccos(np.clip(0.5 * (trace - 1.0), -1.0, 1.0))  # ~1e-8 rad near 0
    worst = segment_max(np.column_stack([distance, angle]), i, j)
    return worst[:, 0], worst[:, 1]
