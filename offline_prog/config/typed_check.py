"""Raw YAML checked against the cell's dataclasses before Drake's typed load, so that
every error names the file, the dotted key and the reason in one line."""

import dataclasses
import math
import types
import typing

from pydrake.common.schema import Transform

from offline_prog.config.safe_yaml import short_repr
from offline_prog.errors import InputError


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
        return check_mapping(file, key, raw, schema)
    if origin is dict:  # {name: value}, names are text
        if not isinstance(raw, dict) or "__tag__" in raw:
            raise InputError(file, key, f"expected a mapping of names, got {short_repr(raw)}")
        for name, item in raw.items():
            if not isinstance(name, str):
                raise InputError(file, f"{key}.{name}", "a name must be text")
            _check_value(file, f"{key}.{name}", item, args[1])
        return
    if (
        origin is list
        and args
        and (
            dataclasses.is_dataclass(args[0])
            or typing.get_origin(args[0]) is list
            or args[0] is str
            or args[0] is Transform
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
            value = float(raw)
            hint = (
                f" (YAML reads {raw} as text: write {value:.1e})"
                if math.isfinite(value)
                else f" (YAML reads {raw} as text; it is not a finite number)"
            )
        raise InputError(file, key, f"expected {schema.__name__}, got {short_repr(raw)}{hint}")
    if schema is float and not math.isfinite(raw):
        raise InputError(file, key, f"{raw} is not a finite number")


def check_mapping(file, prefix, raw, schema):
    """Check raw YAML (a mapping) against a dataclass; raises InputError naming the key."""
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
