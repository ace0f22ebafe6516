"""The panel's request bodies and values, checked before they reach the session.

A request the session cannot use is refused with a one-line reason (400) and changes
nothing: a body larger than ``MAX_BODY_BYTES`` (a touches file: ``MAX_TOUCHES_BODY_BYTES``)
or nested deeper than ``MAX_DEPTH``
(read without recursion, so no RecursionError), text that is not JSON (``NaN`` and
``Infinity`` included, which Python's json would accept), a key the endpoint does not
take, and a value of the wrong kind. Values (:func:`finite`, :func:`boolean`,
:func:`typed`) are checked here once, for the panel and for callers of
:class:`~offline_prog.session.server.Session` alike.
"""

from __future__ import annotations

import json
import math

MAX_BODY_BYTES = 10_000  # a request is a key and a value: ~100 bytes
MAX_TOUCHES_BODY_BYTES = 200_000  # a touches file's text: ~70 bytes a touch
MAX_DEPTH = 2  # an object holding a list at most (a request is one flat object)


class RequestError(ValueError):
    """A request refused; str() is the one-line reason."""


def _depth(text: str) -> int:
    """The deepest nesting of ``[``/``{`` in JSON text (strings skipped), without
    recursion; stops counting past MAX_DEPTH."""
    depth = deepest = 0
    in_string = escaped = False
    for char in text:
        if in_string:
            if escaped:
                escaped = False
            elif char == "\\":
                escaped = True
            elif char == '"':
                in_string = False
        elif char == '"':
            in_string = True
        elif char in "[{":
            depth += 1
            deepest = max(deepest, depth)
            if deepest > MAX_DEPTH:
                break
        elif char in "]}":
            depth -= 1
    return deepest


def _no_constant(name: str):
    raise RequestError(f"{name} is not a JSON number")


def read_body(body: bytes, *, keys: tuple[str, ...], max_bytes: int = MAX_BODY_BYTES) -> dict:
    """The JSON object of a request body, holding only ``keys`` (each optional), of at
    most ``max_bytes``.

    Raises:
        RequestError: too large, not UTF-8, not JSON, too deep, not an object, or a
            key the endpoint does not take.
    """
    if len(body) > max_bytes:
        raise RequestError(f"body larger than {max_bytes} bytes")
    try:
        text = body.decode("utf-8")
    except UnicodeDecodeError:
        raise RequestError("body is not UTF-8 text") from None
    if _depth(text) > MAX_DEPTH:
        raise RequestError(f"JSON nested deeper than {MAX_DEPTH} levels")
    try:
        value = json.loads(text or "{}", parse_constant=_no_constant)
    except RequestError:
        raise
    except json.JSONDecodeError as error:
        raise RequestError(f"not JSON: {error.msg} at character {error.pos}") from None
    except ValueError as error:  # an integer of more than 4300 digits
        raise RequestError(f"not JSON: {str(error)[:80]}") from None
    if not isinstance(value, dict):
        raise RequestError("expected a JSON object")
    unknown = sorted(set(value) - set(keys))
    if unknown:
        raise RequestError(f"unexpected key {unknown[0]!r} (takes {', '.join(keys)})")
    return value


def _shown(value) -> str:
    return repr(value)[:40]


def finite(value, what: str) -> float:
    """A finite number from a JSON number or its text (``"12.5"``).

    Raises:
        RequestError: a boolean, a list, text that is no number, NaN or infinity.
    """
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise RequestError(f"{what} {_shown(value)} is not a number")
    try:
        number = float(value.strip() if isinstance(value, str) else value)
    except (ValueError, OverflowError):
        raise RequestError(f"{what} {_shown(value)} is not a number") from None
    if not math.isfinite(number):
        raise RequestError(f"{what} {_shown(value)} is not a finite number")
    return number


def boolean(value, what: str) -> bool:
    """A JSON boolean, or exactly the text ``"true"`` or ``"false"``.

    Raises:
        RequestError: anything else (``"no"``, ``0``, ``null``): never guessed.
    """
    if isinstance(value, bool):
        return value
    if value in ("true", "false"):
        return value == "true"
    raise RequestError(f"{what} {_shown(value)} is not true or false")


def typed(value, what: str) -> str | float:
    """A typed value as the panel sends it: text or a number (checked by the control).

    Raises:
        RequestError: a boolean, null, a list or an object.
    """
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise RequestError(f"{what} {_shown(value)} is not a number or text")
    return value


def text(value, what: str, *, max_chars: int) -> str:
    """Text of at most ``max_chars`` characters.

    Raises:
        RequestError: anything but text, or longer.
    """
    if not isinstance(value, str):
        raise RequestError(f"{what} {_shown(value)} is not text")
    if len(value) > max_chars:
        raise RequestError(f"{what} is longer than {max_chars} characters")
    return value


def name(value, what: str) -> str:
    """A name (a control's key, an action): text.

    Raises:
        RequestError: anything but text.
    """
    if not isinstance(value, str):
        raise RequestError(f"{what} {_shown(value)} is not text")
    return value
