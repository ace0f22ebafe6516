"""Arc-welding heat input as EN 1011-1 (EN ISO/TR 17671-1) defines it:

    H = k · U · I / v                         [J/m; reported in kJ/mm = 1e-6 J/m]

with U the arc voltage [V], I the current [A], v the travel speed [m/s] and k the
process's thermal efficiency (EN 1011-1: 0.6 for TIG, 0.8 for MIG/MAG and SMAW,
1.0 for submerged arc). The arc runs at a set U and I, so the heat input follows the
travel speed alone: where the robot slows (a corner, a joint at its limit), the part
gets more heat. There is no output to compensate with; the time law holds the speed
within the band's speeds instead (:meth:`HeatInputModel.speed_band`).

The cell keys (``process.heat_input``) and their bounds: ``voltage_v`` (0, 113] V (IEC
60974-1 caps a welding power source's no-load voltage at 113 V peak; arcs burn at
10–45 V), ``current_a`` (0, 2500] A (submerged arc, the highest-current arc process,
runs up to about 2,000 A a wire), ``efficiency`` (0, 1], ``target_kj_mm`` a band of
positive heat inputs up to 100 kJ/mm (arc welds lie below about 10 kJ/mm).
"""

# No ``from __future__ import annotations``: Drake's typed loader reads the keys'
# field types as written.
import dataclasses
from typing import Self

import numpy as np

from offline_prog.errors import InputError
from offline_prog.process import per_metre
from offline_prog.process.key_bounds import at_most, band, positive
from offline_prog.process.protocol import ProcessModel, required_key

MAX_VOLTAGE_V = 113.0  # IEC 60974-1: a welding power source's no-load voltage, peak DC
MAX_CURRENT_A = 2500.0  # submerged arc runs up to about 2,000 A a wire
MAX_HEAT_INPUT_KJ_MM = 100.0  # arc welds lie below about 10 kJ/mm


@dataclasses.dataclass
class HeatInputConfig:
    """``process.heat_input``: the cell's keys."""

    voltage_v: float = required_key()  # arc voltage U
    current_a: float = required_key()  # welding current I
    efficiency: float = required_key()  # thermal efficiency k of the process (EN 1011-1)
    target_kj_mm: list[float] = required_key()  # [low, high]


@dataclasses.dataclass(frozen=True)
class HeatInputModel(ProcessModel):
    """``process.heat_input`` in SI units.

    Attributes:
        arc_power_w: k · U · I, the heat the arc puts into the part [W].
        band_j_m: [low, high] heat input [J/m].
    """

    arc_power_w: float
    band_j_m: tuple[float, float]

    name = "heat_input"
    Keys = HeatInputConfig
    column = "heat_input_kj_mm"
    unit = "kJ/mm"
    unit_scale = 1e-6  # J/m → kJ/mm

    @classmethod
    def check_keys(cls, file, keys: HeatInputConfig, flow) -> None:
        key = f"process.{cls.name}"
        for name in ("voltage_v", "current_a", "efficiency"):
            positive(file, f"{key}.{name}", getattr(keys, name))
        if keys.efficiency > 1:
            raise InputError(
                file, f"{key}.efficiency", f"must be at most 1, got {keys.efficiency:g}"
            )
        band(file, f"{key}.target_kj_mm", keys.target_kj_mm, positive=True)
        at_most(
            file,
            f"{key}.voltage_v",
            keys.voltage_v,
            MAX_VOLTAGE_V,
            "V",
            "IEC 60974-1 caps a welding power source's no-load voltage at 113 V peak; "
            "arcs burn at 10–45 V",
        )
        at_most(
            file,
            f"{key}.current_a",
            keys.current_a,
            MAX_CURRENT_A,
            "A",
            "submerged arc, the highest-current arc process, runs up to about 2,000 A a wire",
        )
        at_most(
            file,
            f"{key}.target_kj_mm",
            keys.target_kj_mm[1],
            MAX_HEAT_INPUT_KJ_MM,
            "kJ/mm",
            "arc welds lie below about 10 kJ/mm (is the unit kJ/mm?)",
        )

    @classmethod
    def from_keys(cls, keys: HeatInputConfig) -> Self:
        low, high = keys.target_kj_mm
        return cls(
            arc_power_w=keys.efficiency * keys.voltage_v * keys.current_a,
            band_j_m=(low * 1e6, high * 1e6),
        )

    @property
    def band(self) -> tuple[float, float]:
        return self.band_j_m

    def predict(self, t: np.ndarray, v_tcp: np.ndarray, command=None) -> np.ndarray:
        """(N,) heat input H = k U I / v [J/m] at TCP speeds v_tcp (N,) [m/s]; NaN where
        the tool stands. ``t`` and ``command`` are unused (no dynamics, no output)."""
        return per_metre(np.full(np.shape(v_tcp), self.arc_power_w), v_tcp)

    def delivered(self, t: np.ndarray, command=None) -> np.ndarray:
        """(N,) ones: the arc burns at its set U and I wherever the torch is on."""
        return np.ones(len(t))

    def delivered_at_rest(self, settings=None) -> float:
        """0: the arc gives its heat at rest too (a standstill with the arc on counts)."""
        return 0.0

    def speed_band(self, u_min: float = 0.0, u_max: float = 0.0) -> tuple[float, float]:
        """TCP speeds [m/s] that give a heat input within the band: kUI/H_high .. kUI/H_low."""
        low, high = self.band_j_m
        return (self.arc_power_w / high, self.arc_power_w / low)

    def speed_band_reason(self, v: float, *, u_min: float = 0.0, u_max: float = 0.0) -> str | None:
        low, high = self.speed_band(u_min, u_max)
        h_low, h_high = (x * 1e-6 for x in self.band_j_m)
        if v > high:
            return (
                f"{v:g} m/s is above the {high:.4g} m/s at which the heat input "
                f"k·U·I/v = {self.arc_power_w:g} W / v falls to "
                f"process.heat_input.target_kj_mm's low end {h_low:g} kJ/mm"
            )
        if v < low:
            return (
                f"{v:g} m/s is below the {low:.4g} m/s under which the heat input "
                f"k·U·I/v = {self.arc_power_w:g} W / v exceeds "
                f"process.heat_input.target_kj_mm's high end {h_high:g} kJ/mm"
            )
        return None
