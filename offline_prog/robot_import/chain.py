"""The serial chain of a URDF from its base link to its flange frame.

A :class:`Chain` keeps, for each joint on the path base → tip (fixed ones included),
its origin X_PC (child joint frame in the parent link), axis and limits; the six
revolute joints are the robot's. :func:`chain_forward` is the chain's own forward
kinematics (numpy), used to derive parameters; :mod:`.verify` checks against Drake's.
"""

from __future__ import annotations

import dataclasses
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix

from offline_prog.errors import InputError

REVOLUTE = ("revolute",)
# A joint type on the chain other than these makes the robot "not 6R".
PASSIVE = ("fixed",)
WORLD = "world"  # Drake's name of the world body in a URDF


@dataclasses.dataclass(frozen=True)
class ChainJoint:
    """One URDF joint on the chain: name, type, parent and child link, X_PC (the joint
    frame in the parent link frame), unit axis in the joint frame, and for revolute
    joints the limits [rad, rad/s] (velocity None when the URDF gives 0 or none)."""

    name: str
    kind: str
    parent: str
    child: str
    X_PC: RigidTransform
    axis: np.ndarray
    lower: float = 0.0
    upper: float = 0.0
    velocity: float | None = None


@dataclasses.dataclass(frozen=True)
class Chain:
    """The path base → tip of a URDF, the parsed document and the description file."""

    root: ET.Element
    file: Path
    base: str
    tip: str
    joints: tuple[ChainJoint, ...]

    @property
    def revolute(self) -> tuple[ChainJoint, ...]:
        return tuple(j for j in self.joints if j.kind in REVOLUTE)

    @property
    def links(self) -> tuple[str, ...]:
        return (self.base, *(j.child for j in self.joints))


def floats(text: str | None, count: int, file: Path, key: str) -> np.ndarray:
    try:
        values = np.array([float(v) for v in (text or "").split()]) if text else np.zeros(count)
    except ValueError:
        raise InputError(file, key, f"expected {count} numbers, got {text!r}") from None
    if values.shape != (count,) or not np.all(np.isfinite(values)):
        raise InputError(file, key, f"expected {count} finite numbers, got {text!r}")
    return values


def origin(element: ET.Element | None, file: Path, key: str) -> RigidTransform:
    """The pose an ``<origin xyz rpy>`` element gives (identity when absent)."""
    if element is None:
        return RigidTransform()
    xyz = floats(element.get("xyz"), 3, file, f"{key} origin xyz")
    rpy = floats(element.get("rpy"), 3, file, f"{key} origin rpy")
    return RigidTransform(RollPitchYaw(rpy), xyz)


def _limit(joint: ET.Element, file: Path, name: str) -> tuple[float, float, float | None]:
    limit = joint.find("limit")
    if limit is None:
        raise InputError(file, f"joint {name} limit", "a revolute joint needs <limit>")
    values = {}
    for key in ("lower", "upper", "velocity"):
        text = limit.get(key)
        try:
            value = float(text) if text is not None else None
        except ValueError:
            raise InputError(file, f"joint {name} limit {key}", f"not a number: {text!r}") from None
        if value is not None and not math.isfinite(value):
            raise InputError(file, f"joint {name} limit {key}", f"not finite: {text!r}")
        values[key] = value
    if values["lower"] is None or values["upper"] is None or values["lower"] >= values["upper"]:
        raise InputError(
            file,
            f"joint {name} limit",
            "needs numeric lower < upper [rad] (got "
            f"{limit.get('lower')!r}, {limit.get('upper')!r})",
        )
    velocity = values["velocity"] if values["velocity"] and values["velocity"] > 0 else None
    return values["lower"], values["upper"], velocity


