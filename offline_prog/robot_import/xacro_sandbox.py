"""A xacro file expanded as data: no code runs, no file outside the packages is read.

The ``xacro`` package (PyPI) expands the macros; its hooks are replaced while it runs:

- ``${...}`` and ``$(eval ...)``: :mod:`.xacro_eval` (numbers, arithmetic, comparisons,
  math names; xacro's own evaluators reach Python's builtins);
- ``<xacro:include>``, ``xacro.load_yaml`` and ``$(find PKG)``: only files inside the
  folders :class:`~.sources.Packages` allows, after symbolic links and ``..``;
- ``$(env ...)``, ``$(optenv ...)`` and ``$(cwd)`` are refused: a description that reads
  the user's environment gives a different robot on another machine.

A refusal is one :class:`~offline_prog.errors.InputError` naming the xacro file being
expanded, the expression and the reason; it is raised even where xacro would have
caught it (an ``optional`` include).
"""

from __future__ import annotations

import builtins
import contextlib
from pathlib import Path
from typing import Any, NoReturn

from offline_prog.errors import InputError
from offline_prog.robot_import import xacro_eval
from offline_prog.robot_import.sources import Packages, unknown_package
from offline_prog.robot_import.xacro_eval import Namespace, RefusedError, allowed

# Expressions evaluated per description: the ROS-I descriptions need a few hundred;
# beyond this a macro expands without end (each level doubling the text).
MAX_EXPRESSIONS = 200_000
_KEY_CHARS = 80  # an expression's text in an error message


def description_text(file: Path, packages: Packages) -> str:
    """The URDF text of ``file``: a .urdf read as is, a .xacro expanded in the sandbox.

    Raises:
        InputError: a missing file, a refused expression or file, a package that is not
            found, or xacro's own error (one line naming the file).
    """
    file = Path(file)
    if not file.is_file():
        raise InputError(file, "", "description file not found")
    if file.suffix.lower() == ".urdf":
        return file.read_text(encoding="utf-8")
    if file.suffix.lower() != ".xacro":
        raise InputError(file, "", "expected a .urdf or .xacro file")
    return _Sandbox(file, packages).expand()


