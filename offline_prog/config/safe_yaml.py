"""Reading a cell file's YAML within limits: size, encoding, aliases, depth, duplicates.

A cell file is small and flat; anything else is refused with one line before it can
hang the loader or flood an error message: a file above ``MAX_CELL_FILE_BYTES``, text
that is not UTF-8 (a UTF-8 byte-order mark is accepted and dropped), more than
``MAX_YAML_NODES`` values once aliases are expanded (a "billion laughs" alias bomb),
nesting deeper than ``MAX_YAML_DEPTH``, and a key given twice in one mapping (YAML
loaders keep the last one silently). The node graph is checked before any Python
object is built from it; libyaml's C loader is used where it is installed.
"""

from __future__ import annotations

import codecs
import re
import reprlib
from pathlib import Path

import yaml

from offline_prog.constants import (
    MAX_CELL_FILE_BYTES,
    MAX_VALUE_CHARS,
    MAX_YAML_DEPTH,
    MAX_YAML_NODES,
)
from offline_prog.errors import InputError

_BaseLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class TagTolerantLoader(_BaseLoader):
    """Reads Drake's tagged nodes (``!Rpy {...}``) as {"__tag__": tag, **mapping}."""


def _construct_tagged(loader, tag_suffix, node):
    if isinstance(node, yaml.MappingNode):
        return {"__tag__": "!" + tag_suffix, **loader.construct_mapping(node, deep=True)}
    return {"__tag__": "!" + tag_suffix}


TagTolerantLoader.add_multi_constructor("!", _construct_tagged)
# YAML 1.2 booleans: only true / false. YAML 1.1 (PyYAML's default) also reads on, off,
# yes, no as booleans, which would turn the contract's ``process_io: {on: ..., off: ...}``
# keys into True / False.
TagTolerantLoader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag != "tag:yaml.org,2002:bool"]
    for first, resolvers in _BaseLoader.yaml_implicit_resolvers.items()
}
TagTolerantLoader.add_implicit_resolver(
    "tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF")
)


def drake_text(data) -> str:
    """YAML text that Drake's typed loader reads as ``data``, parsed by
    :class:`TagTolerantLoader` (YAML 1.2 booleans): Drake's own dumper writes it, so a
    string such as ``on`` or ``"demo, on: plate"`` is quoted where its YAML 1.1 loader
    would read a boolean, and tagged mappings keep their tag. Nothing is edited in the
    user's text."""
    from pydrake.common.yaml import yaml_dump

    def drake(value):
        if isinstance(value, dict):
            return {("_tag" if k == "__tag__" else k): drake(v) for k, v in value.items()}
        if isinstance(value, list):
            return [drake(v) for v in value]
        return value

    return yaml_dump(drake(data))


_short = reprlib.Repr()
_short.maxstring = _short.maxother = MAX_VALUE_CHARS
_short.maxlist = _short.maxdict = 6
_short.maxlevel = 3


def short_repr(value) -> str:
    """repr() of a value for an error message: at most about MAX_VALUE_CHARS."""
    text = _short.repr(value)
    return text if len(text) <= 2 * MAX_VALUE_CHARS else text[: 2 * MAX_VALUE_CHARS] + "..."


def read_text(file: Path, *, what: str = "cell file", max_bytes: int = MAX_CELL_FILE_BYTES) -> str:
    """The file's text: at most ``max_bytes``, UTF-8 (a BOM is dropped).

    Args:
        what: the kind of file, for the messages (a touches or controller file too).

    Raises:
        InputError: unreadable, too large, or not UTF-8 (naming the line).
    """
    try:
        size = file.stat().st_size
        if size > max_bytes:
            raise InputError(file, "", f"{size:,} bytes; a {what} has at most {max_bytes:,}")
        data = file.read_bytes()
    except OSError as error:
        raise InputError(file, "", f"cannot read ({error.strerror})") from None
    if data.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        raise InputError(file, "", f"UTF-16 text; save the {what} as UTF-8")
    try:
        return data.removeprefix(codecs.BOM_UTF8).decode("utf-8")
    except UnicodeDecodeError as error:
        line = data[: error.start].count(b"\n") + 1
        byte = data[error.start]
        raise InputError(
            file,
            "",
            f"line {line}: byte 0x{byte:02x} is not UTF-8 (Latin-1?); save the {what} as UTF-8",
        ) from None


