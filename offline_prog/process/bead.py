"""A sealant or adhesive bead: its cross-section from volume conservation.

The dispenser's flow Q [m³/s] follows its command u (the flow output, in the
controller's unit) through a first-order lag of time constant τ (``lag_s``):

    τ · y' + y = u,   Q = k · y            (k: ``flow_mm3_s_per_unit``)

and the bead laid at TCP speed v has the cross-section (volume conservation: what
leaves the nozzle in dt lies along v · dt of the path)

    A = Q / v.

To hold the target A*, the command follows the speed, u = A* · v / k, and leads it by
τ (the controllers' own lead: KRL ``ANOUT ... DELAY``, RAPID ``TriggSpeed``'s
ScaleLag): a lead by τ cancels the lag exactly wherever the speed changes linearly
and leaves an error that decays with τ where the acceleration changes; what it leaves
is bounded by the path jerk (``process.timing_bound``), which :meth:`BeadModel.jerk_cap`
caps on the process stretch.

The cell keys (``process.bead``) and their bounds: ``area_mm2`` (0, 1000] mm² (a
sealant or adhesive bead is 1–100 mm²), ``tolerance_pct`` (0, 100),
``flow_mm3_s_per_unit`` (0, 10⁶] mm³/s (a litre a second per unit), ``lag_s`` [0, 1] s
(beyond, the path triggers cannot lead it); the model needs ``tool.process_io.flow``
and sets its gain, offset and lead itself.
"""

# No ``from __future__ import annotations``: Drake's typed loader reads the keys'
# field types as written.
import dataclasses
import math
from typing import Self

import numpy as np

from offline_prog.errors import InputError
from offline_prog.process import per_metre
from offline_prog.process.key_bounds import at_most, positive
from offline_prog.process.lag import first_order_response
from offline_prog.process.protocol import SpeedFollowingModel, required_key

MAX_AREA_MM2 = 1000.0  # a round bead of 36 mm; sealant and adhesive beads are 1–100 mm²
MAX_FLOW_MM3_S_PER_UNIT = 1e6  # a litre a second per unit of the output
MAX_LAG_S = 1.0  # a dispenser's lag: beyond this the path triggers cannot lead it


@dataclasses.dataclass
class BeadConfig:
    """``process.bead``: the cell's keys."""

    area_mm2: float = required_key()  # target cross-section of the bead
    tolerance_pct: float = 5.0  # the band: target ± this share
    flow_mm3_s_per_unit: float = required_key()  # dispensed flow per unit of the output
    lag_s: float = 0.0  # the dispenser's first-order time constant


