"""Save: edited values written into the original cell file's text (session Save,
placement's ``placed.yaml``, calibration's ``calibrated.yaml``), and the saved copy next
to the original.

Only the numbers that changed are replaced, each at its place in the text (the YAML
node's marks), so comments, key order, flow or block style and every other value stay
as the engineer wrote them. A key the file does not give (``motion.clearance`` left at
its default) is added to its mapping; a transform whose rotation is not an ``!Rpy``
is rewritten whole as ``{translation: [...], rotation: !Rpy {deg: [...]}}``. The
result is loaded again and compared with the session's cell before it is written. A
copy written into another folder (:func:`relocated_text`) names the same data files,
relative to its new folder.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import yaml
from pydrake.common.yaml import yaml_dump_typed

from offline_prog.config.cell import Cell, load_cell
from offline_prog.config.edits import CellValues
from offline_prog.config.safe_yaml import read_text


def number(value: float) -> str:
    """The shortest text that reads back as ``value`` (no ``-0.0``)."""
    return repr(float(value) + 0.0)


def _child(node, key: str):
    """The value node under ``key`` of a mapping node, or None."""
    if isinstance(node, yaml.MappingNode):
        for k, v in node.value:
            if isinstance(k, yaml.ScalarNode) and k.value == key:
                return v
    return None


def _find(root, dotted: str):
    node = root
    for part in dotted.split("."):
        if part.isdigit():
            items = node.value if isinstance(node, yaml.SequenceNode) else []
            node = items[int(part)] if int(part) < len(items) else None
        else:
            node = _child(node, part)
        if node is None:
            return None
    return node


class _Edits:
    """Text replacements at node marks, applied back to front."""

    def __init__(self, text: str):
        self.text, self.edits = text, []

    def replace(self, node, new: str) -> None:
        self.edits.append((node.start_mark.index, _end(node), new))

    def scalar(self, node, value: float) -> None:
        """Replace a number, unless the text already reads as ``value``."""
        if float(node.value) != value:
            self.replace(node, number(value))

    def add(self, mapping, key: str, value: str) -> None:
        """Add ``key: value`` to a mapping node (flow or block)."""
        if mapping.flow_style:
            at = mapping.end_mark.index - 1  # before the closing brace
            sep = ", " if mapping.value else ""
            self.edits.append((at, at, f"{sep}{key}: {value}"))
            return
        last = mapping.value[-1][1]
        indent = " " * mapping.value[0][0].start_mark.column
        at = _end(last)
        line_end = self.text.find("\n", at)
        at = len(self.text) if line_end < 0 else line_end  # after a trailing comment
        self.edits.append((at, at, f"\n{indent}{key}: {value}"))

    def result(self) -> str:
        text = self.text
        for start, end, new in sorted(self.edits, key=lambda e: e[0], reverse=True):
            text = text[:start] + new + text[end:]
        return text


def _end(node) -> int:
    """Where a node's own text ends: a block collection's end mark lies past the
    comments after it, so take its last child's end."""
    if isinstance(node, yaml.ScalarNode) or getattr(node, "flow_style", False):
        return node.end_mark.index
    children = node.value
    if not children:
        return node.end_mark.index
    last = children[-1][1] if isinstance(node, yaml.MappingNode) else children[-1]
    return _end(last)


def _transform(edits: _Edits, node, p: tuple, rpy_deg: tuple) -> None:
    """Set a transform node's translation and !Rpy degrees (only the changed numbers)."""
    translation, rotation = _child(node, "translation"), _child(node, "rotation")
    deg = _child(rotation, "deg") if rotation is not None and rotation.tag == "!Rpy" else None
    flat = isinstance(node, yaml.MappingNode) and all(
        isinstance(n, yaml.SequenceNode) and len(n.value) == 3 for n in (translation, deg)
    )
    if not flat:
        text = (
            f"{{translation: [{', '.join(map(number, p))}], "
            f"rotation: !Rpy {{deg: [{', '.join(map(number, rpy_deg))}]}}}}"
        )
        edits.replace(node, text)
        return
    for sequence, values in ((translation, p), (deg, rpy_deg)):
        for item, value in zip(sequence.value, values, strict=True):
            edits.scalar(item, value)