def _check_nodes(file: Path, root: yaml.Node) -> None:
    """Count values (aliases expanded), depth and duplicate keys of a node graph,
    without recursion and stopping at the first limit."""
    stack, count, checked = [(root, 1)], 0, set()
    while stack:
        node, depth = stack.pop()
        count += 1
        if count > MAX_YAML_NODES:
            raise InputError(
                file, "", f"more than {MAX_YAML_NODES:,} values once aliases are expanded"
            )
        if depth > MAX_YAML_DEPTH:
            line = node.start_mark.line + 1
            raise InputError(file, "", f"line {line}: nested deeper than {MAX_YAML_DEPTH} levels")
        if isinstance(node, yaml.MappingNode):
            if id(node) not in checked:
                checked.add(id(node))
                seen = set()
                for key, _ in node.value:
                    if isinstance(key, yaml.ScalarNode) and key.tag != "tag:yaml.org,2002:merge":
                        if key.value in seen:
                            line = key.start_mark.line + 1
                            raise InputError(
                                file, "", f"line {line}: key {short_repr(key.value)} given twice"
                            )
                        seen.add(key.value)
            stack.extend((child, depth + 1) for pair in node.value for child in pair)
        elif isinstance(node, yaml.SequenceNode):
            stack.extend((child, depth + 1) for child in node.value)


def _check_depth(file: Path, text: str) -> None:
    """Nesting depth from the parser's events (an iterative pass, no node built).

    libyaml's parser (where installed) yields events as it scans, so our limit fires
    first, with our message and line, on most texts. Where it stops with an error of
    its own (a syntax error, or its own nesting limit: its scanner looks up to 1,024
    characters ahead, and the libyaml bundled with PyYAML 6.0.4 stops at 1,000 levels),
    PyYAML's pure-Python parser, iterative and without a limit, reads the text again:
    our limit, or the error it finds, is the answer. No message text is matched.
    """
    try:
        _walk_depth(file, text, _BaseLoader)
    except yaml.YAMLError:
        if _BaseLoader is yaml.SafeLoader:
            raise
        _walk_depth(file, text, yaml.SafeLoader)  # raises ours, or its own error
        raise


def _walk_depth(file: Path, text: str, loader) -> None:
    """Raises InputError where the events of ``loader``'s parser nest deeper than
    MAX_YAML_DEPTH (yaml.YAMLError where the text is not YAML)."""
    depth = 0
    for event in yaml.parse(text, Loader=loader):
        if isinstance(event, yaml.SequenceStartEvent | yaml.MappingStartEvent):
            depth += 1
            if depth > MAX_YAML_DEPTH:
                line = event.start_mark.line + 1
                raise InputError(
                    file, "", f"line {line}: nested deeper than {MAX_YAML_DEPTH} levels"
                )
        elif isinstance(event, yaml.SequenceEndEvent | yaml.MappingEndEvent):
            depth -= 1


def load(file: Path, text: str):
    """The YAML document in ``text`` as Python data (tagged nodes as dicts).

    Raises:
        InputError: not YAML (naming the line), or beyond the limits above.
    """
    loader = TagTolerantLoader(text)
    try:
        _check_depth(file, text)  # before composing: libyaml's composer recurses in C
        node = loader.get_single_node()
        if node is None:
            return None
        _check_nodes(file, node)
        return loader.construct_document(node)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        line = f"line {mark.line + 1}: " if mark else ""
        problem = getattr(error, "problem", None) or str(error).splitlines()[0]
        raise InputError(file, "", f"{line}not valid YAML ({problem})") from None
    except RecursionError:
        raise InputError(file, "", f"nested deeper than {MAX_YAML_DEPTH} levels") from None
    finally:
        loader.dispose()
