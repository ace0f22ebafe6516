"""The files of an imported robot folder: URDF, robot.yaml, README.md, meshes/SOURCES.md.

The URDF keeps the chain base → tip of the description (joint names, origins, axes,
limits and inertials unchanged; links off the chain dropped), with the converted meshes
(:mod:`.meshes`) and the base and tip links named ``base_link`` and ``tool0`` as every
robot folder has them. robot.yaml carries the derived kinematics, the URDF's limits and
the assumed ones, each marked as such.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import yaml

from offline_prog.robot.kinematics_opw import OpwParameters
from offline_prog.robot.kinematics_ur import UrParameters
from offline_prog.robot_import.chain import Chain
from offline_prog.robot_import.meshes import MeshSource, material_rgba
from offline_prog.robot_import.sources import Packages

# Assumptions where a URDF is silent (the bundled robots state the same two ratios).
ASSUMED_VELOCITY_DEG_S = 90.0  # a joint without a URDF velocity limit
ACCELERATION_RAMP_S = 0.5  # full speed reached in 0.5 s: acceleration = 2 x velocity
JERK_RAMP_S = 0.1  # acceleration limit reached in 0.1 s: jerk = 10 x acceleration
# The program format each maker's controller runs (robot.yaml controller.language).
VENDOR_LANGUAGE = {"kuka": "krl", "abb": "rapid", "universal_robots": "urscript", "fanuc": "fanuc"}
VENDORS = ("fanuc", "kuka", "abb", "universal_robots", "other")
HOME_WRIST_DEG = 30.0  # the home pose's axis 5, off the wrist singularity


def write_urdf(chain: Chain, files: dict, out: Path, name: str) -> Path:
    """``out/<name>.urdf``: the chain with the converted meshes (origins zero)."""
    rename = {chain.base: "base_link", chain.tip: "tool0"}
    robot = ET.Element("robot", name=name)
    robot.append(
        ET.Comment(
            f" {name}: imported by `offline-prog robots import` from {chain.file.name}; "
            "sources and checks in README.md, meshes/SOURCES.md "
        )
    )
    links = {link.get("name"): link for link in chain.root.findall("link")}
    for link_name in chain.links:
        source = links[link_name]
        link = ET.SubElement(robot, "link", name=rename.get(link_name, link_name))
        if source.find("inertial") is not None:
            link.append(source.find("inertial"))
        for role in ("visual", "collision"):
            for k, element in enumerate(source.findall(role)):  # primitives kept
                geometry = element.find("geometry")
                if geometry is not None and geometry.find("mesh") is None:
                    link.append(_primitive(element, chain, f"{link_name}_{role}_{k}", role))
            for file in files.get(link_name, {}).get(role, []):
                element = ET.SubElement(link, role)
                ET.SubElement(element, "origin", xyz="0 0 0", rpy="0 0 0")
                geometry = ET.SubElement(element, "geometry")
                ET.SubElement(geometry, "mesh", filename=file)
    for joint in chain.joints:
        source = next(j for j in chain.root.findall("joint") if j.get("name") == joint.name)
        copy = ET.fromstring(ET.tostring(source))
        for tag in ("parent", "child"):
            copy.find(tag).set(
                "link", rename.get(copy.find(tag).get("link"), copy.find(tag).get("link"))
            )
        robot.append(copy)
    ET.indent(robot, "  ")
    file = out / f"{name}.urdf"
    file.write_text(
        '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n", encoding="utf-8"
    )
    return file


def _primitive(element: ET.Element, chain: Chain, material: str, role: str) -> ET.Element:
    """A copy of a ``<visual>``/``<collision>`` primitive whose material, if any, is its
    own colour by a name of its own (Drake refuses a material without colour, and one
    name given two colours)."""
    copy = ET.fromstring(ET.tostring(element))
    for old in copy.findall("material"):
        copy.remove(old)
    if role == "visual":
        rgba = material_rgba(element, _materials(chain), chain.file)
        colour = ET.SubElement(copy, "material", name=material)
        ET.SubElement(colour, "color", rgba=" ".join(f"{v:g}" for v in rgba))
    return copy


def _materials(chain: Chain) -> dict[str, ET.Element]:
    return {m.get("name"): m for m in chain.root.findall("material")}


def limits_record(chain: Chain) -> tuple[dict, list[str]]:
    """robot.yaml ``limits`` [deg, deg/s, ...] and one note per limit saying its source."""
    joints = chain.revolute
    position = [[_deg(j.lower), _deg(j.upper)] for j in joints]
    from_urdf = [j.velocity is not None for j in joints]
    velocity = [_deg(j.velocity) if j.velocity else ASSUMED_VELOCITY_DEG_S for j in joints]
    acceleration = [round(v / ACCELERATION_RAMP_S, 6) for v in velocity]
    jerk = [round(a / JERK_RAMP_S, 6) for a in acceleration]
    notes = [
        "position_deg: from the URDF <limit lower upper>",
        "velocity_deg_s: from the URDF <limit velocity>"
        if all(from_urdf)
        else f"velocity_deg_s: from the URDF where given; ASSUMED {ASSUMED_VELOCITY_DEG_S:g} deg/s "
        f"for joints {[j.name for j, ok in zip(joints, from_urdf, strict=True) if not ok]}",
        f"acceleration_deg_s2: ASSUMED (not in a URDF): full speed in {ACCELERATION_RAMP_S} s",
        f"jerk_deg_s3: ASSUMED (not in a URDF): acceleration limit reached in {JERK_RAMP_S} s",
    ]
    limits = {
        "position_deg": position,
        "velocity_deg_s": velocity,
        "acceleration_deg_s2": acceleration,
        "jerk_deg_s3": jerk,
    }
    return limits, notes


def _deg(value: float) -> float:
    return round(float(np.degrees(value)), 6)


def family(params) -> str:
    """robot.yaml ``family`` of a derived parameter record (None: drake)."""
    return {OpwParameters: "opw", UrParameters: "ur"}.get(type(params), "drake")


def kinematics_record(params: OpwParameters | UrParameters | None) -> dict | None:
    """robot.yaml ``kinematics`` of an OPW or UR robot (None for family drake)."""
    if params is None:
        return None
    if isinstance(params, UrParameters):
        return {k: float(getattr(params, k)) for k in ("d1", "a2", "a3", "d4", "d5", "d6")}
    record = {k: float(getattr(params, k)) for k in ("a1", "a2", "b", "c1", "c2", "c3", "c4")}
    record["offsets_deg"] = [round(float(np.degrees(o)), 9) + 0.0 for o in params.offsets]
    record["sign_corrections"] = [int(s) for s in params.sign_corrections]
    return record


def home_deg(params: OpwParameters | None, limits: dict) -> list[float]:
    """A home pose [deg, controller axes]: the description's zero with axis 5 turned
    HOME_WRIST_DEG off the wrist singularity, clipped into the limits."""
    home = np.zeros(6)
    if isinstance(params, OpwParameters):
        home[4] = (HOME_WRIST_DEG + np.degrees(params.offsets[4])) * params.sign_corrections[4]
    position = np.array(limits["position_deg"])
    return [round(float(v), 6) + 0.0 for v in np.clip(home, position[:, 0], position[:, 1])]


def robot_yaml(
    *,
    name: str,
    chain: Chain,
    vendor: str,
    params,
    limits: dict,
    notes: list[str],
    controller: dict,
    source: str,
) -> str:
    """The text of robot.yaml (comments say where each number comes from); ``source``
    names the description without the user's folders (Packages.display)."""
    record = {
        "vendor": vendor,
        "family": family(params),
        "urdf": f"{name}.urdf",
        "joint_names": [j.name for j in chain.revolute],
    }
    if params is not None:
        record["kinematics"] = kinematics_record(params)
    record["limits"], record["controller"] = limits, controller
    header = (
        f"# Imported by `offline-prog robots import` from {source}.\n"
        "# Angles at this edge are in degrees (keys say so); lengths in metres.\n"
        + "".join(f"# limits.{note}\n" for note in notes)
        + (
            f"# kinematics: {family(params).upper()} parameters derived from the URDF's joint\n"
            "# origins and axes and checked against its FK (README.md).\n"
            if params is not None
            else "# family drake: no closed-form kinematics fits this chain; joint paths come\n"
            "# from Drake's InverseKinematics (slower, one solution per pose).\n"
        )
    )
    return header + yaml.safe_dump(record, sort_keys=False, width=100, default_flow_style=None)


