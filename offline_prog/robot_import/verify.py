"""Drake's forward kinematics of the description against the derived kinematic model.

The description's own chain (its links and joints base → tip, without geometry, so that
no mesh needs resolving) is loaded into a MultibodyPlant; tool0's pose in base_link at seeded
configurations within the joint limits is compared with the OPW model's.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET

import numpy as np
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant

from offline_prog.robot import kinematics_opw, kinematics_ur
from offline_prog.robot.kinematics_opw import OpwParameters
from offline_prog.robot.kinematics_ur import UrParameters
from offline_prog.robot_import.chain import Chain

VERIFY_SAMPLES = 1000
VERIFY_TOL_M = 1e-9  # position, and rotation as the largest |ΔR| entry (≈ rad)


@dataclasses.dataclass(frozen=True)
class FkCheck:
    """Largest position [m] and rotation [rad] difference over ``samples`` seeded
    configurations (seed ``seed``); ``ok`` when both are within VERIFY_TOL_M."""

    samples: int
    seed: int
    max_position_m: float
    max_rotation_rad: float

    @property
    def ok(self) -> bool:
        return self.max_position_m <= VERIFY_TOL_M and self.max_rotation_rad <= VERIFY_TOL_M


def kinematic_urdf(chain: Chain) -> str:
    """The chain base → tip alone as URDF text: its links (no geometry, no inertia) and
    its joints (name, type, parent, child, origin, axis, limit). Whatever else the
    description holds (a ``world`` link fixed to the base, materials, grippers) stays
    out of Drake's way."""
    robot = ET.Element("robot", name="chain")
    for link in chain.links:
        ET.SubElement(robot, "link", name=link)
    sources = {j.get("name"): j for j in chain.root.findall("joint")}
    for joint in chain.joints:
        source = sources[joint.name]
        copy = ET.SubElement(robot, "joint", name=joint.name, type=joint.kind)
        for tag in ("parent", "child", "origin", "axis", "limit"):
            if source.find(tag) is not None:
                copy.append(ET.fromstring(ET.tostring(source.find(tag))))
    return ET.tostring(robot, encoding="unicode")


def check_fk(
    chain: Chain,
    params: OpwParameters | UrParameters,
    *,
    samples: int = VERIFY_SAMPLES,
    seed: int = 0,
) -> FkCheck:
    """Compare Drake's FK of the description (base → tip of ``chain``) with the OPW or
    UR model's on ``samples`` uniform configurations within the URDF limits."""
    plant = MultibodyPlant(time_step=0.0)
    (model,) = Parser(plant).AddModelsFromString(kinematic_urdf(chain), "urdf")
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(chain.base, model))
    plant.Finalize()
    context = plant.CreateDefaultContext()
    joints = [plant.GetJointByName(j.name, model) for j in chain.revolute]
    base, tip = plant.GetFrameByName(chain.base, model), plant.GetFrameByName(chain.tip, model)
    rng = np.random.default_rng(seed)
    lower = np.array([j.lower for j in chain.revolute])
    upper = np.array([j.upper for j in chain.revolute])
    q = rng.uniform(lower, upper, size=(samples, 6))
    module = kinematics_ur if isinstance(params, UrParameters) else kinematics_opw
    X_opw = module.forward(params, q)
    worst_p = worst_R = 0.0
    for k in range(samples):
        for joint, value in zip(joints, q[k], strict=True):
            joint.set_angle(context, value)
        X_BE = plant.CalcRelativeTransform(context, base, tip).GetAsMatrix4()
        worst_p = max(worst_p, float(np.linalg.norm(X_BE[:3, 3] - X_opw[k, :3, 3])))
        worst_R = max(worst_R, float(np.abs(X_BE[:3, :3] - X_opw[k, :3, :3]).max()))
    return FkCheck(samples, seed, worst_p, worst_R)
