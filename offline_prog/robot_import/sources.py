"""A robot description as URDF text: xacro expanded, ROS packages found without ROS.

ROS-Industrial support packages name their files through ROS packages
(``$(find fanuc_m20ia_support)`` in xacro includes, ``package://fanuc_m20ia_support/...``
in mesh file names). Without a ROS install the packages are found as folders holding a
``package.xml`` whose ``<name>`` is the package's (the ROS-I layout), under the folders the
user gives (``--package-path``), searched a few levels deep. A description reads
only inside those folders and its own package (:class:`Packages`); xacro itself runs in
:mod:`.xacro_sandbox`.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from pathlib import Path

from offline_prog.errors import InputError

# How deep below a --package-path folder package.xml files are looked for.
PACKAGE_SEARCH_DEPTH = 3


@dataclasses.dataclass(frozen=True)
class Packages:
    """The ROS packages a description may use and the folders it may read.

    Attributes:
        folders: ROS package name -> its folder (resolved).
        roots: the resolved folders every file read must lie in (after symbolic links
            and ``..`` are resolved): the ``--package-path`` folders (or the default one)
            and the description's own package.
        file_meshes: whether ``file://`` mesh names (any absolute path) are read
            (``--allow-file-meshes``).
    """

    folders: dict[str, Path]
    roots: tuple[Path, ...]
    file_meshes: bool = False

    def confined(self, path: Path | str, *, file: Path, key: str) -> Path:
        """``path`` resolved, when it lies in one of the roots.

        Raises:
            InputError: naming ``file`` and ``key``, when it lies elsewhere, cannot be
                resolved or is neither a file nor a folder (a pipe would block a read).
        """
        try:
            resolved = Path(path).resolve()
        except (OSError, RuntimeError) as error:  # a symbolic-link loop, a name too long
            raise InputError(file, key, f"cannot be resolved ({error})") from None
        if resolved.exists() and not (resolved.is_file() or resolved.is_dir()):
            raise InputError(file, key, f"{resolved} is not a regular file")
        if not any(resolved.is_relative_to(root) for root in self.roots):
            raise InputError(
                file,
                key,
                f"{resolved} is outside the folders a description may read (--package-path: "
                f"{', '.join(map(str, self.roots))})",
            )
        return resolved

    def display(self, path: Path) -> str:
        """``path`` without the user's folders: ``package://PKG/rel`` inside a package,
        else relative to the folder holding it (its root's name first)."""
        path = Path(path).resolve()
        for package, folder in sorted(self.folders.items()):
            if path.is_relative_to(folder):
                return f"package://{package}/{path.relative_to(folder).as_posix()}"
        for root in self.roots:
            if path.is_relative_to(root):
                return (Path(root.name) / path.relative_to(root)).as_posix()
        return path.name


def packages_for(
    description: Path, package_paths: list[Path], *, file_meshes: bool = False
) -> Packages:
    """The packages under ``package_paths`` (default: the folder above the
    description's package) and the folders the description may read."""
    given = [Path(p) for p in package_paths] or [above_package(description)]
    own = own_package(description)
    roots = tuple(dict.fromkeys([*(p.resolve() for p in given), own]))
    return Packages(find_packages(given), roots, file_meshes)


def own_package(description: Path) -> Path:
    """The description's package folder (the first folder up holding a package.xml),
    else the description's folder; resolved."""
    folder = Path(description).resolve().parent
    for candidate in [folder, *folder.parents]:
        if (candidate / "package.xml").is_file():
            return candidate
    return folder


def above_package(description: Path) -> Path:
    """The folder holding the description's ROS package, where its sibling packages
    are; else the description's folder."""
    own = own_package(description)
    return own.parent if (own / "package.xml").is_file() else own


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


def resolve_uri(uri: str, packages: Packages, *, base_dir: Path, file: Path) -> Path:
    """The file a URDF ``filename`` names: ``package://PKG/rel``, a path relative to
    the description's folder, or (with ``packages.file_meshes``) ``file://abs``.

    Raises:
        InputError: an unknown package, a file outside the packages' folders, a
            ``file://`` name without ``--allow-file-meshes``, or a file that does not
            exist (naming ``file``, the description, and the URI).
    """
    if uri.startswith("package://"):
        package, _, rest = uri.removeprefix("package://").partition("/")
        if package not in packages.folders:
            raise InputError(file, uri, unknown_package(package, packages.folders))
        path = packages.confined(packages.folders[package] / rest, file=file, key=uri)
    elif uri.startswith("file://"):
        if not packages.file_meshes:
            raise InputError(
                file,
                uri,
                "a file:// mesh may lie anywhere: read it only with --allow-file-meshes "
                "(or name it package://PKG/...)",
            )
        path = Path(uri.removeprefix("file://"))
    else:
        path = packages.confined(base_dir / uri, file=file, key=uri)
    if not path.is_file():
        raise InputError(file, uri, f"mesh file not found ({path})")
    return path


def unknown_package(package: str, packages: dict[str, Path]) -> str:
    known = ", ".join(sorted(packages)) or "none"
    return f"ROS package {package!r} not found under --package-path (found: {known})"
