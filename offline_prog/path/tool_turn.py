"""A symmetric tool turned along the path so that the wrist turns smoothly.

The process frame F = [t n b] turns about the tool's symmetry axis a (one of its
columns; y = n for a nozzle) wherever the path bends in the surface: per metre of
path by

    θ′(s) = w_PF(s) · a_P(s),      θ″(s) = w_PF′(s) · a_P(s)

(w_PF: F's angular velocity per metre in P, skew(w_PF) = R_PF′ R_PFᵀ; a_P′ = w_PF × a_P
is orthogonal to w_PF, so θ″ needs w_PF′ only). A fixed tool turn hands all of it to
the wrist: through a 30 mm corner radius the part turns by 90° in 47 mm of path, and
the wrist's jerk there (∝ θ‴ ṡ³) caps the speed (the seal demo slows to half its
process speed at each corner). A tool that cannot tell turns about a apart may take
up the sharp part of the turn instead:

    φ(s) = φ₀ + θ(s) − θ̄(s),    θ̄ = θ smoothed by a Gaussian of width w over s,

so the part turns by θ − φ = θ̄ − φ₀: the same total turn, spread over ~4 w
(``FlangePath(tool_turn=...)`` lays F onto T·R_a(φ)). On a closed path θ̄ wraps
around the seam (θ's total turn taken out first); on an open one the ends are held.
θ is the antiderivative of a quintic spline through the exact θ′ on a 0.5 mm grid,
θ̄ a quintic spline of the smoothed angle (which varies over w ≫ that grid), so
φ, φ′ and φ″ are one function and its exact derivatives, and the part's turn
θ′ − φ′ matches the process frames' to the spline's interpolation error.
"""

from __future__ import annotations

import collections
import threading

import numpy as np
from scipy.interpolate import make_interp_spline
from scipy.ndimage import gaussian_filter1d

from offline_prog.path.arc_length import ArcLengthPath
from offline_prog.path.fixed_tcp import vee
from offline_prog.path.process_frames import NormalField, process_frames

GRID_SPACING_M = 5e-4  # θ and θ̄ sampled every 0.5 mm
SPAN_REFINE = 16
SPAN_MARGIN_RAD = 1e-7
RESIDUALS_KEPT = 4  # σ grids whose θ − θ̄ a turn keeps (see SmoothTurn._residual)
TURNS_KEPT = 4  # SmoothTurns kept by smooth_turn_of
_lock = threading.Lock()
_turns: collections.OrderedDict = collections.OrderedDict()


def turn_rates(path: ArcLengthPath, normal: NormalField, s: np.ndarray, axis: int):
    """(θ′, θ″), each (N,): the process frame's turn about its ``axis`` column per
    metre of path [rad/m] and its derivative [rad/m²] (module doc)."""
    R, R1, R2 = process_frames(path, normal, s)
    w = vee(R1 @ np.swapaxes(R, 1, 2))
    w1 = vee(R2 @ np.swapaxes(R, 1, 2) + R1 @ np.swapaxes(R1, 1, 2))
    a = R[:, :, axis]
    return np.einsum("ij,ij->i", w, a), np.einsum("ij,ij->i", w1, a)


