"""The expressions of a xacro file (``${...}``, ``$(eval ...)``), evaluated as data.

xacro evaluates them with Python's ``eval``: its ``$(eval)`` even with all of Python's
builtins, so a downloaded description could run any code. Here an expression is parsed
with :mod:`ast` and interpreted node by node over a closed set: numbers, strings,
lists, tuples and mappings; arithmetic (``+ - * / // % **``), comparisons, ``and``,
``or``, ``not``, ``x if c else y``, indexing and slicing; the names xacro documents
(the ``math`` module's functions and constants, bare or as ``math.NAME``; ``True``,
``False``, ``true``, ``false``), a few value functions (:data:`VALUE_FUNCTIONS`, bare or
as ``python.NAME``) and the functions the caller adds (``xacro.load_yaml`` confined to
the packages, ``xacro.arg``). Everything else (attribute access on a value, lambdas,
comprehensions, f-strings, any other name) raises :class:`RefusedError`; a ``.`` only looks
up a key of a mapping (xacro's namespaces, ``load_yaml``'s dotted access). Sizes are
bounded, so ``9**9**9`` or ``'x' * 10**10`` is refused, not computed.
"""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Callable
from typing import Any

MAX_INT_BITS = 4096  # an integer result beyond this is refused (2**4096 ~ 1e1233)
# A value's printed size [characters] beyond this is refused: xacro writes values into
# the text, so a nested list repeated (``[[0] * 10**6] * 10**6``) would print 1e12.
MAX_VALUE_CHARS = 10_000_000
MAX_COMBINATORIC = 1000  # math.factorial / comb / perm arguments


class RefusedError(Exception):
    """An expression uses something a robot description may not (the reason)."""


class Namespace:
    """A fixed set of named values reached as ``name.attr`` (``math``, ``python``)."""

    def __init__(self, name: str, members: dict[str, Any]):
        self.name, self.members = name, members

    def attribute(self, attr: str) -> Any:
        if attr not in self.members:
            raise RefusedError(f"{self.name}.{attr} is not allowed ({ALLOWED})")
        return self.members[attr]


def _bounded(function: Callable, bound: int) -> Callable:
    def call(*args):
        if any(isinstance(a, int) and abs(a) > bound for a in args):
            raise RefusedError(f"{function.__name__}() of more than {bound}")
        return function(*args)

    return call


MATH = {
    name: value
    for name, value in vars(math).items()
    if not name.startswith("_") and name not in ("factorial", "comb", "perm")
}
for _name in ("factorial", "comb", "perm"):
    MATH[_name] = _bounded(getattr(math, _name), MAX_COMBINATORIC)


def _numbers(function: Callable) -> Callable:
    """``function`` over an iterable of numbers, in floats (no integer growth)."""

    def call(values, *args):
        values = list(values)
        if not all(isinstance(v, (int, float)) for v in values):
            raise RefusedError(f"{function.__name__}() of anything but numbers")
        return function([float(v) for v in values], *args)

    call.__name__ = function.__name__
    return call


MATH["prod"] = _numbers(math.prod)
VALUE_FUNCTIONS = {
    f.__name__: f
    for f in (abs, min, max, round, int, float, str, bool, len, _numbers(sum), sorted, list, tuple)
}
ALLOWED = (
    "a description may use numbers, strings, arithmetic, comparisons, math names and "
    f"{', '.join(VALUE_FUNCTIONS)}"
)
CONSTANTS = {"True": True, "False": False, "true": True, "false": False, "None": None}


def standard_names() -> dict[str, Any]:
    """The names every expression may use: the math names and value functions bare, as
    ``math.NAME`` and ``python.NAME``, and the boolean constants."""
    return {
        **MATH,
        **VALUE_FUNCTIONS,
        **CONSTANTS,
        "math": Namespace("math", MATH),
        "python": Namespace("python", VALUE_FUNCTIONS),
    }


_BINARY = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.FloorDiv: operator.floordiv,
    ast.Mod: operator.mod,
    ast.Pow: operator.pow,
}
_UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos, ast.Not: operator.not_}
_COMPARE = {
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
    ast.In: lambda a, b: a in b,
    ast.NotIn: lambda a, b: a not in b,
    ast.Is: operator.is_,
    ast.IsNot: operator.is_not,
}
_DATA = (int, float, complex, str, bool, type(None), list, tuple, dict)