def sources_md(
    name: str, sources: list[MeshSource], licence: Path | None, packages: Packages
) -> str:
    """meshes/SOURCES.md: every converted mesh, its source (without the user's folders),
    checksum and transform."""
    rows = "".join(
        f"| {s.link} | {s.role} | `{packages.display(s.source)}` | `{s.sha256[:16]}…` | "
        f"{' '.join(f'{v:g}' for v in s.xyz)} | {' '.join(f'{v:g}' for v in s.rpy)} | "
        f"{' '.join(f'{v:g}' for v in s.scale)} | {s.triangles} | {', '.join(s.written)} |\n"
        for s in sources
    )
    return (
        f"# {name}: mesh sources\n\n"
        "Written by `offline-prog robots import`. Each source mesh was scaled, moved from its\n"
        "URDF `<origin>` into the link frame (applied to the vertices; the written URDF's\n"
        "origins are zero), and written as OBJ in metres, coordinates rounded to 10 um.\n"
        "Visual: one `usemtl` group per source `<visual>`, `Kd` = the URDF material colour,\n"
        "normals split at edges sharper than 30 deg. Collision: positions and faces; a concave\n"
        "mesh is split into CoACD convex pieces (Drake uses each piece's convex hull).\n"
        "Nothing was simplified: triangle counts are the sources'.\n\n"
        "| link | role | source | sha256 | xyz [m] | rpy [rad] | scale | triangles | written |\n"
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n"
        + rows
        + "\n## Licence\n\n"
        + (
            "The source package's licence is copied beside the meshes "
            f"(`LICENSE`, from `{packages.display(licence)}`)."
            if licence
            else "No licence file was found in or above the source package: check the\n"
            "package's `package.xml` before distributing these meshes."
        )
        + "\n"
    )
