"""The robot flange path for a spatially fixed TCP (paper §3.2, eqs. 5–8).

The process frame F at arc length s is brought onto the fixed tool frame T
(X_TP = X_PF(s)⁻¹), so the flange follows

    X_IE(s) = X_IT · X_PF(s)⁻¹ · X_PE,

i.e. p_IE = p_IT + R_IT R_PFᵀ (p_PE − p_PF) (eqs. 5, 7) and R_IE = R_IT R_PFᵀ R_PE
(eqs. 6, 8). Derivatives with respect to s are exact (the chain rule through the
spline and the process frames); w_s is the flange's angular velocity per metre of
path, expressed in I, so that w_IE_I = w_s · ṡ.
"""

from __future__ import annotations

import collections
import dataclasses
import threading

import numpy as np
from pydrake.math import RigidTransform

from offline_prog.path.arc_length import ArcLengthPath
from offline_prog.path.process_frames import NormalField, process_frames


def vee(W: np.ndarray) -> np.ndarray:
    """(N, 3) vector of the skew-symmetric part of (N, 3, 3) matrices."""
    return 0.5 * np.stack(
        [W[:, 2, 1] - W[:, 1, 2], W[:, 0, 2] - W[:, 2, 0], W[:, 1, 0] - W[:, 0, 1]], axis=1
    )


@dataclasses.dataclass(frozen=True)
class FlangeSamples:
    """The flange path and its s-derivatives at N arc lengths s.

    Attributes:
        s: (N,) TCP arc length along the processing path [m].
        p_PF: (N, 3) process-frame origin (path point) in P [m].
        R_PF: (N, 3, 3) process frames [t n b] in P.
        p_IE, dp_IE, ddp_IE: (N, 3) flange position in I and its 1st/2nd
            s-derivatives [m, 1, 1/m].
        R_IE: (N, 3, 3) flange orientation in I.
        w_s, dw_s: (N, 3) angular velocity per unit s in I [rad/m] and its
            s-derivative [rad/m²].
    """

    s: np.ndarray
    p_PF: np.ndarray
    R_PF: np.ndarray
    p_IE: np.ndarray
    dp_IE: np.ndarray
    ddp_IE: np.ndarray
    R_IE: np.ndarray
    w_s: np.ndarray
    dw_s: np.ndarray


# Evaluations kept by part_samples and part_in_tool, each: of at most PART_SAMPLES_MOST
# samples (≤ 2 MB each), the last ones used up to PART_CACHE_BYTES in all. A placement
# candidate of the seal job evaluates about 20 grids that every candidate shares (the
# tool rotations' trial grid and each seam direction's σ grid) and as many of its own
# (its time laws' samples): a count of 16 evicted the shared ones.
PART_SAMPLES_MOST = 5000
PART_CACHE_BYTES = 32 * 2**20


class _KeptValues(collections.OrderedDict):
    """key ↦ (owners, bytes, values), oldest first, with its entries' bytes summed as
    they come and go (``nbytes``: a sum over thousands of small entries per insert was a
    job's planning's hot spot)."""

    nbytes = 0

    def __setitem__(self, key, entry) -> None:
        old = self.get(key)
        if old is not None:
            self.nbytes -= old[1]
        super().__setitem__(key, entry)
        self.nbytes += entry[1]

    def __delitem__(self, key) -> None:
        self.nbytes -= self[key][1]
        super().__delitem__(key)

    def clear(self) -> None:
        super().clear()
        self.nbytes = 0


_part_samples = _KeptValues()
_part_in_tool = _KeptValues()
_lock = threading.Lock()


def _kept(cache: _KeptValues, key: tuple, owners: tuple, compute) -> tuple:
    """compute()'s arrays, made read-only and kept under key (the last used, up to
    PART_CACHE_BYTES); ``owners`` are the objects whose ids the key holds (kept with the
    entry, so an id is theirs while it lives)."""
    with _lock:
        entry = cache.get(key)
        if entry is not None and all(a is b for a, b in zip(entry[0], owners, strict=True)):
            cache.move_to_end(key)
            return entry[2]
    values = compute()
    for value in values:
        value.setflags(write=False)
    size = sum(value.nbytes for value in values)
    with _lock:  # threads may plan at once (a Dask worker's threads)
        cache[key] = (owners, size, values)
        while cache.nbytes > PART_CACHE_BYTES:
            del cache[next(iter(cache))]  # the oldest
    return values


