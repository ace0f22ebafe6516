"""Strings that reach a controller program: one sanitizer per format and kind.

Names, descriptions and file names come from the user's cell file; written raw into a
program, a newline ends a comment and starts a live statement (``name: "x\\nsocket_open(
...)"`` becomes URScript after the ``#``). Every such string goes through exactly one of
the functions here before a writer puts it in a program:

- ``*_comment``: the text of one comment line (KRL ``;``, RAPID ``!``, URScript ``#``):
  printable ASCII on one line. Control characters and Unicode line and paragraph
  separators become spaces, known symbols are spelled out (``σ`` → ``sigma``), accents
  are dropped (``é`` → ``e``) and any other character becomes ``?``.
- ``*_string``: the body of a string literal, quoted: RAPID doubles ``"`` and ``\\``
  and keeps at most 80 characters; URScript strings have no escapes, so ``"`` becomes
  ``'`` and ``\\`` becomes ``/``.
- ``identifier``: a name the program declares (module, routine, data). It is checked,
  not repaired, where the user chose it (a program name), and derived by
  ``identifier_from`` where the program makes one from free text (RAPID tool/wobj).
"""

from __future__ import annotations

import re
import unicodedata

# Symbols our own header text uses, spelled out in ASCII.
_SPELLED = {"°": " deg", "σ": "sigma", "≤": "<=", "≥": ">=", "×": "x", "π": "pi", "→": "->"}
_SPELLED.update({"…": "...", "–": "-", "—": "-", "‘": "'", "’": "'", "“": '"', "”": '"'})
_IDENTIFIER = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")
RAPID_STRING_MAX = 80  # RAPID TRM: a string holds at most 80 characters


def plain_ascii(text: str) -> str:
    """One line of printable ASCII: whitespace and control characters (newline, CR,
    tab, U+2028 ...) are single spaces; symbols spelled out, accents dropped, anything
    else ``?``."""
    for old, new in _SPELLED.items():
        text = text.replace(old, new)
    out = []
    for char in unicodedata.normalize("NFKD", str(text)):
        if " " <= char <= "~":
            out.append(char)
        elif char.isspace() or unicodedata.category(char)[0] in "CZ":
            out.append(" ")  # Cc control, Cf format, Zl/Zp line/paragraph separators
        elif not unicodedata.combining(char):
            out.append("?")
    return " ".join("".join(out).split())


def krl_comment(text: str) -> str:
    """Text for one KRL comment line (the writer puts ``; `` in front)."""
    return plain_ascii(text)


def rapid_comment(text: str) -> str:
    """Text for one RAPID comment line (the writer puts ``! `` in front)."""
    return plain_ascii(text)


def urscript_comment(text: str) -> str:
    """Text for one URScript comment line (the writer puts ``# `` in front)."""
    return plain_ascii(text)


FANUC_COMMENT_MAX = 32  # a TP remark (``! text ;``) holds at most 32 characters


def fanuc_comments(text: str) -> list[str]:
    """Text for FANUC TP remarks (the writer puts ``! `` before and `` ;`` after each):
    plain ASCII, ``;`` as ``,``, split at spaces into pieces of at most 32 characters."""
    words, pieces = plain_ascii(text).replace(";", ",").split(), [""]
    for word in words:
        while len(word) > FANUC_COMMENT_MAX:
            pieces += [word[:FANUC_COMMENT_MAX], ""]
            word = word[FANUC_COMMENT_MAX:]
        joined = f"{pieces[-1]} {word}".strip()
        if len(joined) <= FANUC_COMMENT_MAX:
            pieces[-1] = joined
        else:
            pieces.append(word)
    return [piece for piece in pieces if piece]


def rapid_string(text: str) -> str:
    """A RAPID string literal, quotes included: ``"`` and ``\\`` doubled, ≤ 80 chars."""
    body, length = [], 0
    for char in plain_ascii(text):
        escaped = char * 2 if char in '"\\' else char
        if length + len(escaped) > RAPID_STRING_MAX:
            break
        body.append(escaped)
        length += len(escaped)
    return '"' + "".join(body) + '"'


def urscript_string(text: str) -> str:
    """A URScript string literal, quotes included (no escapes in URScript strings)."""
    return '"' + plain_ascii(text).replace('"', "'").replace("\\", "/") + '"'


def identifier(name: str, *, max_chars: int, what: str) -> str:
    """``name`` if it is an identifier (ASCII letter first, then letters, digits, _; at
    most max_chars), else ValueError naming ``what``."""
    if not (isinstance(name, str) and _IDENTIFIER.match(name) and len(name) <= max_chars):
        raise ValueError(
            f"{what}={name!r}: need a letter, then letters, digits or _ "
            f"(ASCII, at most {max_chars} characters)"
        )
    return name


def identifier_from(prefix: str, text: str, *, max_chars: int) -> str:
    """An identifier ``<prefix>_<text>`` made from free text: every character outside
    ASCII letters, digits and _ becomes _, cut to max_chars."""
    return re.sub(r"[^A-Za-z0-9_]", "_", f"{prefix}_{plain_ascii(text)}")[:max_chars]