def edited_text(text: str, initial: CellValues, state: CellValues) -> str:
    """The cell file's ``text`` with the state's changed values written in.

    Raises:
        ValueError: the text does not hold a key it must (a cell file that loaded
            always does).
    """
    # The pure-Python loader: its marks count characters (libyaml's need not).
    root = yaml.compose(text, Loader=yaml.SafeLoader)
    edits = _Edits(text)
    for key, p, rpy, p0, rpy0 in (
        ("tool.X_IT", state.p_IT, state.rpy_IT_deg, initial.p_IT, initial.rpy_IT_deg),
        ("part.X_PE", state.p_PE, state.rpy_PE_deg, initial.p_PE, initial.rpy_PE_deg),
    ):
        if (p, rpy) != (p0, rpy0):
            node = _find(root, key)
            if node is None:
                raise ValueError(f"{key} not found in the cell file")
            _transform(edits, node, p, rpy)
    for owner, key, value, value0 in (
        ("tool", "free_rotation_deg", state.free_rotation_deg, initial.free_rotation_deg),
        ("tool", "turn_smoothing_mm", state.turn_smoothing_mm, initial.turn_smoothing_mm),
        ("motion", "speed", state.motion_speed, initial.motion_speed),
        ("motion", "clearance", state.clearance, initial.clearance),
    ):
        if value != value0:
            node = _find(root, f"{owner}.{key}")
            if node is None:
                edits.add(_find(root, owner), key, number(value))
            else:
                edits.scalar(node, value)
    for k, (speed, speed0) in enumerate(zip(state.seam_speeds, initial.seam_speeds, strict=True)):
        if speed != speed0:  # a seam's own speed: given in the file (None is never edited)
            edits.scalar(_find(root, f"seams.{k}.speed"), speed)
    return edits.result()


def with_values(
    text: str, poses: dict[str, tuple], strings: dict[str, str], numbers: dict | None = None
) -> str:
    """The cell file's ``text`` with transforms, text values and numbers replaced in
    place.

    Args:
        poses: {dotted key (``tool.X_IT``, ``obstacles.2.pose``): (p [m], rpy [deg])};
            a key the file leaves out (an obstacle at the origin) is added.
        strings: {dotted key: new text} (file names: written quoted); a top-level key
            the file leaves out (``description``) is added.
        numbers: {dotted key (``obstacles.1.size_mm.2``): new number}.

    Raises:
        ValueError: a key of ``strings`` or ``numbers`` is not in the text, or a pose's
            mapping is not.
    """
    root = yaml.compose(text, Loader=yaml.SafeLoader)
    edits = _Edits(text)
    for key, (p, rpy_deg) in poses.items():
        node = _find(root, key)
        if node is None:
            owner, _, name = key.rpartition(".")
            mapping = _find(root, owner)
            if mapping is None:
                raise ValueError(f"{owner} not found in the cell file")
            flat = (
                f"{{translation: [{', '.join(map(number, p))}], "
                f"rotation: !Rpy {{deg: [{', '.join(map(number, rpy_deg))}]}}}}"
            )
            edits.add(mapping, name, flat)
        else:
            _transform(edits, node, p, rpy_deg)
    for key, value in strings.items():
        node = _find(root, key)
        if node is None and "." not in key and isinstance(root, yaml.MappingNode):
            edits.add(root, key, json.dumps(value))
            continue
        if node is None:
            raise ValueError(f"{key} not found in the cell file")
        if node.value != value:  # unchanged text stays as written
            edits.replace(node, json.dumps(value))
    for key, value in (numbers or {}).items():
        node = _find(root, key)
        if not isinstance(node, yaml.ScalarNode):
            raise ValueError(f"{key} not found in the cell file")
        edits.scalar(node, value)
    return edits.result()


