"""Cusps and flange-speed peaks of the robot path, and their smoothing (paper §4).

Mapping each path point to a flange pose can make the flange stop and turn back
(a cusp: |dp_IE/ds| → 0 while the part spins about the TCP) or race (a peak of
|dp_IE/ds|, the flange speed per unit TCP speed). The paper's remedy is to fit
the robot path again as a spline, trading a bounded deviation near the cusps for
lower jerk; ``SmoothedFlangePath`` does that for the flange position.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.arrays import true_runs
from offline_prog.constants import CUSP_MIN_FLANGE_RATIO, CUSP_PEAK_RATIO
from offline_prog.path.bspline_fit import fit_on_knots, open_knots
from offline_prog.path.fixed_tcp import FlangePath, FlangeSamples

# Cusp search grid spacing along the processing path [m].
CUSP_GRID_SPACING_M = 5e-4


@dataclasses.dataclass(frozen=True)
class Cusp:
    """A cusp or flange-speed peak at TCP arc length ``sigma_m``.

    Attributes:
        kind: "cusp" (the flange nearly stops) or "speed_peak".
        flange_speed_ratio: |dp_IE/ds| there (flange speed / TCP speed).
        turn_deg: change of the flange's direction of travel across it [deg].
        angular_rate_rad_per_m: |w_s|, flange rotation per metre of path.
    """

    sigma_m: float
    kind: str
    flange_speed_ratio: float
    turn_deg: float
    angular_rate_rad_per_m: float


def find_cusps(flange: FlangePath) -> list[Cusp]:
    """Scan the flange path on a fine s grid and report cusps and speed peaks.

    Each stretch where |dp_IE/ds| stays below CUSP_MIN_FLANGE_RATIO (a cusp) or
    above CUSP_PEAK_RATIO × its median (a speed peak) is one event, reported at
    its extreme value.
    """
    n = max(200, int(np.ceil(flange.length / CUSP_GRID_SPACING_M)) + 1)
    s = np.linspace(0.0, flange.length, n)
    f = flange(s)
    ratio = np.linalg.norm(f.dp_IE, axis=1)
    rate = np.linalg.norm(f.w_s, axis=1)
    events = [
        (a + int(np.argmin(ratio[a:b])), "cusp")
        for a, b in true_runs(ratio < CUSP_MIN_FLANGE_RATIO)
    ]
    events += [
        (a + int(np.argmax(ratio[a:b])), "speed_peak")
        for a, b in true_runs(ratio > CUSP_PEAK_RATIO * np.median(ratio))
    ]
    cusps = []
    for i, kind in sorted(events):
        a, b = f.dp_IE[max(i - 3, 0)], f.dp_IE[min(i + 3, n - 1)]
        cos_turn = np.dot(a, b) / max(np.linalg.norm(a) * np.linalg.norm(b), 1e-300)
        cusps.append(
            Cusp(
                float(s[i]),
                kind,
                float(ratio[i]),
                float(np.rad2deg(np.arccos(np.clip(cos_turn, -1, 1)))),
                float(rate[i]),
            )
        )
    return cusps


class SmoothedFlangePath:
    """The flange path with its position re-fitted as a spline over s (paper §4).

    The orientation R_IE(s) is kept; the position p_IE(s) is replaced by the
    least-squares quintic with the fewest control points whose deviation from
    the exact flange path stays within ``max_deviation_m``. Because the
    orientation is unchanged, the point under the TCP leaves the processing path
    by exactly the flange's deviation.
    """

    def __init__(self, flange: FlangePath, max_deviation_m: float, degree: int = 5):
        self.exact = flange
        self.X_IT, self.X_PE, self.path = flange.X_IT, flange.X_PE, flange.path
        n = max(400, int(np.ceil(flange.length / CUSP_GRID_SPACING_M)) + 1)
        s = np.linspace(0.0, flange.length, n)
        p = flange(s).p_IE
        lo, hi = degree + 1, n // 2
        best = None
        while lo <= hi:  # fewest control points meeting the bound
            m = (lo + hi) // 2
            spline = fit_on_knots(s, p, open_knots(s, m, degree), degree, closed=False)
            deviation = float(np.linalg.norm(spline(s) - p, axis=1).max())
            if deviation <= max_deviation_m:
                best, hi = (spline, deviation, m), m - 1
            else:
                lo = m + 1
        if best is None:
            raise ValueError(f"cannot smooth within {max_deviation_m * 1e3:.3g} mm")
        self.spline, self.max_deviation_m, self.n_control_points = best

    @property
    def length(self) -> float:
        return self.exact.length

    def __call__(self, s: np.ndarray) -> FlangeSamples:
        exact = self.exact(s)
        s = np.clip(s, 0.0, self.length)
        return dataclasses.replace(
            exact, p_IE=self.spline(s), dp_IE=self.spline(s, 1), ddp_IE=self.spline(s, 2)
        )