def parse_chain(text: str, file: Path, *, base: str = "base_link", tip: str = "tool0") -> Chain:
    """The chain base → tip of URDF ``text`` (from ``file``), checked to be six
    revolute joints (fixed joints between them allowed).

    Raises:
        InputError: invalid XML, a missing link, no path from base to tip, or a chain
            that is not six revolute joints (naming the joints found).
    """
    try:
        root = ET.fromstring(text)
    except ET.ParseError as error:
        raise InputError(file, "", f"not valid URDF XML ({error})") from None
    links = _unique(root, "link", file)
    _unique(root, "joint", file)
    for key, name in (("--base", base), ("--tip", tip)):
        if name not in links:
            raise InputError(
                file, key, f"no link named {name!r} (links: {', '.join(sorted(links))})"
            )
    if base == WORLD:
        raise InputError(file, "--base", f"{WORLD!r} is Drake's world: name the robot's base link")
    path = _path(root, file, base=base, tip=tip)
    joints = tuple(_joint(element, file) for element in reversed(path))
    for element in path:
        if element.find("mimic") is not None:
            raise InputError(
                file,
                f"joint {element.get('name')} mimic",
                f"follows joint {element.find('mimic').get('joint')!r}: a dependent joint on "
                "the chain is not a free axis, and the planner moves six free axes",
            )
    moving = [j for j in joints if j.kind not in PASSIVE]
    if len(moving) != 6 or any(j.kind not in REVOLUTE for j in moving):
        found = ", ".join(f"{j.name} ({j.kind})" for j in moving) or "none"
        raise InputError(
            file, "", f"the chain {base} -> {tip} is not six revolute joints (found: {found})"
        )
    return Chain(root, Path(file), base, tip, joints)


def _unique(root: ET.Element, tag: str, file: Path) -> set[str]:
    """The names of the ``<tag>`` elements, each given once."""
    names: set[str] = set()
    for element in root.findall(tag):
        name = element.get("name")
        if not name:
            raise InputError(file, tag, f"a <{tag}> without a name")
        if name in names:
            raise InputError(file, f"{tag} {name}", "the name is used twice")
        names.add(name)
    return names


def _path(root: ET.Element, file: Path, *, base: str, tip: str) -> list[ET.Element]:
    """The joint elements from ``tip`` up to ``base`` (tip first).

    Raises:
        InputError: a link that is the child of two joints, a cycle, a missing
            parent or child, or no path.
    """
    by_child: dict[str, ET.Element] = {}
    for joint in root.findall("joint"):
        for tag in ("parent", "child"):
            if joint.find(tag) is None or not joint.find(tag).get("link"):
                raise InputError(file, f"joint {joint.get('name')}", f"needs <{tag} link=...>")
        child = joint.find("child").get("link")
        if child in by_child:
            raise InputError(
                file,
                f"joint {joint.get('name')}",
                f"link {child!r} is already the child of joint {by_child[child].get('name')!r} "
                "(a URDF is a tree)",
            )
        by_child[child] = joint
    path: list[ET.Element] = []
    link, seen = tip, {tip}
    while link != base:
        if link not in by_child:
            raise InputError(file, "--base", f"{tip!r} is not below {base!r} in the URDF tree")
        path.append(by_child[link])
        link = path[-1].find("parent").get("link")
        if link in seen:
            raise InputError(
                file, f"joint {path[-1].get('name')}", f"the joints form a cycle through {link!r}"
            )
        seen.add(link)
    return path


def _joint(element: ET.Element, file: Path) -> ChainJoint:
    name, kind = element.get("name"), element.get("type")
    key = f"joint {name}"
    axis = floats(
        element.find("axis").get("xyz") if element.find("axis") is not None else "1 0 0",
        3,
        file,
        f"{key} axis",
    )
    if kind not in PASSIVE and np.linalg.norm(axis) < 1e-12:
        raise InputError(file, f"{key} axis", "zero axis")
    lower, upper, velocity = _limit(element, file, name) if kind in REVOLUTE else (0, 0, None)
    return ChainJoint(
        name=name,
        kind=kind,
        parent=element.find("parent").get("link"),
        child=element.find("child").get("link"),
        X_PC=origin(element.find("origin"), file, key),
        axis=axis / max(np.linalg.norm(axis), 1e-300),
        lower=lower,
        upper=upper,
        velocity=velocity,
    )


def chain_forward(chain: Chain, q: np.ndarray) -> list[RigidTransform]:
    """Poses X_BL of every link on the chain (base first) at joint vector q (6,) [rad]."""
    X_BL, poses, k = RigidTransform(), [RigidTransform()], 0
    for joint in chain.joints:
        X_BL = X_BL @ joint.X_PC
        if joint.kind in REVOLUTE:
            X_BL = X_BL @ RigidTransform(RotationMatrix(AngleAxis(q[k], joint.axis)), np.zeros(3))
            k += 1
        poses.append(X_BL)
    return poses