def data_file_keys(cell: Cell) -> dict[str, str]:
    """{dotted key of the cell file: file name as written} of every data file the cell
    names (path points, DXF, meshes, CAD models)."""
    keys = {}
    if cell.part.mesh:
        keys["part.mesh"] = cell.part.mesh
    if cell.part.model:  # STEP or mesh: seams, collision and visual geometry
        keys["part.model"] = cell.part.model
    gripper = cell.gripper
    if gripper is not None and gripper.mesh:
        keys["gripper.mesh"] = gripper.mesh
    paths = [("path", cell.path)] if cell.path else list(enumerate(cell.seams))
    for key, path in paths:
        key = key if isinstance(key, str) else f"seams.{key}"
        for name in ("points", "dxf"):
            if getattr(path, name):
                keys[f"{key}.{name}"] = getattr(path, name)
        if path.cad is not None and path.cad.file:
            keys[f"{key}.cad.file"] = path.cad.file
    for owner, shapes in (
        ("obstacles", cell.obstacles),
        ("part.geometry", cell.part.geometry),
        ("tool.geometry", cell.tool.geometry),
        ("gripper.geometry", gripper.geometry if gripper is not None else []),
    ):
        for i, shape in enumerate(shapes):
            if shape.shape == "mesh" and shape.mesh:
                keys[f"{owner}.{i}.mesh"] = shape.mesh
    return keys


def relocated_text(
    cell_file: Path,
    cell: Cell,
    out_dir: Path,
    poses: dict[str, tuple],
    strings: dict[str, str] | None = None,
    numbers: dict | None = None,
) -> str:
    """The cell file's text with ``poses``, ``strings`` and ``numbers`` written in (see
    :func:`with_values`), to be written into ``out_dir``: its data files and
    ``robot.robots_dir`` re-pointed from there (unchanged when ``out_dir`` is the cell
    file's own folder)."""
    source, target = Path(cell_file).resolve().parent, Path(out_dir).resolve()
    names = dict(data_file_keys(cell))
    if cell.robot.robots_dir is not None:
        names["robot.robots_dir"] = cell.robot.robots_dir
    relocated = {
        key: os.path.relpath(source / name, target)
        for key, name in names.items()
        if source != target  # the same folder: every name stays as written
    }
    text = Path(cell_file).read_text(encoding="utf-8")
    return with_values(text, poses, relocated | (strings or {}), numbers)


MAX_SAVES = 10_000


def free_name(file: Path) -> Path:
    """``<stem>-<n>.yaml`` next to ``file``, the first n ≥ 1 not taken."""
    for n in range(1, MAX_SAVES):
        candidate = file.with_name(f"{file.stem}-{n}{file.suffix}")
        if not candidate.exists():
            return candidate
    raise FileExistsError(f"{file.parent}: {MAX_SAVES} saved copies of {file.name}")


def save_cell(original: Path, initial: CellValues, state: CellValues, cell: Cell) -> Path:
    """Write ``cell`` (``state``'s, edited from ``initial``) next to ``original``; returns
    the new file.

    Raises:
        OSError: the folder is not writable.
        RuntimeError: the written file does not load to ``cell`` (it is removed).
    """
    text = edited_text(read_text(original), initial, state)
    while True:
        target = free_name(original)
        try:
            with open(target, "x", encoding="utf-8") as stream:  # never replaces a file
                stream.write(text)
            break
        except FileExistsError:  # taken since free_name looked: the next one
            continue
    if not loads_to(target, cell):
        os.unlink(target)
        raise RuntimeError(f"{target}: the edited file did not load to the session's cell")
    return target


def loads_to(file: Path, cell: Cell) -> bool:
    """Whether the cell file ``file`` loads to ``cell`` (False if it does not load)."""
    try:
        return yaml_dump_typed(load_cell(file)) == yaml_dump_typed(cell)
    except Exception:
        return False
