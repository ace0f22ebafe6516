"""Work-cell files: YAML loaded into typed dataclasses (Drake's typed YAML loader).

Transforms use Drake's schema form
``{translation: [x, y, z], rotation: !Rpy {deg: [r, p, y]}}``. Before the typed
load, the raw YAML is checked against the same dataclasses so that every error
names the file, the dotted key and the reason in one line.
"""

import dataclasses
import math
import os
import types
import typing
from pathlib import Path

from pydrake.common.schema import Transform
from pydrake.common.yaml import yaml_load_typed
from pydrake.math import RigidTransform

from offline_prog.config import safe_yaml
from offline_prog.config.safe_yaml import short_repr
from offline_prog.errors import InputError

REQUIRED = {"required": True}


def required():
    """A field that the cell file must give (the default only serves the loader)."""
    return dataclasses.field(default=None, metadata=REQUIRED)


@dataclasses.dataclass
class ShapeConfig:
    """A named collision/visual shape, posed in its owner's frame (I for obstacles,
    T for the tool, P for the part). Sizes in mm (the keys say so)."""

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
    model: str = required()  # folder name in robots/
    X_IB: Transform = dataclasses.field(default_factory=Transform, metadata=REQUIRED)


@dataclasses.dataclass
class ToolConfig:
    X_IT: Transform = dataclasses.field(default_factory=Transform, metadata=REQUIRED)
    name: str = "tool"
    # A tool symmetric about one of T's axes (nozzle, torch) may turn about it by up to
    # this angle to keep the robot inside its limits; y is the pressing direction n.
    free_rotation_deg: float = 0.0
    symmetry_axis: str = "y"
    geometry: list[ShapeConfig] = dataclasses.field(default_factory=list)  # in T


@dataclasses.dataclass
class PartConfig:
    X_PE: Transform = dataclasses.field(default_factory=Transform, metadata=REQUIRED)
    name: str = "part"
    mesh: str | None = None  # STL/OBJ/PLY in P, relative to the cell file
    mesh_units: str = "m"
    geometry: list[ShapeConfig] = dataclasses.field(default_factory=list)  # in P
    mass_kg: float | None = None  # payload: the part's mass ...
    center_of_mass_mm: list[float] | None = None  # ... and its centre of mass in P


@dataclasses.dataclass
class GripperConfig:
    """The robot-held gripper that holds the part: its mass and centre of mass in the
    flange frame E (payload statements of the programs)."""

    mass_kg: float = required()
    center_of_mass_mm: list[float] = dataclasses.field(default_factory=lambda: [0.0, 0.0, 0.0])


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
    units: str = required()  # m | mm
    closed: bool = False  # a closed contour (periodic spline): the ends must meet
    points: str | None = None  # CSV x,y,z[,nx,ny,nz], relative to the cell file
    dxf: str | None = None
    dxf_layer: str | None = None
    analytic: AnalyticPath | None = None
    normal: list[float] | None = None  # constant surface normal in P (into the surface)
    normal_from_mesh: bool = False  # normals from part.mesh
    degree: int = 5
    fit_tolerance_mm: float = 0.1
    normal_tolerance_deg: float = 2.0  # max angle, given (CSV) to fitted normal
    n_control_points: int | None = None


@dataclasses.dataclass
class MotionConfig:
    speed: float = required()  # m/s of the time-law parameter (at the TCP by default)
    max_acceleration: float = required()  # m/s²
    max_jerk: float = required()  # m/s³
    speed_reference: str = "tcp"  # tcp | flange
    sample_rate_hz: float = 250.0
    cusp_smoothing_mm: float | None = None  # re-fit the flange path within this deviation
    clearance: float = 0.005  # m: robot and part vs obstacles, the tool and each other
    self_clearance: float = 0.005  # m: robot link vs robot link (pairs of class "check")


@dataclasses.dataclass
class Cell:
    robot: RobotConfig = dataclasses.field(default_factory=RobotConfig, metadata=REQUIRED)
    tool: ToolConfig = dataclasses.field(default_factory=ToolConfig, metadata=REQUIRED)
    part: PartConfig = dataclasses.field(default_factory=PartConfig, metadata=REQUIRED)
    path: PathConfig = dataclasses.field(default_factory=PathConfig, metadata=REQUIRED)
    motion: MotionConfig = dataclasses.field(default_factory=MotionConfig, metadata=REQUIRED)
    name: str = ""
    description: str = ""
    gripper: GripperConfig | None = None
    obstacles: list[ShapeConfig] = dataclasses.field(default_factory=list)  # in I
    # Pairs of shape names whose contact is intended (the tool tip on the part).
    allowed_contact: list[list[str]] = dataclasses.field(default_factory=list)