class _Sandbox:
    """xacro's hooks for one expansion (see the module docstring)."""

    def __init__(self, file: Path, packages: Packages):
        import xacro

        self.xacro, self.file, self.packages = xacro, file, packages
        self.refusal: InputError | None = None
        self.count = 0
        self.names = xacro_eval.standard_names()
        self.xacro_names = Namespace(
            "xacro",
            {
                "load_yaml": allowed(self.load_yaml),
                "arg": allowed(self.arg),
                "dotify": allowed(xacro.YamlDictWrapper),
                "tokenize": allowed(xacro.tokenize),
                "fatal": allowed(self.fatal),
            },
        )

    def expand(self) -> str:
        from xacro import substitution_args

        xacro = self.xacro
        hooks = [
            (xacro, "safe_eval", self.safe_eval),
            (xacro, "eval_extension", self.eval_extension(xacro.eval_extension)),
            (xacro, "get_include_files", self.include_files(xacro.get_include_files)),
            (substitution_args, "_eval", self.substitution_eval),
            (substitution_args, "_eval_find", allowed(self.find)),
            (substitution_args, "_eval_env", self.environment("env")),
            (substitution_args, "_eval_optenv", self.environment("optenv")),
        ]
        with contextlib.ExitStack() as stack:
            for module, name, value in hooks:
                stack.enter_context(_patched(module, name, value))
            try:
                document = xacro.process_file(str(self.file))
            except InputError as error:
                raise (self.refusal or error) from None
            except Exception as error:  # xacro raises many kinds: XacroException, XML, ...
                if self.refusal is not None:
                    raise self.refusal from None
                raise InputError(self.file, "", f"xacro: {' '.join(str(error).split())}") from None
        if self.refusal is not None:  # xacro caught it (an optional include)
            raise self.refusal
        return document.toxml()

    def refuse(self, key: str, reason: str) -> NoReturn:
        stack = [f for f in getattr(self.xacro, "filestack", None) or [] if f]
        key = " ".join(key.split())
        if len(key) > _KEY_CHARS:
            key = key[: _KEY_CHARS - 3] + "..."
        error = InputError(stack[-1] if stack else self.file, key, reason)
        self.refusal = self.refusal or error
        raise error

    def counted(self, key: str) -> None:
        self.count += 1
        if self.count > MAX_EXPRESSIONS:
            self.refuse(key, f"more than {MAX_EXPRESSIONS} expressions: a macro without end?")

    # ${...}: names from xacro's property tables, then the standard names.
    def safe_eval(self, expr: str, symbols: Any, _locals: Any = None) -> Any:
        key = f"${{{expr}}}"
        self.counted(key)

        def lookup(name: str) -> Any:
            table = symbols
            while isinstance(table, self.xacro.Table):
                if dict.__contains__(table, name):
                    return table[name]
                table = table.parent
            return self.standard(name)

        return self.evaluate(expr, lookup, key)

    def standard(self, name: str) -> Any:
        if name in self.names:
            return self.names[name]
        if name == "xacro":
            return self.xacro_names
        if name in ("load_yaml", "dotify", "tokenize"):  # xacro's deprecated bare names
            return self.xacro_names.attribute(name)
        if name in self.xacro._global_symbols:
            raise RefusedError(f"{name} is not allowed ({xacro_eval.ALLOWED})")
        raise _unknown(name)

    def evaluate(self, expr: str, lookup, key: str) -> Any:
        try:
            return xacro_eval.evaluate(expr, lookup)
        except RefusedError as refused:
            self.refuse(key, str(refused))
        except SyntaxError as error:
            self.refuse(key, str(error))

    # $(eval ...): xacro's names there (arg values, find, dirname) and the standard ones.
    def substitution_eval(self, expr: str, context: dict) -> str:
        key = f"$(eval {expr})"
        self.counted(key)
        args = context.setdefault("arg", {})
        from xacro.substitution_args import _eval_arg, _eval_dirname, convert_value

        functions = {
            "arg": allowed(lambda name: convert_value(_eval_arg(name, args=args), "auto")),
            "dirname": allowed(lambda: _eval_dirname(context.get("filename"))),
            "find": allowed(self.find),
        }

        def lookup(name: str) -> Any:
            if name in functions:
                return functions[name]
            if name in ("env", "optenv"):
                raise RefusedError(f"{name}() reads the environment: not allowed in a description")
            if name in self.names:
                return self.names[name]
            if name in args:
                return convert_value(args[name], "auto")
            raise _unknown(name)

        return str(self.evaluate(expr, lookup, key))

    def find(self, package: str) -> str:
        key = f"$(find {package})"
        if package not in self.packages.folders:
            self.refuse(key, unknown_package(package, self.packages.folders))
        return str(self.confined(self.packages.folders[package], key))

    def confined(self, path: Path | str, key: str) -> Path:
        try:
            return self.packages.confined(path, file=self.file, key=key)
        except InputError as error:
            self.refuse(key, error.reason)

    def load_yaml(self, filename: str) -> Any:
        key = f"xacro.load_yaml({filename!r})"
        path = self.confined(self.xacro.abs_filename_spec(str(filename)), key)
        return self.xacro.load_yaml(str(path))

    def arg(self, name: str) -> Any:
        return self.xacro.substitution_args_context["arg"][name]

    def fatal(self, *args: Any) -> NoReturn:
        raise self.xacro.XacroException(" ".join(map(str, args)))

    def environment(self, command: str):
        def refuse(name: str, *_default: str, **_named: str) -> NoReturn:
            self.refuse(
                f"$({command} {name})",
                "reads the user's environment: not allowed in a robot description "
                "(write the value into the file, or pass it as a xacro argument)",
            )

        return refuse

    def eval_extension(self, original):
        def extension(text: str) -> Any:
            if text.strip() == "$(cwd)":
                self.refuse(text, "names the working folder: not allowed in a description")
            return original(text)

        return extension

    def include_files(self, original):
        def files(filename_spec: str, symbols: Any):
            for filename in original(filename_spec, symbols):
                yield str(self.confined(filename, f"xacro:include {filename}"))

        return files


def _unknown(name: str) -> Exception:
    """The error for a name nothing defines: a refusal for one of Python's builtins."""
    if hasattr(builtins, name):
        return RefusedError(f"{name} is a Python builtin ({xacro_eval.ALLOWED})")
    return NameError(f"name {name!r} is not defined")


@contextlib.contextmanager
def _patched(module, name: str, value):
    """Replace ``module.name`` while the block runs."""
    old = getattr(module, name)
    setattr(module, name, value)
    try:
        yield
    finally:
        setattr(module, name, old)