class SmoothTurn:
    """φ(s) = φ₀ + θ(s) − θ̄(s) (module doc), callable as ``FlangePath``'s tool_turn.

    Args:
        path: the processing path in P (its ``closed`` decides how θ̄ wraps).
        normal: the surface normal field.
        axis: the symmetry axis, "x", "y" or "z" of T.
        width_m: the Gaussian's standard deviation w over arc length [m], > 0.
        offset_rad: φ₀ [rad].
        scale: the share of θ − θ̄ taken up (< 1 where the free rotation is too small).
    """

    def __init__(
        self,
        path: ArcLengthPath,
        normal: NormalField,
        *,
        axis: str,
        width_m: float,
        offset_rad: float = 0.0,
        scale: float = 1.0,
    ):
        if not (np.isfinite(width_m) and width_m > 0):
            raise ValueError(f"tool turn: width must be > 0 m, got {width_m}")
        self.path, self.normal, self.axis = path, normal, "xyz".index(axis)
        self.width_m, self.offset_rad, self.scale = width_m, offset_rad, scale
        self._residuals: dict[bytes, tuple] = {}  # σ grid ↦ θ − θ̄ (shared with copies)
        length = path.length
        s = np.linspace(0.0, length, max(int(np.ceil(length / GRID_SPACING_M)), 10) + 1)
        # θ: the antiderivative of a quintic spline through the exact θ′ (module doc).
        self._theta = make_interp_spline(s, turn_rates(path, normal, s, self.axis)[0], k=5)
        self._theta = self._theta.antiderivative()
        theta = self._theta(s)
        step = s[1] - s[0]
        if path.closed:  # wrap the periodic part: θ less its total turn spread evenly
            trend = theta[-1] * s / length  # s = L is s = 0 again: left out of the wrap
            periodic = gaussian_filter1d((theta - trend)[:-1], width_m / step, mode="wrap")
            smooth = np.append(periodic, periodic[0]) + trend
        else:
            smooth = gaussian_filter1d(theta, width_m / step, mode="nearest")
        self._smooth = make_interp_spline(s, smooth, k=5)
        # The span of θ − θ̄ [rad]: φ₀ + scale · span must stay within the free rotation;
        # taken on a SPAN_REFINE× finer grid than the splines' (they overshoot their
        # nodes by up to ~1e-5 rad on a 5 mm width) and widened by SPAN_MARGIN_RAD.
        fine = np.linspace(0.0, length, SPAN_REFINE * (len(s) - 1) + 1)
        residual = self._theta(fine) - self._smooth(fine)
        self.span_rad = (residual.min() - SPAN_MARGIN_RAD, residual.max() + SPAN_MARGIN_RAD)

    def with_offset(self, offset_rad: float, scale: float = 1.0) -> SmoothTurn:
        """The same turn about another φ₀, taking up ``scale`` of θ − θ̄ (no refit)."""
        other = object.__new__(SmoothTurn)
        other.__dict__.update(self.__dict__, offset_rad=offset_rad, scale=scale)
        return other

    def __call__(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(φ, φ′, φ″), each (N,), at arc lengths s (N,) [rad, rad/m, rad/m²]."""
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.path.length)
        k = self.scale
        return tuple(
            (self.offset_rad if nu == 0 else 0.0) + k * residual
            for nu, residual in enumerate(self._residual(s))
        )

    def _residual(self, s: np.ndarray) -> tuple[np.ndarray, ...]:
        """(θ − θ̄, its first and second derivatives) at s (N,): the same for every φ₀
        (``with_offset`` copies share the splines and this cache), so the tool rotations
        tried for a seam evaluate the splines once per σ grid (the last RESIDUALS_KEPT)."""
        key = s.tobytes()
        residual = self._residuals.get(key)
        if residual is None:
            residual = tuple(self._theta(s, nu) - self._smooth(s, nu) for nu in range(3))
            for value in residual:
                value.setflags(write=False)
            with _lock:  # threads may plan at once (a Dask worker's threads)
                while len(self._residuals) >= RESIDUALS_KEPT:
                    self._residuals.pop(next(iter(self._residuals)))
                self._residuals[key] = residual
        return residual


def smooth_turn_of(
    path: ArcLengthPath, normal: NormalField, *, axis: str, width_m: float
) -> SmoothTurn:
    """``SmoothTurn(path, normal, axis=axis, width_m=width_m)``, one of the last
    TURNS_KEPT: the turn depends on neither X_IT nor X_PE, so a session's pose edits
    and placement candidates reuse it (its splines, span and σ-grid residuals)."""
    key = (id(path), id(normal), axis, width_m)
    with _lock:
        entry = _turns.get(key)
        if entry is not None and entry[0] is path and entry[1] is normal:
            _turns.move_to_end(key)
            return entry[2]
    turn = SmoothTurn(path, normal, axis=axis, width_m=width_m)
    with _lock:  # threads may plan at once (a Dask worker's threads)
        _turns[key] = (path, normal, turn)
        while len(_turns) > TURNS_KEPT:
            _turns.popitem(last=False)
    return turn
