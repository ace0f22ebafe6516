"""Work-cell files: YAML loaded into typed dataclasses (Drake's typed YAML loader).

Transforms use Drake's schema form
``{translation: [x, y, z], rotation: !Rpy {deg: [r, p, y]}}``. Before the typed
load, the raw YAML is checked against the same dataclasses so that every error
names the file, the dotted key and the reason in one line.
"""

import dataclasses
import os
from pathlib import Path

from pydrake.common.schema import Transform
from pydrake.common.yaml import yaml_load_typed
from pydrake.math import RigidTransform

from offline_prog.config import safe_yaml
from offline_prog.config.cad_keys import CadSeamConfig
from offline_prog.config.calibration_keys import CalibrationConfig
from offline_prog.config.process_keys import ProcessConfig
from offline_prog.config.typed_check import check_mapping
from offline_prog.errors import InputError

REQUIRED = {"required": True}


def required():
    """A field that the cell file must give (the default only serves the loader)."""
    return dataclasses.field(default=None, metadata=REQUIRED)


FIT_TOLERANCE_MM = 0.1  # path.fit_tolerance_mm's default for measured points
CAD_FIT_TOLERANCE_MM = 0.01  # ... and for a cad: seam (an exact source)


@dataclasses.dataclass
class ShapeConfig:
    """A named collision/visual shape, posed in its owner's frame (I for obstacles,
    T for the tool, P for the part, E for the gripper). Sizes in mm (the keys say so)."""

    name: str = required()
    shape: str = required()  # box | cylinder | sphere | capsule | mesh
    size_mm: list[float] | None = None  # box: [x, y, z]
    radius_mm: float | None = None  # sphere, cylinder, capsule
    length_mm: float | None = None  # cylinder, capsule: along the shape's z
    mesh: str | None = None  # STL/OBJ/PLY/GLB, relative to the cell file
    mesh_units: str = "m"
    pose: Transform = dataclasses.field(default_factory=Transform)


@dataclasses.dataclass
class RobotConfig:
    model: str = required()  # folder name in robots/ (or robots_dir, OFFLINE_PROG_ROBOTS)
    robots_dir: str | None = None  # a folder of robot folders, relative to the cell file
    X_IB: Transform = dataclasses.field(default_factory=Transform, metadata=REQUIRED)


@dataclasses.dataclass
class DigitalSwitch:
    """Switch a digital output at a distance along the path: ``lead_mm`` before the
    seam's start (on) or before its end (off); negative: after. ``delay_s``: the valve's
    response time [s]: the output is set that much earlier, so the valve opens (closes)
    at the lead's position."""

    digital_output: int = required()
    lead_mm: float = 0.0
    delay_s: float = 0.0


@dataclasses.dataclass
class AnalogFlow:
    """An analog output following the TCP speed: value = offset + per_mps · v_TCP,
    clipped to [min, max] (the controller's unit, e.g. volts), while the digital output
    is on; at rest (offset clipped to [min, max]) otherwise. ``lag_s``: the dispenser's
    lag [s], by which the command leads the tool."""

    analog_output: int = required()
    per_mps: float | None = None  # required unless process.bead sets it (check_cell)
    offset: float = 0.0
    min: float = 0.0
    max: float = 10.0
    lag_s: float = 0.0
    # FANUC: the unit of AO[n]'s value as the I/O module takes it: volts, or counts
    # (the value in volts times counts_per_volt, a whole number).
    ao_unit: str = "volts"
    counts_per_volt: float | None = None


@dataclasses.dataclass
class ProcessIoConfig:
    on: DigitalSwitch | None = None
    off: DigitalSwitch | None = None
    flow: AnalogFlow | None = None


@dataclasses.dataclass
class ToolConfig:
    X_IT: Transform = dataclasses.field(default_factory=Transform, metadata=REQUIRED)
    name: str = "tool"
    # A tool symmetric about one of T's axes (nozzle, torch) may turn about it by up to
    # this angle to keep the robot inside its limits; y is the pressing direction n.
    free_rotation_deg: float = 0.0
    symmetry_axis: str = "y"
    # With a free rotation: the tool turns along the path so that the part turns
    # through bends smoothly, over about 4x this length (path.tool_turn); 0: fixed.
    turn_smoothing_mm: float = 0.0
    geometry: list[ShapeConfig] = dataclasses.field(default_factory=list)  # in T
    process_io: ProcessIoConfig | None = None  # the process output (glue gun, torch)
    # The controller's frame that holds T: KUKA BASE_DATA[n] (external TCP), FANUC UFRAME.
    controller_frame: int | None = None