def part_samples(path: ArcLengthPath, normal: NormalField, s: np.ndarray) -> tuple:
    """(p_PF, dp_PF, ddp_PF, R_PF, dR_PF, ddR_PF) at s (N,): the path point (N, 3) and
    process frame (N, 3, 3) in P with their first two s-derivatives, read-only.

    They depend on neither X_IT nor X_PE (nor the tool turn): the tool rotations tried
    for one seam, placement candidates and session edits evaluate the same path at the
    same σ grid again and again, so the last evaluations (of grids up to
    PART_SAMPLES_MOST, PART_CACHE_BYTES in all) are kept: the same path and normal
    objects, the same s bit for bit, the same arrays (read-only, so no caller changes
    what another gets).

    Raises:
        NormalTangentError: from :func:`process_frames`.
    """

    def compute():
        return (*path(s, order=2), *process_frames(path, normal, s))

    if len(s) > PART_SAMPLES_MOST:
        return compute()
    return _kept(_part_samples, (id(path), id(normal), s.tobytes()), (path, normal), compute)


def part_in_tool(path: ArcLengthPath, normal: NormalField, X_PE, s: np.ndarray) -> tuple:
    """(p_PF, R_PF, p_TE_T, dp_TE_T, ddp_TE_T, M, dM, ddM) at s (N,): what of the flange
    path depends on the part and X_PE only, not on X_IT or the tool's turn (kept as
    :func:`part_samples` keeps its values; every tool rotation tried reuses them).

    p_TE_T (N, 3): the flange origin from T's origin in T, R_TP (p_PE − p_PF) (paper
    eqs. 5, 7), and its first two s-derivatives; M (N, 3, 3) = R_TP R_PE, the flange
    orientation in T before the tool's turn (eqs. 6, 8), and its derivatives.
    """

    def compute():
        p_PF, dp_PF, ddp_PF, R_PF, dR_PF, ddR_PF = part_samples(path, normal, s)
        R_PE = X_PE.rotation().matrix()
        d = X_PE.translation() - p_PF
        R_TP, dR_TP, ddR_TP = (np.swapaxes(M, 1, 2) for M in (R_PF, dR_PF, ddR_PF))
        p_TE_T = np.einsum("nij,nj->ni", R_TP, d)
        dp_TE_T = np.einsum("nij,nj->ni", dR_TP, d) - np.einsum("nij,nj->ni", R_TP, dp_PF)
        ddp_TE_T = (
            np.einsum("nij,nj->ni", ddR_TP, d)
            - 2.0 * np.einsum("nij,nj->ni", dR_TP, dp_PF)
            - np.einsum("nij,nj->ni", R_TP, ddp_PF)
        )
        M, dM, ddM = R_TP @ R_PE, dR_TP @ R_PE, ddR_TP @ R_PE
        return p_PF, R_PF, p_TE_T, dp_TE_T, ddp_TE_T, M, dM, ddM

    if len(s) > PART_SAMPLES_MOST:
        return compute()
    pose = X_PE.GetAsMatrix4().tobytes()
    return _kept(_part_in_tool, (id(path), id(normal), pose, s.tobytes()), (path, normal), compute)


