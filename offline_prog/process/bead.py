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
and leaves an error that decays with τ where the acceleration changes.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.process import per_metre
from offline_prog.process.lag import first_order_response


@dataclasses.dataclass(frozen=True)
class BeadModel:
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

    column = "bead_area_mm2"
    unit_scale = 1e6  # m² → mm²

    @property
    def per_mps(self) -> float:
        """The output's gain that holds A*: u = A* · v / k [unit per m/s]."""
        return self.area_m2 / self.flow_m3_s_per_unit

    @property
    def band(self) -> tuple[float, float]:
        """[low, high] of the cross-section [m²]."""
        return (self.area_m2 * (1 - self.tolerance), self.area_m2 * (1 + self.tolerance))

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