@dataclasses.dataclass
class PartConfig:
    X_PE: Transform = dataclasses.field(default_factory=Transform, metadata=REQUIRED)
    name: str = "part"
    mesh: str | None = None  # STL/OBJ/PLY in P, relative to the cell file
    mesh_units: str = "m"  # of mesh, and of model when it is a mesh
    model: str | None = None  # STEP or STL/OBJ/PLY: seams (cad:), collision and visual
    geometry: list[ShapeConfig] = dataclasses.field(default_factory=list)  # in P
    mass_kg: float | None = None  # payload: the part's mass ...
    # ... its inertia [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] about its centre of mass, axes of P
    # (default: from its shapes, the mass spread evenly through them) ...
    inertia_kgm2: list[float] | None = None
    center_of_mass_mm: list[float] | None = None  # ... and its centre of mass in P
    # The controller's frame that holds P on the flange: KUKA TOOL_DATA[m], FANUC UTOOL.
    controller_frame: int | None = None


@dataclasses.dataclass
class GripperConfig:
    """The gripper on the flange that holds the part, everything in the flange frame E:
    its shapes and mesh (drawn and collision-checked with the robot) and its mass
    properties (the payload, with the part's). Centre of mass and inertia default to
    those of its shapes with the mass spread evenly through them."""

    mass_kg: float | None = None
    center_of_mass_mm: list[float] | None = None  # in E (default: the shapes', else E's origin)
    # [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] about the centre of mass, axes of E (default: the shapes')
    inertia_kgm2: list[float] | None = None
    mesh: str | None = None  # STL/OBJ/PLY/GLB in E, relative to the cell file ("gripper")
    mesh_units: str = "m"
    geometry: list[ShapeConfig] = dataclasses.field(default_factory=list)  # in E


GRIPPER_MESH_NAME = "gripper"  # the shape of gripper.mesh (as part.mesh is part.name)


@dataclasses.dataclass
class AnalyticPath:
    """A math curve in P, lengths in path.units: kind line | arc | rounded_rectangle."""

    kind: str = required()
    start: list[float] | None = None  # line
    end: list[float] | None = None  # line
    center: list[float] | None = None  # arc, rounded_rectangle
    radius: float | None = None  # arc
    start_deg: float | None = None  # arc
    end_deg: float | None = None  # arc
    size: list[float] | None = None  # rounded_rectangle [width, height]
    corner_radius: float | None = None  # rounded_rectangle


@dataclasses.dataclass
class PathConfig:
    units: str | None = None  # m | mm; required except for cad: (config.cad_keys)
    # A closed contour (periodic spline; its ends: path.closing). Not given: true for a
    # cad: loop, false otherwise (load_cell decides, so a cell reads the same checked or
    # not); false on a cad: loop is refused (config.cad_keys).
    closed: bool | None = None
    points: str | None = None  # CSV x,y,z[,nx,ny,nz], relative to the cell file
    dxf: str | None = None
    dxf_layer: str | None = None
    dxf_entity: int | None = None  # which path entity (0-based) when the DXF has several
    csv_seam: str | None = None  # rows of this seam (CSV seam column); seams: its name
    analytic: AnalyticPath | None = None
    cad: CadSeamConfig | None = None  # edges and faces of part.model (config.cad_keys)
    normal: list[float] | None = None  # constant surface normal in P (into the surface)
    normal_from_mesh: bool = False  # normals from part.mesh
    degree: int = 5
    # Max point-to-curve distance. Not given: 0.1 mm (load_cell decides); for a cad:
    # seam 0.01 mm (its source is exact) unless it has sharp corners, which the fit
    # rounds (path.inputs.load_points decides, knowing the corners).
    fit_tolerance_mm: float | None = None
    normal_tolerance_deg: float = 2.0  # max angle, given (CSV) to fitted normal
    n_control_points: int | None = None
    # A closed seam's bead runs past its start by this much before the gun closes [mm]
    # (the path runs on over its first overlap_mm); refused on an open seam.
    overlap_mm: float = 0.0
    # flying | rest. flying (the default): the tool reaches the seam's start already at
    # the process speed and leaves its end at it (a lead-in and lead-out along the
    # seam's tangent, lifting off the part, timed with the seam: path.lead). A lead
    # that cannot be run (out of reach, a joint limit, a collision, speed_reference
    # flange) falls back to rest; report.json names the entry and why. rest: the seam
    # starts and ends at rest (a cusp at its end, a process that must start standing).
    entry: str = "flying"