class FlangePath:
    """X_IE(s) for a part carried past the fixed tool.

    Args:
        path: the processing path r(s) = p_PF in P, by arc length.
        normal: the surface normal field on the part.
        X_IT: the fixed TCP frame T in I.
        X_PE: the flange frame E in the part frame P.
        tool_turn: optional φ(s) ↦ (φ, φ′, φ″) (N,) each [rad, rad/m, rad/m²]: the
            process frame is laid onto T·R_axis(φ(s)) (a tool symmetric about axis).
        axis: (3,) unit axis of T for tool_turn.
    """

    def __init__(
        self,
        path: ArcLengthPath,
        normal: NormalField,
        *,
        X_IT: RigidTransform,
        X_PE: RigidTransform,
        tool_turn=None,
        axis=(0.0, 1.0, 0.0),
    ):
        self.path = path
        self.normal = normal
        self.X_IT = X_IT
        self.X_PE = X_PE
        self.tool_turn = tool_turn
        self.axis = np.asarray(axis, dtype=float)
        # (s bytes, FlangeSamples) of the last evaluation: a joint plan evaluates the
        # same samples several times in a row (the output samples four times: the
        # workspace trajectory, the IK, the joint rates, the singularity distances).
        # One tuple, replaced whole: threads may read it at once.
        self._last: tuple = (None, None)

    @property
    def length(self) -> float:
        """TCP path length [m]."""
        return self.path.length

    def __call__(self, s: np.ndarray) -> FlangeSamples:
        """The flange path at s (N,) [m]; its arrays are read-only (an evaluation at the
        same s, bit for bit, returns the same FlangeSamples)."""
        s = np.asarray(s, dtype=float)
        key = s.tobytes()
        last_key, last = self._last
        if key == last_key:
            return last
        samples = self._compute(s.copy())  # the caller's s stays the caller's
        for field in dataclasses.fields(samples):
            getattr(samples, field.name).setflags(write=False)
        self._last = (key, samples)
        return samples

    def _compute(self, s: np.ndarray) -> FlangeSamples:
        p_PF, R_PF, p_TE_T, dp_TE_T, ddp_TE_T, M, dM, ddM = part_in_tool(
            self.path, self.normal, self.X_PE, s
        )
        R_IT = self.X_IT.rotation().matrix()
        p_IT = self.X_IT.translation()

        # p_IE = p_IT + G p_TE_T (paper eqs. 5, 7), G = R_IT · R_axis(φ(s)): the tool
        # frame the process frame is laid onto.
        G, dG, ddG = self._tool_rotation(s, R_IT)
        p_IE = p_IT + np.einsum("nij,nj->ni", G, p_TE_T)
        dp_IE = np.einsum("nij,nj->ni", dG, p_TE_T) + np.einsum("nij,nj->ni", G, dp_TE_T)
        ddp_IE = (
            np.einsum("nij,nj->ni", ddG, p_TE_T)
            + 2.0 * np.einsum("nij,nj->ni", dG, dp_TE_T)
            + np.einsum("nij,nj->ni", G, ddp_TE_T)
        )

        # R_IE = R_IT R_TP R_PE (paper eqs. 6, 8) and its derivatives.
        R_IE = G @ M
        dR_IE = dG @ M + G @ dM
        ddR_IE = ddG @ M + 2.0 * dG @ dM + G @ ddM
        # skew(w_s) = R' Rᵀ; its derivative is R'' Rᵀ + R' R'ᵀ.
        R_EI = np.swapaxes(R_IE, 1, 2)
        w_s = vee(dR_IE @ R_EI)
        dw_s = vee(ddR_IE @ R_EI + dR_IE @ np.swapaxes(dR_IE, 1, 2))
        return FlangeSamples(s, p_PF, R_PF, p_IE, dp_IE, ddp_IE, R_IE, w_s, dw_s)

    def poses(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(p_IE (N, 3) [m], R_IE (N, 3, 3)) at s (N,): the flange poses alone, the
        same numbers as ``self(s)`` gives (no derivatives)."""
        s = np.asarray(s, dtype=float)
        _, _, p_TE_T, _, _, M, _, _ = part_in_tool(self.path, self.normal, self.X_PE, s)
        G = self._tool_rotation(s, self.X_IT.rotation().matrix(), order=0)[0]
        return self.X_IT.translation() + np.einsum("nij,nj->ni", G, p_TE_T), G @ M

    def _tool_rotation(self, s: np.ndarray, R_IT: np.ndarray, order: int = 2):
        """(G, G′, G″), each (N, 3, 3): G = R_IT·exp(K φ(s)), K = skew(axis) (G alone,
        the others None, for ``order`` 0)."""
        n = len(s)
        if self.tool_turn is None:
            G = np.broadcast_to(R_IT, (n, 3, 3))
            zero = np.zeros((n, 3, 3))
            return G, zero, zero
        phi, dphi, ddphi = (np.asarray(v, dtype=float) for v in self.tool_turn(s))
        a = self.axis
        K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
        A = (
            np.eye(3)
            + np.sin(phi)[:, None, None] * K
            + (1.0 - np.cos(phi))[:, None, None] * (K @ K)
        )  # Rodrigues
        G = R_IT @ A
        if order == 0:
            return G, None, None
        dG = G @ K * dphi[:, None, None]
        ddG = G @ (K @ K * (dphi**2)[:, None, None] + K * ddphi[:, None, None])
        return G, dG, ddG