def _is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _is_float_text(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _check_vector(file, key, value, size):
    if not (isinstance(value, list) and len(value) == size and all(map(_is_number, value))):
        raise InputError(file, key, f"expected a list of {size} numbers, got {short_repr(value)}")
    if not all(math.isfinite(v) for v in value):
        raise InputError(file, key, f"NaN or infinity in {short_repr(value)}")


def _check_transform(file, key, raw):
    if not isinstance(raw, dict):
        raise InputError(
            file, key, "expected {translation: [x, y, z], rotation: !Rpy {deg: [...]}}"
        )
    unknown = set(raw) - {"translation", "rotation", "base_frame"}
    if unknown:
        raise InputError(
            file, f"{key}.{sorted(unknown)[0]}", "unknown key (allowed: translation, rotation)"
        )
    if "translation" in raw:
        _check_vector(file, f"{key}.translation", raw["translation"], 3)
    rotation = raw.get("rotation")
    if rotation is not None:
        if not (
            isinstance(rotation, dict)
            and rotation.get("__tag__") == "!Rpy"
            and set(rotation) == {"__tag__", "deg"}
        ):
            raise InputError(file, f"{key}.rotation", "expected !Rpy {deg: [roll, pitch, yaw]}")
        _check_vector(file, f"{key}.rotation.deg", rotation["deg"], 3)


def _check_value(file, key, raw, schema):
    """Check raw YAML against a field type; raises InputError naming ``key``."""
    origin, args = typing.get_origin(schema), typing.get_args(schema)
    if origin in (typing.Union, types.UnionType):
        if raw is None:
            return
        return _check_value(file, key, raw, next(a for a in args if a is not type(None)))
    if schema is Transform:
        return _check_transform(file, key, raw)
    if dataclasses.is_dataclass(schema):
        return _check_mapping(file, key, raw, schema)
    if (
        origin is list
        and args
        and (
            dataclasses.is_dataclass(args[0])
            or typing.get_origin(args[0]) is list
            or args[0] is str
        )
    ):
        if not isinstance(raw, list):
            raise InputError(file, key, f"expected a list, got {short_repr(raw)}")
        for i, item in enumerate(raw):
            _check_value(file, f"{key}[{i}]", item, args[0])
        return
    if origin is list:
        if not (isinstance(raw, list) and all(map(_is_number, raw))):
            raise InputError(file, key, f"expected a list of numbers, got {short_repr(raw)}")
        if not all(math.isfinite(v) for v in raw):
            raise InputError(file, key, f"NaN or infinity in {short_repr(raw)}")
        return
    expected = {
        float: _is_number,
        int: lambda v: isinstance(v, int) and not isinstance(v, bool),
        bool: lambda v: isinstance(v, bool),
        str: lambda v: isinstance(v, str),
    }[schema]
    if not expected(raw):
        hint = ""
        if schema is float and isinstance(raw, str) and _is_float_text(raw):
            hint = f" (YAML reads {raw} as text: write {float(raw):.1e})"
        raise InputError(file, key, f"expected {schema.__name__}, got {short_repr(raw)}{hint}")
    if schema is float and not math.isfinite(raw):
        raise InputError(file, key, f"{raw} is not a finite number")


def _check_mapping(file, prefix, raw, schema):
    if not isinstance(raw, dict) or "__tag__" in raw:
        raise InputError(file, prefix or "(top level)", "expected a mapping of keys")
    hints = typing.get_type_hints(schema)
    fields = {f.name: f for f in dataclasses.fields(schema)}
    for name in raw:
        if name not in fields:
            where = f"{prefix}.{name}" if prefix else str(name)
            raise InputError(file, where, f"unknown key (allowed: {', '.join(fields)})")
    for name, field in fields.items():
        where = f"{prefix}.{name}" if prefix else name
        if name not in raw or raw[name] is None:
            if field.metadata.get("required"):
                raise InputError(file, where, "missing (required)")
            continue
        _check_value(file, where, raw[name], hints[name])


def load_cell(file: str | os.PathLike) -> Cell:
    """Load and check a cell file.

    Raises:
        InputError: with a one-line message naming the file, key and reason.
    """
    file = Path(file)
    text = safe_yaml.read_text(file)  # size, encoding
    raw = safe_yaml.load(file, text)  # aliases, depth, duplicate keys
    _check_mapping(file, "", raw, Cell)
    try:
        return yaml_load_typed(schema=Cell, data=text)
    except Exception as error:  # Drake's message is multi-line; keep its first line.
        first_line = (str(error).strip().splitlines() or [type(error).__name__])[0]
        raise InputError(file, "", first_line) from None


def transform(value: Transform) -> RigidTransform:
    """The RigidTransform of a schema Transform (deterministic only)."""
    return value.GetDeterministicValue()
