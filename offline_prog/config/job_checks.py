"""Semantic checks of a job's keys (``seams:``, ``job:``, ``tool.process_io``) that
their types alone cannot express; every failure is an InputError naming the file and key.
"""

from __future__ import annotations

from pathlib import Path

from offline_prog.config.cell import Cell, JobConfig, SeamConfig
from offline_prog.config.names import name_pattern
from offline_prog.constants import MAX_SPEED_M_S
from offline_prog.errors import InputError
from offline_prog.process.registry import MODELS

DIRECTIONS = ("forward", "reverse", "auto")
APPROACH_KINDS = ("normal", "tangent", "none")
MAX_APPROACH_MM = 1000.0  # approach, retract and I/O lead distances
MAX_LINK_TIME_S = 600.0  # planning time per link
MAX_FLOW_LAG_S = 1.0  # a dispenser's lag: beyond this the path triggers cannot lead it
MAX_VALVE_DELAY_S = 1.0  # a valve's response time (on.delay_s, off.delay_s)
MAX_SEAM_NAME_CHARS = 20  # KRL names are at most 24 characters; we add a prefix
SEAM_NAME = name_pattern(MAX_SEAM_NAME_CHARS)


def _error(file, key, reason) -> InputError:
    return InputError(file, key, reason)


def check_job(file: Path, cell: Cell) -> None:
    """Seam names unique and safe in a controller program; directions, speeds,
    approach and retract; job order; process I/O numbers and ranges."""
    names: set[str] = set()
    for k, seam in enumerate(cell.seams):
        key = f"seams[{k}]"
        if not SEAM_NAME.fullmatch(seam.name):
            raise _error(
                file,
                f"{key}.name",
                f"{seam.name!r} is not a seam name (letters, digits and _, starting "
                f"with a letter, at most {MAX_SEAM_NAME_CHARS} characters: it names "
                "labels in controller programs)",
            )
        if seam.name.lower() in names:
            raise _error(file, f"{key}.name", f"{seam.name!r} is used twice")
        names.add(seam.name.lower())
        if seam.direction not in DIRECTIONS:
            raise _error(
                file, f"{key}.direction", f"{seam.direction!r} (use {', '.join(DIRECTIONS)})"
            )
        if seam.speed is not None and not 0 < seam.speed <= MAX_SPEED_M_S:
            raise _error(file, f"{key}.speed", f"must be within (0, {MAX_SPEED_M_S:g}] m/s")
        for end in ("approach", "retract"):
            move = getattr(seam, end)
            if move.kind not in APPROACH_KINDS:
                raise _error(
                    file, f"{key}.{end}.kind", f"{move.kind!r} (use {', '.join(APPROACH_KINDS)})"
                )
            if not 0 <= move.distance_mm <= MAX_APPROACH_MM:
                raise _error(
                    file,
                    f"{key}.{end}.distance_mm",
                    f"must be within [0, {MAX_APPROACH_MM:g}] mm, got {move.distance_mm:g}",
                )
    _check_overlaps(file, cell)
    job = cell.job or JobConfig()
    if job.order not in ("given", "auto"):
        raise _error(file, "job.order", f"{job.order!r} (use given or auto)")
    if not 0 < job.link_time_s <= MAX_LINK_TIME_S:
        raise _error(file, "job.link_time_s", f"must be within (0, {MAX_LINK_TIME_S:g}] s")
    if job.home is not None and len(job.home.joints_deg) != 6:
        raise _error(file, "job.home.joints_deg", "expected 6 joint values [deg]")
    io = cell.tool.process_io
    if io is not None:
        for name in ("on", "off"):
            switch = getattr(io, name)
            if switch is not None and abs(switch.lead_mm) > MAX_APPROACH_MM:
                raise _error(
                    file,
                    f"tool.process_io.{name}.lead_mm",
                    f"must be within ±{MAX_APPROACH_MM:g} mm",
                )
            if switch is not None and not 0 <= switch.delay_s <= MAX_VALVE_DELAY_S:
                raise _error(
                    file,
                    f"tool.process_io.{name}.delay_s",
                    f"must be within [0, {MAX_VALVE_DELAY_S:g}] s (the valve's response "
                    f"time), got {switch.delay_s:g}",
                )
        _check_leads(file, cell, io)
        if (io.on is None) != (io.off is None):
            raise _error(file, "tool.process_io", "give both on and off (or neither)")
        if io.on is not None and io.on.digital_output != io.off.digital_output:
            raise _error(file, "tool.process_io.off.digital_output", "must equal on's")
        if io.flow is not None and not io.flow.min < io.flow.max:
            raise _error(file, "tool.process_io.flow", "needs min < max")
        model = None if cell.process is None else MODELS.get(cell.process.model)
        if io.flow is not None and io.flow.per_mps is None and not (model and model.sets_flow):
            setters = " or ".join(f"process.{name}" for name, m in MODELS.items() if m.sets_flow)
            raise _error(
                file,
                "tool.process_io.flow.per_mps",
                f"missing: the flow's V per m/s (or a {setters} model that sets it)",
            )
        if io.flow is not None and io.flow.per_mps is not None and not io.flow.per_mps > 0:
            raise _error(
                file,
                "tool.process_io.flow.per_mps",
                f"must be > 0 V per m/s (the flow rises with the speed), got {io.flow.per_mps:g}",
            )
        if io.flow is not None:
            _check_ao_unit(file, io.flow)
        if io.flow is not None and not 0 <= io.flow.lag_s <= MAX_FLOW_LAG_S:
            raise _error(
                file,
                "tool.process_io.flow.lag_s",
                f"must be within [0, {MAX_FLOW_LAG_S:g}] s, got {io.flow.lag_s:g}",
            )


