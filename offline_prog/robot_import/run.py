"""``offline-prog robots import``: a robot folder from a URDF or xacro description.

Reads the description as data (:mod:`.xacro_sandbox`: no code runs, no file outside the
packages is read), finds the six-revolute chain (:mod:`.chain`), checks its numbers'
units (:mod:`.plausible`), derives its OPW parameters (:mod:`.derive`) and checks them
against Drake's FK of the description (:mod:`.verify`), converts the meshes
(:mod:`.meshes`), writes the URDF, robot.yaml and README (:mod:`.record`), loads the
result as any robot is loaded and computes its self-collision matrix
(:mod:`offline_prog.scene.self_collision`), all in a staged folder swapped in at the
end (:mod:`.folder`).
"""

from __future__ import annotations

import dataclasses
import shutil
import tempfile
from pathlib import Path

import numpy as np

from offline_prog.atomic import staged_folder, temp_prefix
from offline_prog.config.names import MAX_ROBOT_NAME_CHARS, name_problem
from offline_prog.errors import InputError
from offline_prog.robot.kinematics_opw import OpwParameters
from offline_prog.robot.kinematics_ur import UrParameters
from offline_prog.robot.model import PARAMS_FILE, RobotModel, load_robot
from offline_prog.robot_import import record
from offline_prog.robot_import.chain import Chain, parse_chain
from offline_prog.robot_import.derive import STRUCTURE_TOL, axes_at_zero, derive_opw
from offline_prog.robot_import.derive_ur import derive_ur
from offline_prog.robot_import.folder import check_target, mark
from offline_prog.robot_import.meshes import convert_meshes
from offline_prog.robot_import.plausible import check_plausible
from offline_prog.robot_import.readme import readme_text
from offline_prog.robot_import.sources import Packages, packages_for
from offline_prog.robot_import.verify import FkCheck, check_fk
from offline_prog.robot_import.xacro_sandbox import description_text
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
    allow_file_meshes: bool = False,
    j23_coupled: bool | None = None,
) -> ImportResult:
    """Write ``out/<name>/`` from ``description`` (see the module docstring).

    Args:
        allow_file_meshes: read ``file://`` mesh names (anywhere on disk).
        j23_coupled: whether the controller counts axis 3 from the horizontal; needed
            for ``vendor="abb"`` (model-dependent), derived for FANUC, refused else.

    Raises:
        InputError: one line naming the file, key and reason for any bad input; the
            folder is only written when everything checked out, in one step.
    """
    description = Path(description)
    problem = name_problem(name, max_chars=MAX_ROBOT_NAME_CHARS)
    if problem:
        raise InputError(description, "--name", f"{problem}: it names the robot folder")
    if vendor not in record.VENDORS:
        raise InputError(
            description, "--vendor", f"{vendor!r} is not one of {', '.join(record.VENDORS)}"
        )
    _check_coupling_flag(description, vendor, j23_coupled)
    target = Path(out) / name
    check_target(target, force=force)
    packages = packages_for(description, list(package_paths), file_meshes=allow_file_meshes)
    chain = parse_chain(description_text(description, packages), description, base=base, tip=tip)
    check_plausible(chain)
    params = derive_opw(chain) or derive_ur(chain)
    fk = check_fk(chain, params) if params is not None else None
    if fk is not None and not fk.ok:  # the README keeps the figures; Drake IK instead
        params = None
    limits, notes = record.limits_record(chain)
    controller = _controller(chain, vendor, params, limits, j23_coupled)
    with staged_folder(target) as staging:
        files, sources = convert_meshes(chain, packages, staging)
        licence = _licence(description, packages)
        if licence is not None and sources:
            shutil.copyfile(licence, staging / "meshes" / "LICENSE")
        if sources:
            (staging / "meshes" / "SOURCES.md").write_text(
                record.sources_md(name, sources, licence, packages), encoding="utf-8"
            )
        record.write_urdf(chain, files, staging, name)
        # What robot.yaml and the README both say.
        facts = {
            "name": name,
            "chain": chain,
            "vendor": vendor,
            "params": params,
            "notes": notes,
            "controller": controller,
            "source": packages.display(description),
        }
        text = record.robot_yaml(**facts, limits=limits)
        (staging / PARAMS_FILE).write_text(text, encoding="utf-8")
        staged = _load_staged(staging, name)
        pairs = write_matrix(staged, staging / MATRIX_FILE, samples=samples, seed=0)
        readme = readme_text(**facts, fk=fk, packages=packages, pairs=pairs, samples=samples)
        (staging / "README.md").write_text(readme, encoding="utf-8")
        mark(staging)
        check_target(target, force=force)  # again: a folder may have appeared meanwhile
    return ImportResult(target, load_robot(name, Path(out)), params, fk, pairs)


