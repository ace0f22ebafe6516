"""The process quality along a job: what the part gets on every row, and where it
leaves the band, with why.

The model (``process.registry.process_model``) predicts the quality from the planned TCP
speed and the output as the programs set it (the plan's analog column: for the bead the
flow command leading by the dispenser's lag, for the tape the heater's power). What is
dispensed is gated by the process output: the bead's flow and the heater's power reach
the part only while the digital output is on (where there is one), the torch's arc too.

The part gets material wherever the output is open: on a seam's ``process`` rows and
on its approach and retract (a switch led by ``on.lead_mm`` before the seam's start, or
off after its end). On these rows a row is *dispensing* when the output is on and
(bead, tape) its lagged flow or power is positive; elsewhere (links, the output off) the
quality column is NaN. The share within the band is weighted by the tool's path length
(trapezoid weights from ``path_m``, continuous from the approach through the seam to the
retract), over the dispensing length; ``process_length_m`` is the seam's alone. A row
where the tool stands (v below ``constants.STANDSTILL_SPEED_M_S``) while dispensing is out of
the band (the bead piles up, the weld overheats) and NaN in the column, unless the
output follows the speed to rest (the heater: no power, nothing dispensed).

Each stretch outside the band gets one cause, decided at its worst row i (the largest
excess over the band) in this order:

1. ``standstill``: v_i below the model's least defined speed;
2. ``output saturated``: the output the target needs at v_i, offset + gain · v_i, lies
   outside the output's [min, max] (for the tape: the heater's full power);
3. ``approach`` / ``retract``: i lies on the move onto or off the seam, gun open;
4. ``start ramp``: the seam starts from rest and i lies on its first rise: before the
   speed first reaches RAMP_SHARE of the seam's top speed or first falls; ``end ramp``:
   the seam ends at rest and i lies on its last fall (after the speed last was at the
   top or last rose);
5. ``lag`` (a bead with a lag): the speed changes where the lead cannot cancel the
   dispenser's first-order lag (a slowdown, a corner);
6. ``slowdown``: v_i below RAMP_SHARE of the seam's top speed (heat input, tape);
7. ``process speed``: at the seam's top speed and still outside: the set speed itself
   gives a quality off the band.

For the bead the share is also computed with compensation off: the same flow without
the lead (the flow set at the speed of the moment, live from where the output goes
on), through the same lag.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from offline_prog.constants import STANDSTILL_SPEED_M_S
from offline_prog.io_events import IoEvent, ProcessIo, Signal
from offline_prog.process.protocol import SATURATION_TOL, ProcessModel

RAMP_SHARE = 0.99  # of the seam's top speed: below it before the first / after the last time
MAX_STRETCHES = 200  # listed in the report per job (the count is always given)


@dataclasses.dataclass(frozen=True)
class Stretch:
    """A stretch of one seam outside the band: σ [m] and t [s] at its first and last
    row, the worst value (SI; inf at a standstill) and its cause (see the module)."""

    seam: str
    sigma_start_m: float
    sigma_end_m: float
    t_start_s: float
    t_end_s: float
    worst: float
    cause: str


@dataclasses.dataclass(frozen=True)
class QualitySummary:
    """min, max (SI, over the dispensing rows where the tool moves), the share of the
    dispensing length within the band (None: nothing dispensed), with compensation off
    (bead only), the lengths [m] and the stretches outside."""

    min: float | None
    max: float | None
    share_within_band: float | None
    share_within_band_uncompensated: float | None
    process_length_m: float
    dispensed_length_m: float
    stretches: list[Stretch]


@dataclasses.dataclass(frozen=True)
class ProcessQuality:
    """The quality along a job: ``values`` (N,) SI, NaN off the dispensing rows and at a
    standstill; the summary of the job and of each seam (by name, in run order); for
    the bead ``uncompensated`` (N,) the same with compensation off (else None)."""

    model: ProcessModel
    values: np.ndarray
    job: QualitySummary
    seams: dict[str, QualitySummary]
    uncompensated: np.ndarray | None = None

    @property
    def column(self) -> np.ndarray:
        """(N,) the values in the column's unit (trajectory.csv ``model.column``)."""
        return self.values * self.model.unit_scale

    def as_dict(self) -> dict:
        """report.json's ``quality`` (values in ``unit``; positions in m, times in s)."""
        model, scale = self.model, self.model.unit_scale
        low, high = model.band
        out = {
            "model": model.name,
            "column": model.column,
            "unit": model.unit,
            "band": [low * scale, high * scale],
            "target": model.target * scale,
            **_summary_dict(self.job, scale, stretches=True),
            "seams": {name: _summary_dict(s, scale) for name, s in self.seams.items()},
        }
        if not model.compares_uncompensated:
            del out["share_within_band_uncompensated"]
            for seam in out["seams"].values():
                del seam["share_within_band_uncompensated"]
        return out