@dataclasses.dataclass
class ApproachConfig:
    """How the tool meets (approach) or leaves (retract) a seam: a straight line in P
    along −n (``normal``: off the surface) or −t (``tangent``: along the path, before
    its start / after its end) of the process frame F at the seam's end, or ``none``."""

    kind: str = "normal"  # normal | tangent | none
    distance_mm: float = 50.0

    @property
    def normal_m(self) -> float:
        """The move's distance off the surface [m]: a flying seam's lead may take it over
        (timing.lead_length); 0 for a tangent move or none."""
        return self.distance_mm * 1e-3 if self.kind == "normal" else 0.0

    @property
    def tangent_m(self) -> float:
        """The move's distance along the seam's tangent [m]: a flying seam's lead may
        take it over (timing.lead_length); 0 for a normal move or none."""
        return self.distance_mm * 1e-3 if self.kind == "tangent" else 0.0


def seam_moves_m(approach: ApproachConfig, retract: ApproachConfig) -> dict[str, tuple]:
    """A seam's ``stages.Inputs.normal_moves_m`` and ``tangent_moves_m`` [m], (approach,
    retract) each, as keyword arguments: the moves its leads may take over."""
    return {
        "normal_moves_m": (approach.normal_m, retract.normal_m),
        "tangent_moves_m": (approach.tangent_m, retract.tangent_m),
    }


@dataclasses.dataclass
class SeamConfig(PathConfig):
    """One seam of a job: a processing path (every key of ``path:``) plus its name,
    direction, an optional own speed and how the tool meets and leaves it."""

    name: str = required()  # unique; in reports, programs and trajectory.csv
    direction: str = "forward"  # forward | reverse | auto (the planner picks)
    speed: float | None = None  # m/s, overrides motion.speed for this seam
    approach: ApproachConfig = dataclasses.field(default_factory=ApproachConfig)
    retract: ApproachConfig = dataclasses.field(default_factory=ApproachConfig)


@dataclasses.dataclass
class HomeConfig:
    joints_deg: list[float] = required()  # the controller's axes [deg]


@dataclasses.dataclass
class JobConfig:
    """The job around the seams: where the robot starts and ends, and the seam order."""

    home: HomeConfig | None = None  # default: the robot's home_deg (robot.yaml)
    order: str = "given"  # given | auto (order, direction, branch for the least air time)
    link_time_s: float = 10.0  # planning time per link before the plan fails [s]


@dataclasses.dataclass
class MotionConfig:
    speed: float = required()  # m/s of the time-law parameter (at the TCP by default)
    max_acceleration: float = required()  # m/s²
    max_jerk: float = required()  # m/s³
    speed_reference: str = "tcp"  # tcp | flange
    # time_optimal (TOPP-RA + jerk stage, the default) | sin2 (the paper's law); Drake's
    # loader reads a string, check_cell turns it into constants.TimeLaw.
    time_law: str = "time_optimal"
    # constant_speed | cycle_time (time_optimal only); check_cell: constants.ProcessIntent
    process: str = "constant_speed"
    sample_rate_hz: float = 250.0
    cusp_smoothing_mm: float | None = None  # re-fit the flange path within this deviation
    clearance: float = 0.005  # m: robot and part vs obstacles, the tool and each other
    self_clearance: float = 0.005  # m: robot link vs robot link (pairs of class "check")
    # m/s of the tool along the part on approach and retract (None: the seam's process
    # speed; config.process_speed.approach_speed decides)
    approach_speed: float | None = None
    link_speed_percent: float = 100.0  # % of the joints' speed limits on links (PTP)
    # mm of a flying seam's lead-in and lead-out (path.entry: flying). None: what the
    # process speed needs under the seam's caps (its ramp from rest, half as much again,
    # plus the I/O switches' leads and the dispenser's lag run at that speed); 0: every
    # seam starts and ends at rest.
    lead_mm: float | None = None


@dataclasses.dataclass
class TranslationRanges:
    """Search ranges of a translation [mm], per axis of the frame it is expressed in;
    an axis not named keeps the cell's value."""

    x: list[float] | None = None  # [low, high] mm
    y: list[float] | None = None
    z: list[float] | None = None


