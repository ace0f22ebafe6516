"""``offline-prog robots import``: a robot folder from a URDF or xacro description.

Reads the description (:mod:`.sources`), finds the six-revolute chain (:mod:`.chain`),
derives its OPW parameters (:mod:`.derive`) and checks them against Drake's FK of the
description (:mod:`.verify`), converts the meshes (:mod:`.meshes`), writes the URDF,
robot.yaml and README (:mod:`.record`), loads the result as any robot is loaded and
computes its self-collision matrix (:mod:`offline_prog.scene.self_collision`).
"""

from __future__ import annotations

import dataclasses
import shutil
import tempfile
from pathlib import Path

import numpy as np

from offline_prog.errors import InputError
from offline_prog.robot.kinematics_opw import OpwParameters
from offline_prog.robot.kinematics_ur import UrParameters
from offline_prog.robot.model import PARAMS_FILE, RobotModel, load_robot
from offline_prog.robot_import import record
from offline_prog.robot_import.chain import Chain, parse_chain
from offline_prog.robot_import.derive import axes_at_zero, derive_opw
from offline_prog.robot_import.derive_ur import derive_ur
from offline_prog.robot_import.meshes import convert_meshes
from offline_prog.robot_import.readme import readme_text
from offline_prog.robot_import.sources import description_text, find_packages
from offline_prog.robot_import.verify import FkCheck, check_fk
from offline_prog.scene.self_collision import MATRIX_FILE, write_matrix

IMPORT_SAMPLES = 10_000  # self-collision samples, as the bundled robots'


@dataclasses.dataclass(frozen=True)
class ImportResult:
    """What an import wrote: the folder, the loaded robot, the derived OPW or UR
    parameters (None: Drake IK), the FK check (None without a closed form) and the self-collision
    pairs."""

    folder: Path
    robot: RobotModel
    params: OpwParameters | UrParameters | None
    fk: FkCheck | None
    pairs: list


def import_robot(
    description: Path,
    *,
    name: str,
    out: Path,
    package_paths: list[Path] = (),
    vendor: str = "other",
    base: str = "base_link",
    tip: str = "tool0",
    samples: int = IMPORT_SAMPLES,
    force: bool = False,
) -> ImportResult:
    """Write ``out/<name>/`` from ``description`` (see the module docstring).

    Raises:
        InputError: one line naming the file, key and reason for any bad input; the
            folder is only written when everything checked out.
    """
    description = Path(description)
    if not name or Path(name).name != name or name in (".", "..") or "/" in name:
        raise InputError(description, "--name", f"{name!r} is not a folder name")
    if vendor not in record.VENDORS:
        raise InputError(
            description, "--vendor", f"{vendor!r} is not one of {', '.join(record.VENDORS)}"
        )
    target = Path(out) / name
    if target.exists() and not force:
        raise InputError(target, "--name", "folder exists (use --force to replace it)")
    packages = find_packages([Path(p) for p in package_paths] or [_above_package(description)])
    chain = parse_chain(description_text(description, packages), description, base=base, tip=tip)
    params = derive_opw(chain) or derive_ur(chain)
    fk = check_fk(chain, params) if params is not None else None
    if fk is not None and not fk.ok:  # the README keeps the figures; Drake IK instead
        params = None
    Path(out).mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(dir=out, prefix=f".{name}."))
    try:
        files, sources = convert_meshes(chain, packages, staging)
        licence = _licence(description, packages)
        if licence is not None and sources:
            shutil.copyfile(licence, staging / "meshes" / "LICENSE")
        if sources:
            (staging / "meshes" / "SOURCES.md").write_text(
                record.sources_md(name, sources, licence), encoding="utf-8"
            )
        record.write_urdf(chain, files, staging, name)
        limits, notes = record.limits_record(chain)
        controller = _controller(chain, vendor, params, limits)
        text = record.robot_yaml(
            name=name,
            chain=chain,
            vendor=vendor,
            params=params,
            limits=limits,
            notes=notes,
            controller=controller,
        )
        (staging / PARAMS_FILE).write_text(text, encoding="utf-8")
        _load_staged(staging, name)
        if target.exists():
            shutil.rmtree(target)
        staging.rename(target)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    robot = load_robot(name, Path(out))
    pairs = write_matrix(robot, target / MATRIX_FILE, samples=samples, seed=0)
    (target / "README.md").write_text(
        readme_text(
            name=name,
            chain=chain,
            vendor=vendor,
            params=params,
            fk=fk,
            notes=notes,
            controller=controller,
            packages=packages,
            pairs=pairs,
            samples=samples,
        ),
        encoding="utf-8",
    )
    return ImportResult(target, robot, params, fk, pairs)


def _load_staged(staging: Path, name: str) -> RobotModel:
    """Load the staged folder as a robot (checks robot.yaml as every robot is checked)."""
    link = staging.parent / f".{name}.check"
    shutil.rmtree(link, ignore_errors=True)
    link.mkdir()
    try:
        (link / name).symlink_to(staging.resolve(), target_is_directory=True)
        return load_robot(name, link)
    except ValueError as error:
        raise InputError(staging / PARAMS_FILE, "", str(error)) from None
    finally:
        shutil.rmtree(link, ignore_errors=True)


def _controller(chain: Chain, vendor: str, params, limits: dict) -> dict:
    """robot.yaml ``controller``: language, home, and for FANUC the J2/J3 coupling."""
    controller = {"home_deg": record.home_deg(params, limits)}
    if vendor in record.VENDOR_LANGUAGE:
        controller["language"] = record.VENDOR_LANGUAGE[vendor]
    if vendor == "fanuc":
        # FANUC counts J3 from the horizontal (the ROS-Industrial fanuc_driver's J23
        # linkage): controller J3 = q3 + f q2 with f = u2 · u3, the two parallel axes.
        u, _, _ = axes_at_zero(chain)
        controller["j23_coupled"] = True
        controller["j23_factor"] = int(np.sign(u[1] @ u[2]))
    return controller


def _above_package(description: Path) -> Path:
    """The folder holding the description's ROS package (the first folder up with a
    package.xml), where its sibling packages are; else the description's folder."""
    folder = description.resolve().parent
    for candidate in [folder, *folder.parents]:
        if (candidate / "package.xml").is_file():
            return candidate.parent
    return folder


def _licence(description: Path, packages: dict[str, Path]) -> Path | None:
    """The first LICENSE file in or above the description's package folder."""
    folder = description.resolve().parent
    for candidate in [folder, *folder.parents][:4]:
        for file_name in ("LICENSE", "LICENSE.txt", "LICENSE.md", "license.txt"):
            if (candidate / file_name).is_file():
                return candidate / file_name
    return None