def _summary_dict(summary: QualitySummary, scale: float, *, stretches: bool = False) -> dict:
    def shown(x):  # None: nothing dispensed, or a standstill (no finite value)
        return None if x is None or not np.isfinite(x) else x * scale

    out = {
        "min": shown(summary.min),
        "max": shown(summary.max),
        "share_within_band": summary.share_within_band,
        "share_within_band_uncompensated": summary.share_within_band_uncompensated,
        "process_length_m": summary.process_length_m,
        "dispensed_length_m": summary.dispensed_length_m,
        "n_stretches_outside": len(summary.stretches),
    }
    if stretches:
        out["stretches_outside"] = [
            {**dataclasses.asdict(s), "worst": shown(s.worst)}
            for s in summary.stretches[:MAX_STRETCHES]
        ]
    return out


def process_quality(
    model: ProcessModel,
    *,
    t: np.ndarray,
    v_tcp: np.ndarray,
    path_m: np.ndarray,
    segments,
    command: np.ndarray | None,
    digital: np.ndarray | None,
    settings: ProcessIo | None,
    events: list[IoEvent],
) -> ProcessQuality:
    """The quality on every row of a job, per job and per seam.

    Args:
        model: a process model (process.registry.process_model).
        t: (N,) job times [s]; v_tcp: (N,) TCP speed along the part [m/s];
            path_m: (N,) position along each seam's path [m] (job.assemble).
        segments: the job's segments (``kind``, ``seam``, ``start``, ``stop``).
        command: (N,) the speed-following output as the controller sets it (bead: the
            flow, tape: the heater's power; None for heat input).
        digital: (N,) 0/1 of the process output, or None (no switching).
        settings: the process I/O in SI units (the output's law and limits).
        events: the plan's I/O events (the flow's live windows, for compensation off).
    """
    t, v = np.asarray(t, float), np.asarray(v_tcp, float)
    seam_of, process_of, names = _seam_rows(segments, len(t))
    gate = np.ones(len(t), bool) if digital is None else np.asarray(digital) > 0
    values, dispensing = _values(model, t, v, command, gate & (seam_of >= 0), settings)
    weights = _row_weights(np.nan_to_num(np.asarray(path_m, float)), seam_of)
    low, high = model.band
    inside = dispensing & (values >= low) & (values <= high)
    uncompensated, off_shown = None, None
    if model.compares_uncompensated:
        u_off = _uncompensated_command(t, v, settings, events)
        off_values, off_dispensing = _values(model, t, v, u_off, gate & (seam_of >= 0), settings)
        off_inside = off_dispensing & (off_values >= low) & (off_values <= high)
        uncompensated = (off_inside, off_dispensing)
        off_shown = np.where(off_dispensing & np.isfinite(off_values), off_values, np.nan)
    causes = _cause_rows(model, v, process_of, len(names), settings)
    causes = _with_moves(causes, segments, len(t))
    stretches = _stretches(
        values, dispensing & ~inside, model.band, seam_of, names, t, path_m, causes
    )
    shown = np.where(dispensing & np.isfinite(values), values, np.nan)

    def summary(rows: np.ndarray, process: np.ndarray, seam: str | None = None):
        s = _summary(values, rows, dispensing, inside, uncompensated, weights)
        listed = [x for x in stretches if seam is None or x.seam == seam]
        return dataclasses.replace(
            s, stretches=listed, process_length_m=float(weights[process].sum())
        )

    seams = {name: summary(seam_of == k, process_of == k, name) for k, name in enumerate(names)}
    return ProcessQuality(model, shown, summary(seam_of >= 0, process_of >= 0), seams, off_shown)


