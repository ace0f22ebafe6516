"""The load the robot carries: the gripper (fixed to the flange E) and the part (in P).

Each body's mass properties come from the cell, key by key: the mass
(``gripper.mass_kg``, ``part.mass_kg``); the centre of mass (``center_of_mass_mm``) and
the inertia about it (``inertia_kgm2``: [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] in the body's
frame axes) when given, else those of the body's shapes (``gripper.geometry`` and
``gripper.mesh`` in E; the part's mesh, model and geometry in P) with the mass spread
evenly through their volumes (Drake's ``CalcSpatialInertia`` per shape, summed with
the parallel-axis theorem: shapes that overlap count twice, so a body is best
modelled with touching shapes; a mesh that does not close a volume counts as its
convex hull), else a point mass at the frame's origin. Which one was used is part
of the record (``*_from``).

:func:`payload_record` is the plan's payload record (SI units, JSON-ready): stored in
plan.npz (``ProgramData.payload``) for the program writers and in report.json.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from pydrake.geometry import Convex, Mesh
from pydrake.math import RigidTransform
from pydrake.multibody.tree import CalcSpatialInertia, SpatialInertia

from offline_prog.config.cell import Cell, transform
from offline_prog.scene.shapes import CellShape, cell_geometry

MM = 1e-3
DIGITS = 12  # decimals stored [m, kg m²]: sums of shapes leave 1e-20 where 0 is exact
# (row, column) of the six inertia key entries [Ixx, Iyy, Izz, Ixy, Ixz, Iyz].
INERTIA_KEY_ORDER = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


@dataclasses.dataclass(frozen=True)
class MassProperties:
    """One rigid body's mass properties in its frame O (E for the gripper, P for the part).

    Attributes:
        mass_kg: its mass [kg].
        p_OC: (3,) its centre of mass C from Oo, expressed in O [m].
        I_C: (3, 3) its rotational inertia about C, axes of O [kg m²].
        com_from, inertia_from: where each came from: the cell key (e.g.
            ``gripper.inertia_kgm2``), ``shapes``, or ``frame origin`` / ``point mass``
            when the cell gives neither.
    """

    mass_kg: float
    p_OC: np.ndarray
    I_C: np.ndarray
    com_from: str
    inertia_from: str


def inertia_matrix(values) -> np.ndarray:
    """(3, 3) the symmetric inertia of [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] [kg m²]."""
    matrix = np.zeros((3, 3))
    for value, (i, j) in zip(values, INERTIA_KEY_ORDER, strict=True):
        matrix[i, j] = matrix[j, i] = float(value)
    return matrix


def _unit_density_inertia(shape: CellShape) -> SpatialInertia:
    """M_GGo_G of a shape filled with density 1 kg/m³ (its mass is its volume)."""
    if shape.kind != "mesh":
        return CalcSpatialInertia(shape.collision_shapes()[0], 1.0)
    if shape.mesh.is_watertight:
        return CalcSpatialInertia(Mesh(str(shape.visual_file)), 1.0)
    return CalcSpatialInertia(Convex(str(shape.visual_file)), 1.0)  # its hull


def shapes_mass_properties(shapes: list[CellShape]) -> tuple[float, np.ndarray, np.ndarray]:
    """(volume [m³], centre of volume p_OC (3,) [m], inertia about it per unit density
    (3, 3) [m⁵], axes of O) of shapes posed in their owner's frame O by X_OG."""
    M_OOo_O = SpatialInertia.Zero()
    for shape in shapes:
        M_GGo_O = _unit_density_inertia(shape).ReExpress(shape.X_OG.rotation())
        M_OOo_O += M_GGo_O.Shift(-shape.X_OG.translation())  # about Oo
    volume = M_OOo_O.get_mass()
    if not volume > 0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    p_OC = M_OOo_O.get_com()
    I_C = M_OOo_O.Shift(p_OC).CalcRotationalInertia().CopyToFullMatrix3()
    return volume, p_OC, I_C