@dataclasses.dataclass(frozen=True)
class BeadModel(SpeedFollowingModel):
    """The bead of ``process.bead`` in SI units.

    Attributes:
        area_m2: target cross-section A* [m²].
        tolerance: the band's half-width as a share of A* (0.05 for 5 %).
        flow_m3_s_per_unit: dispensed flow per unit of the output k [m³/s].
        lag_s: the dispenser's time constant τ [s].
    """

    area_m2: float
    tolerance: float
    flow_m3_s_per_unit: float
    lag_s: float

    name = "bead"
    Keys = BeadConfig
    column = "bead_area_mm2"
    unit = "mm²"
    unit_scale = 1e6  # m² → mm²
    sets_flow = True  # the flow's gain, offset and lead are the bead's
    lag_key = "process.bead.lag_s"
    compares_uncompensated = True  # the share with the flow set at the speed of the moment
    flies_slowed = True  # at rest the flow's lag spoils the ends (+1800 % rows)

    @classmethod
    def check_keys(cls, file, keys: BeadConfig, flow) -> None:
        key = f"process.{cls.name}"
        for name in ("area_mm2", "tolerance_pct", "flow_mm3_s_per_unit"):
            positive(file, f"{key}.{name}", getattr(keys, name))
        if not (math.isfinite(keys.lag_s) and 0 <= keys.lag_s <= MAX_LAG_S):
            raise InputError(
                file, f"{key}.lag_s", f"must be within [0, {MAX_LAG_S:g}] s, got {keys.lag_s:g}"
            )
        if keys.tolerance_pct >= 100:
            raise InputError(file, f"{key}.tolerance_pct", "must be below 100")
        at_most(
            file,
            f"{key}.area_mm2",
            keys.area_mm2,
            MAX_AREA_MM2,
            "mm²",
            "sealant and adhesive beads are 1–100 mm² (is the unit mm²?)",
        )
        at_most(
            file,
            f"{key}.flow_mm3_s_per_unit",
            keys.flow_mm3_s_per_unit,
            MAX_FLOW_MM3_S_PER_UNIT,
            "mm³/s",
            "a litre a second per unit of the output is beyond any dispenser (is the unit mm³/s?)",
        )
        if flow is None:
            raise InputError(
                file, "tool.process_io.flow", "missing: process.model bead needs the flow output"
            )
        for name, value in (
            ("per_mps", flow.per_mps),
            ("lag_s", flow.lag_s),
            ("offset", flow.offset),
        ):
            if value not in (None, 0.0):
                raise InputError(
                    file,
                    f"tool.process_io.flow.{name}",
                    f"set by process.bead (the flow holds its area_mm2 with no offset, "
                    f"leading by its lag_s): remove {name}",
                )

    @classmethod
    def from_keys(cls, keys: BeadConfig) -> Self:
        return cls(
            area_m2=keys.area_mm2 * 1e-6,
            tolerance=keys.tolerance_pct / 100.0,
            flow_m3_s_per_unit=keys.flow_mm3_s_per_unit * 1e-9,
            lag_s=keys.lag_s,
        )

    @property
    def per_mps(self) -> float:
        """The output's gain that holds A*: u = A* · v / k [unit per m/s]."""
        return self.area_m2 / self.flow_m3_s_per_unit

    @property
    def band(self) -> tuple[float, float]:
        """[low, high] of the cross-section [m²]."""
        return (self.area_m2 * (1 - self.tolerance), self.area_m2 * (1 + self.tolerance))

    @property
    def target(self) -> float:
        """A* [m²]."""
        return self.area_m2

    @property
    def output_lag_s(self) -> float:
        return self.lag_s

    def speed_output(self) -> dict:
        """The flow's gain A*/k, no offset, leading by the dispenser's lag."""
        return {"per_mps": self.per_mps, "offset": 0.0, "lag_s": self.lag_s}

    def predict(self, t: np.ndarray, v_tcp: np.ndarray, command: np.ndarray) -> np.ndarray:
        """The bead's cross-section A [m²] at the samples.

        Args:
            t: (N,) times [s].
            v_tcp: (N,) TCP speed along the part [m/s].
            command: (N,) the flow output as the controller sets it (unit of the output).

        Returns:
            (N,) A = k · y / v [m²], NaN where the tool stands (v < 0.1 mm/s).
        """
        flow = self.flow_m3_s_per_unit * first_order_response(t, command, self.lag_s)
        return per_metre(flow, v_tcp)

    def speed_band(self, u_min: float, u_max: float) -> tuple[float, float]:
        """TCP speeds [m/s] at which the output within [u_min, u_max] can give A*:
        k · u_min / A* ≤ v ≤ k · u_max / A*."""
        k, area = self.flow_m3_s_per_unit, self.area_m2
        return (max(k * u_min / area, 0.0), k * u_max / area)

    def speed_band_reason(self, v: float, *, u_min: float, u_max: float) -> str | None:
        low, high = self.speed_band(u_min, u_max)
        what = f"process.bead.area_mm2 {self.area_m2 * 1e6:g} mm²"
        k = self.flow_m3_s_per_unit * 1e9
        if v > high:
            return (
                f"{v:g} m/s is above the {high:.4g} m/s at which the flow output at its max "
                f"{u_max:g} (tool.process_io.flow.max; {k:g} mm³/s per unit) lays {what}"
            )
        if v < low:
            return (
                f"{v:g} m/s is below the {low:.4g} m/s at which the flow output at its min "
                f"{u_min:g} (tool.process_io.flow.min) lays {what}: the bead is too large"
            )
        return None

    def jerk_cap(self, v_process: float) -> tuple[float, str | None]:
        """J_bead = 2·t·v_p/τ² [m/s³]: the path jerk at which the lead-compensated
        dispenser keeps the bead within its tolerance t at the speed v_p [m/s]
        (process.timing_bound); inf without a lag."""
        if self.lag_s**2 <= 0.0:  # no lag (or one so small its square underflows)
            return math.inf, None
        cap = 2.0 * self.tolerance * v_process / self.lag_s**2
        reason = (
            f"the dispenser's lag {self.lag_s:g} s holds the bead within "
            f"±{100 * self.tolerance:g} % at {v_process:g} m/s up to a path jerk of "
            f"2·tol·v/τ² = {cap:.4g} m/s³"
        )
        return cap, reason