def evaluate(text: str, lookup: Callable[[str], Any]) -> Any:
    """The value of expression ``text``; ``lookup(name)`` gives a name's value (raising
    NameError for an unknown name, :class:`RefusedError` for a forbidden one).

    Raises:
        RefusedError: a construct outside the closed set (see the module docstring).
        NameError, TypeError, ValueError, ZeroDivisionError, ...: as Python would for
            an allowed expression that fails (xacro reports them as its own errors).
    """
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError) as error:
        raise SyntaxError(f"invalid expression ({error})") from None
    try:
        value = _Interpreter(lookup).eval(tree.body)
    except RecursionError:
        raise RefusedError("expression nested too deeply") from None
    if callable(value) or isinstance(value, Namespace):
        raise RefusedError("a function is not a value")
    return value


class _Interpreter:
    def __init__(self, lookup: Callable[[str], Any]):
        self.lookup = lookup
        self.functions = {id(f) for f in [*MATH.values(), *VALUE_FUNCTIONS.values()]}

    def eval(self, node: ast.AST) -> Any:
        method = getattr(self, f"_{type(node).__name__}", None)
        if method is None:
            raise RefusedError(f"{_describe(node)} is not allowed ({ALLOWED})")
        return _size_checked(method(node))

    def _Constant(self, node: ast.Constant) -> Any:
        if not isinstance(node.value, (int, float, complex, str, bool, type(None))):
            raise RefusedError(f"the constant {node.value!r} is not allowed")
        return node.value

    def _Name(self, node: ast.Name) -> Any:
        return self.lookup(node.id)

    def _Attribute(self, node: ast.Attribute) -> Any:
        value = self.eval(node.value)
        if isinstance(value, Namespace):
            return value.attribute(node.attr)
        if isinstance(value, dict):  # xacro's namespaces and load_yaml's dotted access
            return value[node.attr]
        kind = type(value).__name__
        raise RefusedError(f"attribute access .{node.attr} on a {kind} ({ALLOWED})")

    def _Subscript(self, node: ast.Subscript) -> Any:
        value = self.eval(node.value)
        if not isinstance(value, (str, list, tuple, dict)):
            raise RefusedError(f"indexing a {type(value).__name__}")
        return value[self.eval(node.slice)]

    def _Slice(self, node: ast.Slice) -> slice:
        parts = [None if p is None else self.eval(p) for p in (node.lower, node.upper, node.step)]
        if not all(p is None or isinstance(p, int) for p in parts):
            raise RefusedError("a slice of anything but integers")
        return slice(*parts)

    def _BinOp(self, node: ast.BinOp) -> Any:
        if type(node.op) not in _BINARY:
            raise RefusedError(f"the operator {type(node.op).__name__} is not allowed ({ALLOWED})")
        a, b = self.eval(node.left), self.eval(node.right)
        _check_binary(node.op, a, b)
        return _BINARY[type(node.op)](a, b)

    def _UnaryOp(self, node: ast.UnaryOp) -> Any:
        if type(node.op) not in _UNARY:
            raise RefusedError(f"the operator {type(node.op).__name__} is not allowed ({ALLOWED})")
        return _UNARY[type(node.op)](self.eval(node.operand))

    def _BoolOp(self, node: ast.BoolOp) -> Any:
        value = None
        for operand in node.values:
            value = self.eval(operand)
            if bool(value) == isinstance(node.op, ast.Or):
                return value
        return value

    def _Compare(self, node: ast.Compare) -> bool:
        left = self.eval(node.left)
        for op, right_node in zip(node.ops, node.comparators, strict=True):
            right = self.eval(right_node)
            if not _COMPARE[type(op)](left, right):
                return False
            left = right
        return True

    def _IfExp(self, node: ast.IfExp) -> Any:
        return self.eval(node.body) if self.eval(node.test) else self.eval(node.orelse)

    def _List(self, node: ast.List) -> list:
        return [self.eval(e) for e in self._plain(node.elts)]

    def _Tuple(self, node: ast.Tuple) -> tuple:
        return tuple(self.eval(e) for e in self._plain(node.elts))

    def _Dict(self, node: ast.Dict) -> dict:
        if any(k is None for k in node.keys):
            raise RefusedError("** in a mapping is not allowed")
        return {self.eval(k): self.eval(v) for k, v in zip(node.keys, node.values, strict=True)}

    def _Call(self, node: ast.Call) -> Any:
        function = self.eval(node.func)
        if id(function) not in self.functions and not getattr(function, "xacro_allowed", False):
            raise RefusedError(f"calling {ast.unparse(node.func)} is not allowed ({ALLOWED})")
        if any(k.arg is None for k in node.keywords):
            raise RefusedError("** in a call is not allowed")
        args = [self.eval(a) for a in self._plain(node.args)]
        return function(*args, **{k.arg: self.eval(k.value) for k in node.keywords})

    @staticmethod
    def _plain(elements: list[ast.expr]) -> list[ast.expr]:
        if any(isinstance(e, ast.Starred) for e in elements):
            raise RefusedError("* unpacking is not allowed")
        return elements


