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

The cell keys (``process.tape_heating``) and their bounds: ``width_mm`` (0, 1000] mm
(tapes are 3–300 mm wide), ``thickness_mm`` (0, 5] mm (the model's thin tape: tapes
are 0.1–0.3 mm), ``density_kg_m3`` [100, 22600] kg/m³ (osmium, the densest element, is
22,590; below 100 the unit is likely g/cm³), ``specific_heat_j_kg_k``
[100, 15000] J/(kg·K) (no solid is below about 110, lead's 129; hydrogen's 14,300 is
the highest of any substance; below 100 the unit is likely kJ/(kg·K)),
``absorbed_fraction`` (0, 1], ``ambient_c`` from absolute zero, −273.15 °C,
``target_c`` a band above ``ambient_c`` up to 1000 °C (thermoplastic tapes are laid at
200–450 °C; every polymer matrix has burnt long before), ``max_power_w`` (0, 100] kW
(tape-laying heaters are 1–12 kW), ``power_output.w_per_unit`` (0, 100] kW.
"""

# No ``from __future__ import annotations``: Drake's typed loader reads the keys'
# field types as written.
import dataclasses
from typing import Self

import numpy as np

from offline_prog.errors import InputError
from offline_prog.process import per_metre
from offline_prog.process.key_bounds import at_least, at_most, band, positive
from offline_prog.process.protocol import SpeedFollowingModel, required_key

ABSOLUTE_ZERO_C = -273.15
# (low, high, unit, why) of each key with physical bounds beyond being positive.
BOUNDS = {
    "width_mm": (None, 1000.0, "mm", "tapes are 3–300 mm wide (is the unit mm?)"),
    "thickness_mm": (
        None,
        5.0,
        "mm",
        "the model heats a thin tape through its thickness; tapes are 0.1–0.3 mm (is the unit mm?)",
    ),
    "density_kg_m3": (
        100.0,
        22600.0,
        "kg/m³",
        "osmium, the densest element, is 22,590 kg/m³; a tape is 900–2,000 "
        "(is the unit kg/m³? 1.55 g/cm³ is 1550 kg/m³)",
    ),
    "specific_heat_j_kg_k": (
        100.0,
        15000.0,
        "J/(kg·K)",
        "no solid is below about 110 J/(kg·K) (lead: 129) and no substance above "
        "hydrogen's 14,300 (is the unit J/(kg·K)? 1.2 kJ/(kg·K) is 1200)",
    ),
    "max_power_w": (None, 1e5, "W", "tape-laying heaters are 1–12 kW (is the unit W?)"),
}
MAX_TARGET_C = 1000.0  # thermoplastic tapes are laid at 200–450 °C
MAX_W_PER_UNIT = 1e5  # [W] per unit of the output: no tape heater is larger


@dataclasses.dataclass
class PowerOutput:
    analog_output: int = required_key()  # the heater's power command on the controller
    w_per_unit: float = required_key()  # heater power per unit of the output [W]


@dataclasses.dataclass
class TapeHeatingConfig:
    """``process.tape_heating``: the cell's keys."""

    width_mm: float = required_key()
    thickness_mm: float = required_key()
    density_kg_m3: float = required_key()
    specific_heat_j_kg_k: float = required_key()
    absorbed_fraction: float = required_key()  # share of the heater power the tape takes up
    ambient_c: float = 20.0  # the tape's temperature before the heater
    target_c: list[float] = required_key()  # nip temperature band [low, high]
    max_power_w: float = required_key()
    power_output: PowerOutput = dataclasses.field(
        default_factory=PowerOutput, metadata={"required": True}
    )