def _seam_rows(segments, n: int) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(seam_of, process_of, names): per row the index of its seam among ``names`` (run
    order) on its approach, process and retract rows (seam_of) and on its process rows
    alone (process_of), −1 elsewhere (links)."""
    seam_of, process_of = np.full(n, -1), np.full(n, -1)
    names: list[str] = []
    for segment in segments:
        if segment.kind == "process":
            process_of[segment.start : segment.stop] = len(names)
            names.append(segment.seam)
    for segment in segments:
        if segment.kind in ("approach", "process", "retract"):
            seam_of[segment.start : segment.stop] = names.index(segment.seam)
    return seam_of, process_of, names


def _with_moves(causes: dict, segments, n: int) -> dict[str, np.ndarray]:
    """The causes with ``approach`` and ``retract`` (their rows) after the output's
    (see the module)."""
    moves = {kind: np.zeros(n, bool) for kind in ("approach", "retract")}
    for segment in segments:
        if segment.kind in moves:
            moves[segment.kind][segment.start : segment.stop] = True
    first = {key: causes[key] for key in ("standstill", "output saturated")}
    rest = {key: mask for key, mask in causes.items() if key not in first}
    return first | moves | rest


def _values(model: ProcessModel, t, v, command, on, settings) -> tuple[np.ndarray, np.ndarray]:
    """(N,) quality [SI] (inf at a standstill) and (N,) dispensing rows among ``on``.

    Below the least defined speed a row counts only if the output gives more than its
    law gives at that speed (the bead's lagged flow, the arc): the part then gets it
    without the tool moving. An output that follows the speed to rest (the heater)
    gives a vanishing amount there: not dispensing."""
    amount = model.delivered(t, command)
    values = model.predict(t, v, command)
    at_rest = model.delivered_at_rest(settings)
    slow = v < STANDSTILL_SPEED_M_S
    dispensing = on & (amount > 0) & ~(slow & (amount <= at_rest + SATURATION_TOL))
    values = np.where(dispensing & slow, np.inf, values)
    return values, dispensing


def _uncompensated_command(t, v, settings: ProcessIo, events: list[IoEvent]) -> np.ndarray:
    """(N,) the flow without the lead: flow(v(t)) while the output is live, each live
    window starting lag_s later, at the gate (the cut-off, at the valve's closing, is
    not led either way)."""
    live = np.zeros(len(t), bool)
    flow = [e for e in events if e.signal is Signal.ANALOG]
    for on, off in zip(flow[::2], flow[1::2], strict=True):
        live |= (t >= on.t_s + settings.lag_s) & (t < off.t_s)
    return np.where(live, settings.flow(v), settings.idle)


def _row_weights(path: np.ndarray, seam_of: np.ndarray) -> np.ndarray:
    """(N,) path length [m] each process row stands for: half of each neighbouring
    interval on the same seam (trapezoid rule)."""
    ds = np.abs(np.diff(path)) * ((seam_of[1:] == seam_of[:-1]) & (seam_of[1:] >= 0))
    return 0.5 * (np.append(ds, 0.0) + np.insert(ds, 0, 0.0))


def _cause_rows(model: ProcessModel, v, seam_of, n_seams, settings) -> dict[str, np.ndarray]:
    """Per row, the masks the causes are decided from (see the module)."""
    index = np.arange(len(v))
    on = seam_of >= 0
    seam = np.maximum(seam_of, 0)
    top = np.zeros(n_seams)
    np.maximum.at(top, seam_of[on], v[on])
    at_top = on & (v >= RAMP_SHARE * top[seam])
    first, last = np.full(n_seams, len(v)), np.full(n_seams, -1)
    np.minimum.at(first, seam_of[on], index[on])
    np.maximum.at(last, seam_of[on], index[on])
    # A ramp runs from rest (at the seam's end: to rest), before the speed first reaches
    # (after it last leaves) its top, as long as it rises (falls) monotonically.
    same = on[1:] & (seam_of[1:] == seam_of[:-1])
    falls, rises = same & (v[1:] < v[:-1]), same & (v[1:] > v[:-1])
    ramp_up_end = np.full(n_seams, len(v))
    ramp_down_start = np.full(n_seams, -1)
    np.minimum.at(ramp_up_end, seam_of[at_top], index[at_top])
    np.minimum.at(ramp_up_end, seam_of[:-1][falls], index[:-1][falls])
    np.maximum.at(ramp_down_start, seam_of[at_top], index[at_top])
    np.maximum.at(ramp_down_start, seam_of[1:][rises], index[1:][rises])
    at_rest = (1.0 - RAMP_SHARE) * top
    from_rest = v[np.minimum(first, len(v) - 1)] <= at_rest
    to_rest = v[np.maximum(last, 0)] <= at_rest
    return {
        "standstill": v < STANDSTILL_SPEED_M_S,
        "output saturated": model.saturated(v, settings),
        "start ramp": on & from_rest[seam] & (index < ramp_up_end[seam]),
        "end ramp": on & to_rest[seam] & (index > ramp_down_start[seam]),
        "lag": np.full(len(v), model.output_lag_s > 0),
        "slowdown": ~at_top,
        "process speed": np.ones(len(v), bool),
    }


def _stretches(values, outside, band, seam_of, names, t, path_m, causes) -> list[Stretch]:
    """The runs of ``outside`` rows on one seam, each with its worst row's cause."""
    key = np.where(outside, seam_of, -1)
    edge = np.diff(key) != 0
    starts = np.flatnonzero(outside & np.insert(edge, 0, True))
    lasts = np.flatnonzero(outside & np.append(edge, True))
    low, high = band
    excess = np.nan_to_num(np.abs(values - np.clip(values, low, high)), nan=np.inf)
    out = []
    for first, last in zip(starts, lasts, strict=True):  # per stretch, not per row
        worst = int(first + np.argmax(excess[first : last + 1]))
        cause = next(name for name, mask in causes.items() if mask[worst])
        out.append(
            Stretch(
                names[seam_of[first]],
                float(path_m[first]),
                float(path_m[last]),
                float(t[first]),
                float(t[last]),
                float(values[worst]),
                cause,
            )
        )
    return out


def _summary(values, rows, dispensing, inside, uncompensated, weights) -> QualitySummary:
    """The summary over ``rows`` (stretches filled in by the caller)."""
    on = rows & dispensing
    finite = values[on & np.isfinite(values)]
    dispensed = float(weights[on].sum())

    def share(inside_, on_):
        length = float(weights[on_].sum())
        return float(weights[on_ & inside_].sum() / length) if length > 0 else None

    off = None
    if uncompensated is not None:
        off_inside, off_dispensing = uncompensated
        off = share(off_inside, rows & off_dispensing)
    return QualitySummary(
        min=float(finite.min()) if finite.size else None,
        max=float(finite.max()) if finite.size else None,
        share_within_band=share(inside, on),
        share_within_band_uncompensated=off,
        process_length_m=float(weights[rows].sum()),
        dispensed_length_m=dispensed,
        stretches=[],
    )
