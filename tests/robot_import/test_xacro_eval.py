"""xacro expressions evaluated as data: what ROS-Industrial descriptions write gives
xacro's values, and every way out to Python (builtins, attributes, lambdas,
comprehensions, names built from strings) or to unbounded work is refused."""

import math
import re

import pytest

from offline_prog.robot_import.xacro_eval import (
    MAX_VALUE_CHARS,
    RefusedError,
    allowed,
    evaluate,
    standard_names,
)

NAMES = {**standard_names(), "prefix": "left_", "table": {"a": {"b": 2.5}}, "n": 3}


def lookup(name):
    if name in NAMES:
        return NAMES[name]
    raise NameError(name)


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("-pi/2.0", -math.pi / 2),
        ("230/255", 230 / 255),
        ("radians(-170)", math.radians(-170)),
        ("math.cos(pi) + sqrt(4)", 1.0),
        ("prefix + 'base_link'", "left_base_link"),
        ("n > 2 and n != 4", True),
        ("1 if n == 3 else 2", 1),
        ("table['a']['b'] * 2", 5.0),
        ("table.a.b", 2.5),  # xacro's dotted access to load_yaml's mappings
        ("python.max([1, n, 2])", 3),
        ("int(round(2.6)) + len('ab') + abs(-1)", 6),
        ("str(n) * 2", "33"),
        ("[1, 2, 3][1:]", [2, 3]),
        ("2 ** 10", 1024),
        ("true or False", True),
        ("sum([0.5, 0.25]) + factorial(5)", 120.75),
    ],
)
def test_description_expressions_give_xacro_values(text, value):
    result = evaluate(text, lookup)
    assert result == (pytest.approx(value) if isinstance(value, float) else value)
    assert type(result) is type(value)


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ("().__class__.__bases__[0].__subclasses__()", "attribute access .__class__ on a tuple"),
        ("'x'.join(['a'])", "attribute access .join on a str"),
        ("(lambda: 1)()", "a lambda"),
        ("[x for x in [1, 2]]", "a comprehension"),
        ("{x: 1 for x in [1]}", "a comprehension"),
        ("sum(x for x in [1])", "a generator"),
        ("f'{n}'", "an f-string"),
        ("(y := 2)", "assignment"),
        ("math.__dict__", "math.__dict__ is not allowed"),
        ("python.vars", "python.vars is not allowed"),
        ("max(*[1, 2])", "unpacking"),
        ("9 ** 9 ** 9", "too large"),
        ("'x' * 10 ** 10", f"more than {MAX_VALUE_CHARS} characters"),
        ("[[0] * 1000000] * 1000000", f"more than {MAX_VALUE_CHARS} characters"),
        ("'%*d' % (10 ** 9, 1)", "string formatting"),
        ("factorial(10 ** 7)", "factorial() of more than"),
        ("prod([2 ** 4000] * 10) > 0", None),  # in floats: overflow, not a hang
        ("sin", "a function is not a value"),
        ("1 << 10 ** 9", "the operator LShift"),
    ],
)
def test_escapes_and_unbounded_work_are_refused(text, reason):
    if reason is None:
        with pytest.raises(OverflowError):
            evaluate(text, lookup)
        return
    with pytest.raises(RefusedError, match=re.escape(reason)):
        evaluate(text, lookup)


def test_only_allowed_functions_are_called():
    """A function reaches an expression only through a name the caller chose; one the
    caller marks with allowed() is called, any other callable value is refused."""
    seen = []
    own = {"ok": allowed(lambda x: seen.append(x) or x), "raw": print}
    assert evaluate("ok(2) + 1", lambda name: own[name]) == 3 and seen == [2]
    with pytest.raises(RefusedError, match="calling raw"):
        evaluate("raw('x')", lambda name: own[name])


def test_unknown_names_and_bad_syntax_are_ordinary_errors():
    with pytest.raises(NameError):
        evaluate("nothing + 1", lookup)
    with pytest.raises(SyntaxError):
        evaluate("1 +", lookup)
    with pytest.raises(ZeroDivisionError):
        evaluate("1 / 0", lookup)