def _load_staged(staging: Path, name: str) -> RobotModel:
    """Load the staged folder as a robot (checks robot.yaml as every robot is checked);
    its URDF path is the staged one, so the matrix is computed from the staged files."""
    check = Path(tempfile.mkdtemp(dir=staging.parent, prefix=temp_prefix("check")))
    try:
        (check / name).symlink_to(staging.resolve(), target_is_directory=True)
        return load_robot(name, check)
    except ValueError as error:
        raise InputError(staging / PARAMS_FILE, "", str(error)) from None
    finally:
        shutil.rmtree(check, ignore_errors=True)


def _check_coupling_flag(description: Path, vendor: str, j23_coupled: bool | None) -> None:
    """ABB's J2/J3 coupling differs by model; FANUC's is the controller's convention;
    the other vendors' controllers count the URDF's axes."""
    if vendor == "abb" and j23_coupled is None:
        raise InputError(
            description,
            "--vendor abb",
            "ABB models differ: say whether the controller counts axis 3 from the horizontal "
            "(--j23-coupled, e.g. the IRB 2400's parallel arm) or from the upper arm "
            "(--no-j23-coupled); the abb_driver's J23_coupled parameter of your model",
        )
    if vendor not in ("abb", "fanuc") and j23_coupled:
        raise InputError(
            description, "--j23-coupled", f"a {vendor} controller counts the URDF's axes"
        )
    if vendor == "fanuc" and j23_coupled is False:
        raise InputError(
            description,
            "--no-j23-coupled",
            "FANUC controllers count J3 from the horizontal (the fanuc_driver's J23 linkage)",
        )


def _controller(chain: Chain, vendor: str, params, limits: dict, j23_coupled) -> dict:
    """robot.yaml ``controller``: language, home, and the J2/J3 coupling (FANUC always,
    ABB when ``j23_coupled``)."""
    controller = {"home_deg": record.home_deg(params, limits)}
    if vendor in record.VENDOR_LANGUAGE:
        controller["language"] = record.VENDOR_LANGUAGE[vendor]
    if vendor == "fanuc" or (vendor == "abb" and j23_coupled):
        # The controller counts J3 from the horizontal (ROS-Industrial fanuc_driver's
        # J23 linkage, abb_driver's J23_coupled): J3 = q3 + f q2 with f = u2 · u3, the
        # two parallel axes' directions.
        u, _, _ = axes_at_zero(chain)
        factor = int(np.sign(u[1] @ u[2]))
        if abs(abs(u[1] @ u[2]) - 1) > STRUCTURE_TOL:
            raise InputError(
                chain.file, "--vendor", "axes 2 and 3 are not parallel: no J2/J3 coupling fits"
            )
        if vendor == "abb" and factor != 1:
            raise InputError(
                chain.file,
                "--j23-coupled",
                "axes 2 and 3 turn opposite ways in this URDF; the RAPID writer counts "
                "axis 3 = q2 + q3 (same directions), so the program would be wrong",
            )
        controller["j23_coupled"] = True
        if factor != 1:
            controller["j23_factor"] = factor
    return controller


def _licence(description: Path, packages: Packages) -> Path | None:
    """The first LICENSE file in or above the description's folder, inside the
    folders the description may read."""
    folder = description.resolve().parent
    for candidate in [folder, *folder.parents][:4]:
        for file_name in ("LICENSE", "LICENSE.txt", "LICENSE.md", "license.txt"):
            file = candidate / file_name
            if file.is_file() and any(file.resolve().is_relative_to(r) for r in packages.roots):
                return file.resolve()
    return None