AO_UNITS = ("volts", "counts")  # tool.process_io.flow.ao_unit


def _check_ao_unit(file: Path, flow) -> None:
    """``flow.ao_unit`` one of AO_UNITS; ``counts_per_volt`` > 0 with counts, absent
    with volts (a number that would change nothing is refused, not ignored)."""
    key = "tool.process_io.flow"
    if flow.ao_unit not in AO_UNITS:
        raise _error(file, f"{key}.ao_unit", f"{flow.ao_unit!r} (use volts or counts)")
    per_volt = flow.counts_per_volt
    if flow.ao_unit == "counts" and not (per_volt is not None and per_volt > 0):
        raise _error(file, f"{key}.counts_per_volt", "must be > 0 counts per V with counts")
    if flow.ao_unit == "volts" and per_volt is not None:
        raise _error(file, f"{key}.counts_per_volt", "only with ao_unit: counts")


# The process outputs each controller family can have (its own numbering):
# KUKA KSS 8: $OUT[1..4096], $ANOUT[1..32]; UR e-Series: standard digital out 0..7,
# standard analog out 0..1; ABB: signals named do<n> / ao<n> in the I/O configuration;
# FANUC: DO[n], AO[n], logical numbers from 1 (the I/O assignment maps them onto racks
# and slots; DO[0] and AO[0] do not exist), the upper end set by that assignment.
IO_PARTS = ("on", "off", "flow")  # tool.process_io's outputs
OUTPUT_RANGES = {
    "krl": {"digital_output": (1, 4096), "analog_output": (1, 32)},
    "urscript": {"digital_output": (0, 7), "analog_output": (0, 1)},
    "rapid": {"digital_output": (1, 9999), "analog_output": (1, 9999)},
    "fanuc": {"digital_output": (1, 9999), "analog_output": (1, 9999)},
}


def _check_overlaps(file: Path, cell: Cell) -> None:
    """``overlap_mm`` only on a closed seam, within [0, MAX_APPROACH_MM]."""
    specs = [(f"seams[{k}]", seam) for k, seam in enumerate(cell.seams)]
    if cell.path is not None:
        specs.append(("path", cell.path))
    for key, spec in specs:
        if spec.overlap_mm == 0.0:
            continue
        if not 0 < spec.overlap_mm <= MAX_APPROACH_MM:
            raise _error(
                file,
                f"{key}.overlap_mm",
                f"must be within [0, {MAX_APPROACH_MM:g}] mm, got {spec.overlap_mm:g}",
            )
        if not spec.closed:
            raise _error(
                file,
                f"{key}.overlap_mm",
                "an open seam has no start to overlap (only a closed seam's bead runs past "
                "its start)",
            )


def _check_leads(file: Path, cell: Cell, io) -> None:
    """An output switched on ``lead_mm`` before a seam's start lies on its approach (a
    negative lead: on the seam); one switched off before the end, on the seam or (a
    negative lead) on the retract. What depends on the seam's length is checked when it
    is planned."""
    for seam in cell.seams or [SeamConfig(name="seam")]:  # path: has the default moves
        name = f"seam {seam.name}"
        room_on = seam.approach.distance_mm * (seam.approach.kind != "none")
        room_off = seam.retract.distance_mm * (seam.retract.kind != "none")
        if io.on is not None and io.on.lead_mm > room_on:
            raise _error(
                file,
                "tool.process_io.on.lead_mm",
                f"{io.on.lead_mm:g} mm before the start of {name} is beyond its approach "
                f"({room_on:g} mm)",
            )
        if io.off is not None and -io.off.lead_mm > room_off:
            raise _error(
                file,
                "tool.process_io.off.lead_mm",
                f"{-io.off.lead_mm:g} mm after the end of {name} is beyond its retract "
                f"({room_off:g} mm)",
            )


def check_process_io(file: Path, cell: Cell, language: str | None) -> None:
    """The process output numbers exist on the robot's controller (``OUTPUT_RANGES``):
    ``tool.process_io``'s and those the process model's keys name (the tape heater's
    ``power_output``)."""
    io = cell.tool.process_io
    outputs = [] if io is None else [(f"tool.process_io.{n}", getattr(io, n)) for n in IO_PARTS]
    if cell.process is not None:
        model = MODELS[cell.process.model]
        outputs += model.controller_outputs(getattr(cell.process, model.name))
    ranges = OUTPUT_RANGES.get(language, {"digital_output": (0, 9999), "analog_output": (0, 9999)})
    for key, part in outputs:
        if part is None:
            continue
        kind = "digital_output" if hasattr(part, "digital_output") else "analog_output"
        low, high = ranges[kind]
        number = getattr(part, kind)
        if not low <= number <= high:
            raise _error(
                file,
                f"{key}.{kind}",
                f"{number} is not an output of the robot's {language or 'controller'} "
                f"controller (use {low}..{high})",
            )