def allowed(function: Callable) -> Callable:
    """``function`` (a caller's, e.g. a confined ``load_yaml``) made callable from an
    expression."""

    def call(*args, **kwargs):
        return function(*args, **kwargs)

    call.xacro_allowed = True
    return call


def _describe(node: ast.AST) -> str:
    names = {
        "Lambda": "a lambda",
        "ListComp": "a comprehension",
        "SetComp": "a comprehension",
        "DictComp": "a comprehension",
        "GeneratorExp": "a generator",
        "JoinedStr": "an f-string",
        "NamedExpr": "an assignment (:=)",
    }
    return names.get(type(node).__name__, f"the construct {type(node).__name__}")


def _length(value: Any) -> int:
    return len(value) if isinstance(value, (str, list, tuple)) else 0


def _check_binary(op: ast.operator, a: Any, b: Any) -> None:
    """Refuse an operation whose result would be too large before computing it."""
    ints = isinstance(a, int) and isinstance(b, int)
    if isinstance(op, ast.Pow) and ints and b > 0 and a.bit_length() * b > MAX_INT_BITS + b:
        raise RefusedError(f"{a} ** {b} is too large")
    if isinstance(op, ast.Mult):
        if ints and a.bit_length() + b.bit_length() > MAX_INT_BITS:
            raise RefusedError("a product too large")
        sequence, count = (a, b) if _length(a) else (b, a)
        repeated = _length(sequence) and isinstance(count, int) and count > 0
        if repeated and _chars(sequence) * count > MAX_VALUE_CHARS:
            raise RefusedError(f"a value of more than {MAX_VALUE_CHARS} characters")
    if isinstance(op, ast.Mod) and isinstance(a, str):
        raise RefusedError("string formatting with % is not allowed")


def _chars(value: Any, budget: int = MAX_VALUE_CHARS) -> int:
    """About how many characters ``value`` prints as; stops counting past ``budget``."""
    if isinstance(value, str):
        return len(value)
    if isinstance(value, bool) or value is None:
        return 5
    if isinstance(value, int):
        return value.bit_length() // 3 + 1
    if isinstance(value, (float, complex)):
        return 24
    if isinstance(value, (list, tuple, dict)):
        total = 2
        items = [x for kv in value.items() for x in kv] if isinstance(value, dict) else value
        for item in items:
            total += 2 + _chars(item, budget - total)
            if total > budget:
                break
        return total
    return 0  # a function, a namespace, an XML block: printed by name, if at all


def _size_checked(value: Any) -> Any:
    if isinstance(value, int) and not isinstance(value, bool):
        if value.bit_length() > MAX_INT_BITS:
            raise RefusedError("an integer too large")
    elif _chars(value) > MAX_VALUE_CHARS:
        raise RefusedError(f"a value of more than {MAX_VALUE_CHARS} characters")
    return value


def is_data(value: Any) -> bool:
    """True for a plain value (number, string, list, mapping, None)."""
    return isinstance(value, _DATA)
