"""Arc-welding heat input as EN 1011-1 (EN ISO/TR 17671-1) defines it:

    H = k · U · I / v                         [J/m; reported in kJ/mm = 1e-6 J/m]

with U the arc voltage [V], I the current [A], v the travel speed [m/s] and k the
process's thermal efficiency (EN 1011-1: 0.6 for TIG, 0.8 for MIG/MAG and SMAW,
1.0 for submerged arc). The arc runs at a set U and I, so the heat input follows the
travel speed alone: where the robot slows (a corner, a joint at its limit), the part
gets more heat. There is no output to compensate with; the time law holds the speed
within the band's speeds instead (:meth:`HeatInputModel.speed_band`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.process import per_metre


@dataclasses.dataclass(frozen=True)
class HeatInputModel:
    """``process.heat_input`` in SI units.

    Attributes:
        arc_power_w: k · U · I, the heat the arc puts into the part [W].
        band_j_m: [low, high] heat input [J/m].
    """

    arc_power_w: float
    band_j_m: tuple[float, float]

    column = "heat_input_kj_mm"
    unit_scale = 1e-6  # J/m → kJ/mm

    @property
    def band(self) -> tuple[float, float]:
        return self.band_j_m

    def predict(self, t: np.ndarray, v_tcp: np.ndarray, command=None) -> np.ndarray:
        """(N,) heat input H = k U I / v [J/m] at TCP speeds v_tcp (N,) [m/s]; NaN where
        the tool stands. ``t`` and ``command`` are unused (no dynamics, no output)."""
        return per_metre(np.full(np.shape(v_tcp), self.arc_power_w), v_tcp)

    def speed_band(self, u_min: float = 0.0, u_max: float = 0.0) -> tuple[float, float]:
        """TCP speeds [m/s] that give a heat input within the band: kUI/H_high .. kUI/H_low."""
        low, high = self.band_j_m
        return (self.arc_power_w / high, self.arc_power_w / low)
