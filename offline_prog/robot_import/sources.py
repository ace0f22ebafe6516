"""A robot description as URDF text: xacro expanded, ROS packages found without ROS.

ROS-Industrial support packages name their files through ROS packages
(``$(find fanuc_m20ia_support)`` in xacro includes, ``package://fanuc_m20ia_support/...``
in mesh file names). Without a ROS install the packages are found as folders holding a
``package.xml`` whose ``<name>`` is the package's (the ROS-I layout), under the folders the
user gives (``--package-path``), searched a few levels deep.
"""

from __future__ import annotations

import contextlib
import xml.etree.ElementTree as ET
from pathlib import Path

from offline_prog.errors import InputError

# How deep below a --package-path folder package.xml files are looked for.
PACKAGE_SEARCH_DEPTH = 3


def find_packages(package_paths: list[Path]) -> dict[str, Path]:
    """ROS package name -> its folder, for every package.xml under ``package_paths``.

    A folder that is itself a package counts too. The first folder given wins when
    two hold a package of the same name (as ROS_PACKAGE_PATH does).

    Raises:
        InputError: a folder that does not exist, or a package.xml without a name.
    """
    packages: dict[str, Path] = {}
    for root in package_paths:
        root = Path(root)
        if not root.is_dir():
            raise InputError(root, "--package-path", "not a folder")
        files = [root / "package.xml"] + [
            file
            for depth in range(1, PACKAGE_SEARCH_DEPTH + 1)
            for file in sorted(root.glob("/".join(["*"] * depth) + "/package.xml"))
        ]
        for file in files:
            if file.is_file():
                packages.setdefault(_package_name(file), file.parent.resolve())
    return packages


def _package_name(file: Path) -> str:
    try:
        name = ET.parse(file).getroot().findtext("name")
    except ET.ParseError as error:
        raise InputError(file, "", f"not valid XML ({error})") from None
    if not name or not name.strip():
        raise InputError(file, "name", "a package.xml needs a <name>")
    return name.strip()


def resolve_uri(uri: str, packages: dict[str, Path], *, base_dir: Path, file: Path) -> Path:
    """The file a URDF ``filename`` names: ``package://PKG/rel``, ``file://abs`` or a
    path relative to the description's folder.

    Raises:
        InputError: an unknown package or a file that does not exist (naming ``file``,
            the description, and the URI).
    """
    if uri.startswith("package://"):
        package, _, rest = uri.removeprefix("package://").partition("/")
        if package not in packages:
            raise InputError(file, uri, _unknown(package, packages))
        path = packages[package] / rest
    elif uri.startswith("file://"):
        path = Path(uri.removeprefix("file://"))
    else:
        path = base_dir / uri
    if not path.is_file():
        raise InputError(file, uri, f"mesh file not found ({path})")
    return path


def _unknown(package: str, packages: dict[str, Path]) -> str:
    known = ", ".join(sorted(packages)) or "none"
    return f"ROS package {package!r} not found under --package-path (found: {known})"


def description_text(file: Path, packages: dict[str, Path]) -> str:
    """The URDF text of ``file``: a .urdf read as is, a .xacro expanded by the
    ``xacro`` package (PyPI) with ``$(find PKG)`` resolved through ``packages``.

    Raises:
        InputError: a missing file, a package that is not found, or xacro's own error
            (one line naming the file).
    """
    file = Path(file)
    if not file.is_file():
        raise InputError(file, "", "description file not found")
    if file.suffix.lower() == ".urdf":
        return file.read_text(encoding="utf-8")
    if file.suffix.lower() != ".xacro":
        raise InputError(file, "", "expected a .urdf or .xacro file")
    import xacro
    from xacro import substitution_args

    def find(package: str) -> str:
        if package not in packages:
            raise InputError(file, f"$(find {package})", _unknown(package, packages))
        return str(packages[package])

    with _patched(substitution_args, "_eval_find", find):
        try:
            document = xacro.process_file(str(file))
        except InputError:
            raise
        except Exception as error:  # xacro raises many kinds: XacroException, XML, KeyError
            cause = error.__context__ if isinstance(error.__context__, InputError) else None
            if cause is not None:
                raise cause from None
            raise InputError(file, "", f"xacro: {' '.join(str(error).split())}") from None
    return document.toxml()


@contextlib.contextmanager
def _patched(module, name: str, value):
    """Replace ``module.name`` while the block runs. The PyPI xacro resolves
    ``$(find PKG)`` with ament_index (a ROS 2 install); we resolve it from package.xml
    folders instead."""
    old = getattr(module, name)
    setattr(module, name, value)
    try:
        yield
    finally:
        setattr(module, name, old)
