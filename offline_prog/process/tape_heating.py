"""Tape laying: the tape's temperature at the nip from an energy balance of a moving
heated strip.

The heater (laser, hot gas, infrared) puts the power P [W] into the tape, of which the
tape absorbs the share η. The tape (width w, thickness h, density ρ, specific heat c)
runs through the heated zone at the TCP speed v, so its mass flow is ρ·w·h·v [kg/s] and
the steady energy balance gives the nip temperature

    T_nip = T_0 + η · P / (ρ · c · w · h · v)

(e.g. Stokes-Cleary, Grouve et al., "Thermal modelling of laser-assisted tape
placement", the lumped limit). Assumptions: the tape heats uniformly through its
thickness (thin tape: Biot number ≪ 1), no heat is lost between heater and nip (no
convection, no conduction into the substrate or the roller), the heater follows its
command at once, and c does not depend on T. The nip temperature is then an upper
bound; losses lower it.

To hold the target T*, the power follows the speed, P = ρ c w h v (T* − T_0) / η,
within [0, P_max]: at the heater's saturation the tape runs cold, and the speed
above which that happens is :meth:`TapeHeatingModel.speed_band`'s upper end.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.process import per_metre


@dataclasses.dataclass(frozen=True)
class TapeHeatingModel:
    """``process.tape_heating`` in SI units (temperatures in °C).

    Attributes:
        heat_capacity_j_k_m: ρ · c · w · h, the heat one metre of tape takes per kelvin
            [J/(K·m)].
        absorbed_fraction: η.
        ambient_c: T_0 [°C].
        band_c: [low, high] nip temperature [°C]; the target T* is its middle.
        max_power_w: P_max [W].
        w_per_unit: heater power per unit of the output [W].
    """

    heat_capacity_j_k_m: float
    absorbed_fraction: float
    ambient_c: float
    band_c: tuple[float, float]
    max_power_w: float
    w_per_unit: float

    column = "nip_temp_c"
    unit_scale = 1.0

    @property
    def band(self) -> tuple[float, float]:
        return self.band_c

    @property
    def target_c(self) -> float:
        return 0.5 * (self.band_c[0] + self.band_c[1])

    @property
    def per_mps(self) -> float:
        """The output's gain that holds T*: P / w_per_unit per m/s [unit per m/s]."""
        rise = self.target_c - self.ambient_c
        return self.heat_capacity_j_k_m * rise / (self.absorbed_fraction * self.w_per_unit)

    @property
    def max_command(self) -> float:
        """The output at the heater's full power [unit]."""
        return self.max_power_w / self.w_per_unit

    def predict(self, t: np.ndarray, v_tcp: np.ndarray, command: np.ndarray) -> np.ndarray:
        """(N,) nip temperature [°C] from the power output ``command`` (N,) [unit] at TCP
        speeds v_tcp (N,) [m/s]; NaN where the tape stands. ``t`` is unused."""
        power = np.clip(np.asarray(command, float) * self.w_per_unit, 0.0, self.max_power_w)
        heat = per_metre(self.absorbed_fraction * power, v_tcp)  # [J/m]
        return self.ambient_c + heat / self.heat_capacity_j_k_m

    def speed_band(self, u_min: float = 0.0, u_max: float | None = None) -> tuple[float, float]:
        """TCP speeds [m/s] at which the heater can reach the band's low end:
        v ≤ η P_max / (ρ c w h (T_low − T_0))."""
        rise = self.band_c[0] - self.ambient_c
        power = (
            self.max_power_w if u_max is None else min(u_max * self.w_per_unit, self.max_power_w)
        )
        return (0.0, self.absorbed_fraction * power / (self.heat_capacity_j_k_m * rise))