@dataclasses.dataclass
class RpyRanges:
    """Search ranges of roll, pitch, yaw [deg]; an angle not named keeps the cell's."""

    roll: list[float] | None = None  # [low, high] deg
    pitch: list[float] | None = None
    yaw: list[float] | None = None


@dataclasses.dataclass
class PoseRanges:
    translation_mm: TranslationRanges = dataclasses.field(default_factory=TranslationRanges)
    rpy_deg: RpyRanges = dataclasses.field(default_factory=RpyRanges)


@dataclasses.dataclass
class GraspRanges(PoseRanges):
    """Grasps X_PE to choose from (default: part.X_PE alone), each searched within
    the ranges (applied to every candidate)."""

    candidates: list[Transform] = dataclasses.field(default_factory=list)


@dataclasses.dataclass
class PlaceConfig:
    """``place:``, the search space of ``offline-prog place`` (issue 16's contract:
    X_IT.translation_mm, X_IT.rpy_deg, X_PE.candidates, budget, seed)."""

    X_IT: PoseRanges = dataclasses.field(default_factory=PoseRanges)
    X_PE: GraspRanges | None = None
    budget: int = 16  # candidates planned in full (the planning pipeline minus the exports)
    seed: int = 0
    screen_points: int = 1000  # grid points screened by the analytic path IK, per grasp
    top_k: int = 10  # candidates listed in placement.json
    # Obstacles that stand with the tool (its stand): moved with X_IT, their foot kept
    # on the floor by their length (placement.stand), up to stand_max_length_mm.
    moves_with_tool: list[str] = dataclasses.field(default_factory=list)
    stand_max_length_mm: float = 2000.0


@dataclasses.dataclass
class Cell:
    robot: RobotConfig = dataclasses.field(default_factory=RobotConfig, metadata=REQUIRED)
    tool: ToolConfig = dataclasses.field(default_factory=ToolConfig, metadata=REQUIRED)
    part: PartConfig = dataclasses.field(default_factory=PartConfig, metadata=REQUIRED)
    # One of: path (one seam, the shorthand) or seams (a job of several).
    path: PathConfig | None = None
    seams: list[SeamConfig] = dataclasses.field(default_factory=list)
    # The job around the seams (home, order). A path: cell with job: is a one-seam job.
    job: JobConfig | None = None
    motion: MotionConfig = dataclasses.field(default_factory=MotionConfig, metadata=REQUIRED)
    name: str = ""
    description: str = ""
    gripper: GripperConfig | None = None
    obstacles: list[ShapeConfig] = dataclasses.field(default_factory=list)  # in I
    # Pairs of shape names whose contact is intended (the tool tip on the part).
    allowed_contact: list[list[str]] = dataclasses.field(default_factory=list)
    # Where the tool and grasp may go (offline-prog place); plan ignores it.
    place: PlaceConfig | None = None
    # What the part gets along the path: bead, heat input or tape temperature.
    process: ProcessConfig | None = None
    # What the touches of offline-prog calibrate refer to; plan ignores it.
    calibration: CalibrationConfig | None = None


def load_cell(file: str | os.PathLike) -> Cell:
    """Load and check a cell file.

    Raises:
        InputError: with a one-line message naming the file, key and reason.
    """
    file = Path(file)
    text = safe_yaml.read_text(file)  # size, encoding
    raw = safe_yaml.load(file, text)  # aliases, depth, duplicate keys
    check_mapping(file, "", raw, Cell)
    try:
        # Drake's loader reads YAML 1.1 (on, off, yes, no are booleans): it gets the
        # data our YAML 1.2 loader read, written out by Drake's own dumper.
        cell = yaml_load_typed(schema=Cell, data=safe_yaml.drake_text(raw))
    except Exception as error:  # Drake's message is multi-line; keep its first line.
        first_line = (str(error).strip().splitlines() or [type(error).__name__])[0]
        raise InputError(file, "", first_line) from None
    for seam in ([cell.path] if cell.path is not None else []) + cell.seams:
        if seam.closed is None:  # not given: a loop comes back to its start
            seam.closed = seam.cad is not None and seam.cad.loop is not None
        if seam.fit_tolerance_mm is None and seam.cad is None:  # a cad: seam's: its points'
            seam.fit_tolerance_mm = FIT_TOLERANCE_MM
    return cell


def transform(value: Transform) -> RigidTransform:
    """The RigidTransform of a schema Transform (deterministic only)."""
    return value.GetDeterministicValue()
