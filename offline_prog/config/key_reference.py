"""The cell file's key reference, written from the schema the loader checks against.

The documentation's cell file page is made from :func:`cell_key_rows` (a hook of the
documentation build calls :func:`cell_key_reference`), so a key the code accepts is
documented the moment it exists: its dotted name, its type, whether the file must give
it, its default, and the comment the schema's source carries beside or above it.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
import types
import typing

from offline_prog.config.cell import Cell


@dataclasses.dataclass(frozen=True)
class KeyRow:
    """One key of the cell file: ``key`` dotted (``seams[].cad.edges``), its type as the
    file writes it, required or its default, and what the schema says of it."""

    key: str
    type: str
    required: bool
    default: str
    doc: str


def _nested(annotation) -> list[type]:
    """The dataclasses an annotation holds (``X | None``, ``list[X]``)."""
    found = []
    for outer in (annotation, *typing.get_args(annotation)):
        for inner in (outer, *typing.get_args(outer)):
            if dataclasses.is_dataclass(inner) and inner not in found:
                found.append(inner)
    return found


def _type_name(annotation) -> str:
    """``float``, ``list[float]``, ``str | None``, ``mapping`` for a section."""
    if dataclasses.is_dataclass(annotation):
        return "mapping"
    if annotation is type(None):
        return "null"
    if isinstance(annotation, type) and not typing.get_args(annotation):
        return {"Transform": "transform"}.get(annotation.__name__, annotation.__name__)
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin in (types.UnionType, typing.Union):
        return " | ".join(_type_name(a) for a in args)
    if origin is list:
        return f"list[{', '.join(_type_name(a) for a in args)}]"
    return str(annotation).replace("typing.", "")


def _comments(schema: type) -> dict[str, str]:
    """field name ↦ the comment beside it, or the comment lines right above it."""
    try:
        lines = inspect.getsource(schema).splitlines()
    except (OSError, TypeError):  # made by make_dataclass: no source
        return {}
    found, above = {}, []
    for line in lines:
        stripped = line.strip()
        if stripped.startswith("#"):
            above.append(stripped.lstrip("# "))
            continue
        match = re.match(r"\s+(\w+):[^=]*(=.*?)?(#\s*(.*))?$", line)
        if match and match.group(1) in {f.name for f in dataclasses.fields(schema)}:
            beside = match.group(4) or ""
            found[match.group(1)] = " ".join([*above, beside]).strip()
        above = []
    return found


def _default(field: dataclasses.Field) -> str:
    if field.default is not dataclasses.MISSING:
        return "" if field.default is None else repr(field.default)
    if field.default_factory is list:
        return "[]"
    return ""


def cell_key_rows(schema: type = Cell, prefix: str = "") -> list[KeyRow]:
    """Every key of the cell file, depth first in the schema's order."""
    rows, comments = [], _comments(schema)
    for field in dataclasses.fields(schema):
        key = f"{prefix}{field.name}"
        required = bool(field.metadata.get("required"))
        doc = comments.get(field.name, "")
        nested = _nested(field.type)
        if nested and not doc:
            doc = (inspect.getdoc(nested[0]) or "").replace("\n", " ")
            doc = "" if doc.startswith(f"{nested[0].__name__}(") else doc  # generated
        rows.append(
            KeyRow(key, _type_name(field.type), required, "" if required else _default(field), doc)
        )
        is_list = typing.get_origin(field.type) is list
        for inner in nested:
            rows += cell_key_rows(inner, f"{key}[]." if is_list else f"{key}.")
    return rows


def _cell(text: str) -> str:
    """A Markdown table cell: pipes escaped, on one line."""
    return text.replace("|", "\\|").replace("\n", " ")


def cell_key_reference() -> str:
    """The Markdown table of every cell key (the documentation's generated reference)."""
    out = ["| key | type | required / default | what it is |", "|---|---|---|---|"]
    for row in cell_key_rows():
        need = "**required**" if row.required else (f"`{row.default}`" if row.default else "")
        out.append(f"| `{row.key}` | {_cell(row.type)} | {_cell(need)} | {_cell(row.doc)} |")
    return "\n".join(out) + "\n"