def mass_properties(
    mass_kg: float, *, com_mm, inertia_kgm2, shapes: list[CellShape], key: str
) -> MassProperties:
    """A body's mass properties from its keys (``com_mm`` [mm], ``inertia_kgm2``) where
    given, else from its shapes, else a point mass at its frame's origin.

    Args:
        mass_kg: the body's mass [kg].
        com_mm: (3,) the centre of mass in O [mm], or None.
        inertia_kgm2: [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] about the centre of mass [kg m²], or None.
        shapes: the body's CellShapes in O.
        key: the body's key in the cell (``gripper`` or ``part``), naming the sources.
    """
    volume, p_OC, I_unit = shapes_mass_properties(shapes)
    with_shapes = volume > 0
    if com_mm is not None:
        p_OC, com_from = np.asarray(com_mm, float) * MM, f"{key}.center_of_mass_mm"
    elif with_shapes:
        com_from = "shapes"
    else:
        p_OC, com_from = np.zeros(3), "frame origin"
    if inertia_kgm2 is not None:
        I_C, inertia_from = inertia_matrix(inertia_kgm2), f"{key}.inertia_kgm2"
    elif with_shapes:  # the shapes' inertia about their own centre (a given C keeps it)
        I_C, inertia_from = I_unit * (mass_kg / volume), "shapes"
    else:
        I_C, inertia_from = np.zeros((3, 3)), "point mass"
    return MassProperties(float(mass_kg), p_OC, I_C, com_from, inertia_from)


def combined(gripper: MassProperties, part: MassProperties, X_EP: RigidTransform) -> dict:
    """Gripper and part as one load on the flange: mass [kg], centre of mass p_EC (3,)
    [m] in E, inertia about it (3, 3) in E's axes [kg m²], and its principal moments
    (ascending) with their axes (the columns of R_EA, a right-handed frame A) [kg m²]."""
    R_EP = X_EP.rotation().matrix()
    bodies = [(gripper.mass_kg, gripper.p_OC, gripper.I_C)]
    bodies.append((part.mass_kg, X_EP @ part.p_OC, R_EP @ part.I_C @ R_EP.T))
    mass = sum(m for m, _, _ in bodies)
    p_EC = sum(m * p for m, p, _ in bodies) / mass if mass > 0 else np.zeros(3)
    I_C = np.zeros((3, 3))
    for m, p, inertia in bodies:
        d = p - p_EC  # parallel-axis theorem: each body's inertia moved to C
        I_C += inertia + m * (d @ d * np.eye(3) - np.outer(d, d))
    moments, R_EA = np.linalg.eigh((I_C + I_C.T) / 2)
    if np.linalg.det(R_EA) < 0:
        R_EA[:, 2] *= -1
    return {
        "mass_kg": mass,
        "com_E_m": _rounded(p_EC),
        "inertia_E_kgm2": _rounded(I_C),
        "principal_inertia_kgm2": _rounded(moments),
        "R_E_principal": _rounded(R_EA),
    }


def _rounded(values: np.ndarray) -> list:
    return (np.round(values, DIGITS) + 0.0).tolist()  # + 0.0: no -0.0


def _entries(prefix: str, frame: str, body: MassProperties) -> dict:
    return {
        f"{prefix}_mass_kg": body.mass_kg,
        f"{prefix}_com_{frame}_m": _rounded(body.p_OC),
        f"{prefix}_inertia_{frame}_kgm2": _rounded(body.I_C),
        f"{prefix}_com_from": body.com_from,
        f"{prefix}_inertia_from": body.inertia_from,
    }


def payload_record(cell: Cell, cell_file: Path) -> dict:
    """The payload the cell gives, as plan.npz and report.json store it (SI units).

    Keys (each body's only when the cell gives its mass): ``gripper_mass_kg``,
    ``gripper_com_E_m`` (3,), ``gripper_inertia_E_kgm2`` (3, 3) about its centre of
    mass, ``gripper_com_from``, ``gripper_inertia_from``; the same ``part_*`` in P; and
    with both, ``total``: the two as one load on the flange (:func:`combined`, at
    part.X_PE).

    Raises:
        ShapeError: a bad shape entry (one line, naming the key).
    """
    gripper = cell.gripper
    has_gripper = gripper is not None and gripper.mass_kg is not None
    if not has_gripper and cell.part.mass_kg is None:
        return {}
    geometry = cell_geometry(cell, cell_file)
    record, bodies = {}, {}
    if has_gripper:
        bodies["gripper"] = mass_properties(
            gripper.mass_kg,
            com_mm=gripper.center_of_mass_mm,
            inertia_kgm2=gripper.inertia_kgm2,
            shapes=geometry.gripper,
            key="gripper",
        )
        record |= _entries("gripper", "E", bodies["gripper"])
    if cell.part.mass_kg is not None:
        bodies["part"] = mass_properties(
            cell.part.mass_kg,
            com_mm=cell.part.center_of_mass_mm,
            inertia_kgm2=cell.part.inertia_kgm2,
            shapes=geometry.part,
            key="part",
        )
        record |= _entries("part", "P", bodies["part"])
    if len(bodies) == 2:
        X_EP = transform(cell.part.X_PE).inverse()
        record["total"] = combined(bodies["gripper"], bodies["part"], X_EP)
    return record