@dataclasses.dataclass(frozen=True)
class TapeHeatingModel(SpeedFollowingModel):
    """``process.tape_heating`` in SI units (temperatures in °C).

    Attributes:
        heat_capacity_j_k_m: ρ · c · w · h, the heat one metre of tape takes per kelvin
            [J/(K·m)].
        absorbed_fraction: η.
        ambient_c: T_0 [°C].
        band_c: [low, high] nip temperature [°C]; the target T* is its middle.
        max_power_w: P_max [W].
        w_per_unit: heater power per unit of the output [W].
        analog_output: the heater's power output on the controller (None: not named).
    """

    heat_capacity_j_k_m: float
    absorbed_fraction: float
    ambient_c: float
    band_c: tuple[float, float]
    max_power_w: float
    w_per_unit: float
    analog_output: int | None = None

    name = "tape_heating"
    Keys = TapeHeatingConfig
    column = "nip_temp_c"
    unit = "°C"
    unit_scale = 1.0

    @classmethod
    def check_keys(cls, file, keys: TapeHeatingConfig, flow) -> None:
        key = f"process.{cls.name}"
        for name in (
            "width_mm",
            "thickness_mm",
            "density_kg_m3",
            "specific_heat_j_kg_k",
            "absorbed_fraction",
            "max_power_w",
        ):
            positive(file, f"{key}.{name}", getattr(keys, name))
        if keys.absorbed_fraction > 1:
            raise InputError(
                file,
                f"{key}.absorbed_fraction",
                f"must be at most 1, got {keys.absorbed_fraction:g}",
            )
        for name, (low, high, unit, why) in BOUNDS.items():
            if low is not None:
                at_least(file, f"{key}.{name}", getattr(keys, name), low, unit, why)
            at_most(file, f"{key}.{name}", getattr(keys, name), high, unit, why)
        at_least(
            file,
            f"{key}.ambient_c",
            keys.ambient_c,
            ABSOLUTE_ZERO_C,
            "°C",
            "nothing is colder than absolute zero",
        )
        band(file, f"{key}.target_c", keys.target_c, positive=False)
        if not keys.target_c[0] > keys.ambient_c:
            raise InputError(
                file, f"{key}.target_c", f"must lie above ambient_c {keys.ambient_c:g} °C"
            )
        at_most(
            file,
            f"{key}.target_c",
            keys.target_c[1],
            MAX_TARGET_C,
            "°C",
            "thermoplastic tapes are laid at 200–450 °C; every polymer matrix has burnt "
            "long before 1000 °C",
        )
        output = keys.power_output
        if output is None or output.analog_output is None:
            raise InputError(file, f"{key}.power_output", "missing: the heater's power output")
        positive(file, f"{key}.power_output.w_per_unit", output.w_per_unit)
        at_most(
            file,
            f"{key}.power_output.w_per_unit",
            output.w_per_unit,
            MAX_W_PER_UNIT,
            "W",
            "no tape heater gives 100 kW per unit of its output (is the unit W?)",
        )
        if flow is not None:
            raise InputError(
                file,
                "tool.process_io.flow",
                "process.model tape_heating drives the heater's power_output along the "
                "speed: a tape cell has no flow output",
            )

    @classmethod
    def from_keys(cls, keys: TapeHeatingConfig) -> Self:
        capacity = (
            keys.density_kg_m3
            * keys.specific_heat_j_kg_k
            * keys.width_mm
            * 1e-3
            * keys.thickness_mm
            * 1e-3
        )
        return cls(
            heat_capacity_j_k_m=capacity,
            absorbed_fraction=keys.absorbed_fraction,
            ambient_c=keys.ambient_c,
            band_c=(keys.target_c[0], keys.target_c[1]),
            max_power_w=keys.max_power_w,
            w_per_unit=keys.power_output.w_per_unit,
            analog_output=keys.power_output.analog_output,
        )

    @classmethod
    def controller_outputs(cls, keys: TapeHeatingConfig) -> list[tuple[str, object]]:
        """The heater's power output."""
        return [(f"process.{cls.name}.power_output", keys.power_output)]

    @property
    def band(self) -> tuple[float, float]:
        return self.band_c

    @property
    def target_c(self) -> float:
        return 0.5 * (self.band_c[0] + self.band_c[1])

    def speed_output(self) -> dict:
        """The heater's power output: gain ρcwh(T*−T_0)/(η·W per unit), within
        [0, P_max], following at once."""
        return {
            "analog_output": self.analog_output,
            "per_mps": self.per_mps,
            "offset": 0.0,
            "min": 0.0,
            "max": self.max_command,
            "lag_s": 0.0,
        }

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

    def speed_band_reason(
        self, v: float, *, u_min: float = 0.0, u_max: float | None = None
    ) -> str | None:
        high = self.speed_band(u_min, u_max)[1]
        if v > high:
            return (
                f"{v:g} m/s is above the {high:.4g} m/s at which the heater "
                f"(process.tape_heating.max_power_w {self.max_power_w:g} W) reaches "
                f"target_c's low end {self.band_c[0]:g} °C"
            )
        return None
