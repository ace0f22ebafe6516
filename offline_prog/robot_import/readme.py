"""README.md of an imported robot folder: where every number came from, and the checks."""

from __future__ import annotations

import numpy as np

from offline_prog.robot.kinematics_opw import OpwParameters
from offline_prog.robot.kinematics_ur import UrParameters
from offline_prog.robot_import.chain import Chain
from offline_prog.robot_import.sources import Packages
from offline_prog.robot_import.verify import VERIFY_TOL_M, FkCheck


def readme_text(
    *,
    name: str,
    chain: Chain,
    vendor: str,
    params: OpwParameters | None,
    fk: FkCheck | None,
    notes: list[str],
    controller: dict,
    packages: Packages,
    source: str,
    pairs: list,
    samples: int,
) -> str:
    """The folder's README (Markdown); paths appear without the user's folders
    (``source`` and the packages as :meth:`Packages.display` gives them)."""
    joints = chain.revolute
    rows = "".join(
        f"| {j.name} | {np.degrees(j.lower):.3f} .. {np.degrees(j.upper):.3f} | "
        f"{f'{np.degrees(j.velocity):.3f}' if j.velocity else 'not given'} |\n"
        for j in joints
    )
    counts = {
        kind: sum(p.kind == kind for p in pairs)
        for kind in ("adjacent", "always", "constant", "never", "check")
    }
    kinematics = "## Kinematics\n\n" + _kinematics(chain, params, fk) + "\n"
    coupling = _coupling(vendor, controller)
    return (
        f"# {name}\n\nImported by `offline-prog robots import` from `{source}` "
        f"(vendor: {vendor}). Files: `{name}.urdf` (the chain `{chain.base}` -> `{chain.tip}` of "
        "the description; joint names, origins, axes, limits unchanged; links off the chain "
        "dropped; base and tip named `base_link` and `tool0`), `robot.yaml`, "
        "`self_collision.yaml`, `meshes/` (`meshes/SOURCES.md`: every source file and what was "
        "done to it).\n\nROS packages used: "
        + (", ".join(f"`{k}`" for k in sorted(packages.folders)) or "none")
        + "\n\n"
        + kinematics
        + "\n## Limits\n\n| joint | position [deg] | velocity [deg/s] |\n| --- | --- | --- |\n"
        + rows
        + "\n"
        + "".join(f"- {note}\n" for note in notes)
        + coupling
        + "\n## Self-collision\n\n"
        + f"`self_collision.yaml`, {samples} sampled configurations, seed 0: "
        + ", ".join(f"{v} {k}" for k, v in counts.items())
        + " pairs; the planner checks the `check` pairs.\n"
    )


def _coupling(vendor: str, controller: dict) -> str:
    """The Controller axes section of a J2/J3-coupled robot ("" for the others)."""
    if not controller.get("j23_coupled"):
        return ""
    factor = controller.get("j23_factor", 1)
    source = (
        "The ROS-Industrial FANUC driver converts between the two the same way "
        "(ros-industrial/fanuc, `fanuc_driver`: the J23 linkage correction, parameter "
        "`J23_factor`)."
        if vendor == "fanuc"
        else "As the ROS-Industrial ABB driver's `J23_coupled` parameter (given on the "
        "command line: `--j23-coupled`)."
    )
    return (
        f"\n## Controller axes\n\nThe {vendor.upper()} controller counts J3 from the "
        f"horizontal, not from the upper arm: controller J3 = q3 + ({factor}) q2 of this URDF "
        "(`controller: {j23_coupled: true, j23_factor: ...}`; the factor is the dot product "
        f"of the URDF's parallel axes 2 and 3). {source} The URDF's position limits are the "
        "controller's axis ranges and apply to the controller's axes.\n"
    )


def _kinematics(chain: Chain, params, fk: FkCheck | None) -> str:
    """The Kinematics section: the derived parameters and the FK check, or why none."""
    if params is None:
        return (
            "**No closed form.** The chain is neither ortho-parallel with a spherical wrist "
            "nor a UR-type arm in UR's conventions (or the derived parameters did not "
            "reproduce its FK"
            + (f": {fk.max_position_m:.1e} m" if fk is not None else "")
            + "), so `family: drake`: joint paths come from Drake's InverseKinematics, slower "
            "and one solution per pose.\n"
        )
    if isinstance(params, UrParameters):
        text = (
            "UR form (UR's Denavit-Hartenberg lengths, `kinematics_ur`), read off the joint "
            "axes and fitted to the URDF's FK:\n\n"
            + "".join(
                f"- {k}: {getattr(params, k):g} m\n" for k in ("d1", "a2", "a3", "d4", "d5", "d6")
            )
        )
    else:
        text = (
            "OPW (ortho-parallel base, spherical wrist; Brandstötter et al. 2014, "
            "opw_kinematics conventions), derived from the URDF's joint origins and axes at "
            "q = 0:\n\n"
            + "".join(
                f"- {k}: {getattr(params, k):g} m\n"
                for k in ("a1", "a2", "b", "c1", "c2", "c3", "c4")
            )
            + f"- offsets: {[round(float(np.degrees(o)), 6) for o in params.offsets]} deg\n"
            f"- sign corrections: {list(params.sign_corrections)}\n"
        )
    return text + (
        f"\nCheck: Drake's FK of the description (`{chain.base}` -> `{chain.tip}`) against "
        f"this model on {fk.samples} uniform configurations within the limits (seed "
        f"{fk.seed}): max position difference {fk.max_position_m:.1e} m, max rotation-matrix "
        f"entry difference {fk.max_rotation_rad:.1e} (tolerance {VERIFY_TOL_M:g}).\n"
    )
