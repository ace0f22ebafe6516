"""The load the robot carries: the gripper (fixed to the flange E) and the part (P).

The record is the plan's (``scene.payload.payload_record``, stored in plan.npz): the
gripper's mass and centre of mass in E, the part's in P, their inertias and the two as
one load. A program states the load only when both masses are given, and never a load
the cell does not give: ``export`` of a controller program refuses a plan without them
(one line: add the masses, or ``--no-payload``), and ``plan`` writes its programs
without a load statement; then every program header and report.json say that the
payload is not set and the controller's active load is used, so that nobody runs the
robot with a wrong load unknowingly. The programs write the inertia the record gives
(about each load's centre of mass) as principal moments and their axes, the way KRL
``$LOAD`` and RAPID ``loaddata`` take it (a point mass: all zero).
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class Principal:
    """An inertia about a centre of mass as its principal ``moments`` (3,) [kg m²] and
    their axes, the columns of ``R`` (3, 3) (a right-handed frame) in the frame the
    inertia was given in."""

    moments: np.ndarray
    R: np.ndarray


def principal(inertia: np.ndarray) -> Principal:
    """The principal moments (ascending) and axes of an inertia matrix (3, 3) [kg m²]."""
    inertia = np.asarray(inertia, float)
    moments, R = np.linalg.eigh((inertia + inertia.T) / 2)
    if np.linalg.det(R) < 0:
        R[:, 2] *= -1
    return Principal(np.maximum(moments, 0.0), R)


@dataclasses.dataclass(frozen=True)
class Payload:
    """Masses [kg] and centres of mass [m]: the gripper's p_EG in E, the part's p_PC in
    P; inertias about them [kg m²]: the gripper's I_G_E in E's axes, the part's I_C_P in
    P's, and both as one load on the flange (``total_inertia``: the record's, at the
    plan's grasp; None: a record without it)."""

    gripper_mass_kg: float
    p_EG: np.ndarray
    part_mass_kg: float
    p_PC: np.ndarray
    I_G_E: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((3, 3)))
    I_C_P: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((3, 3)))
    total_inertia: Principal | None = None

    def total(self, X_EP: np.ndarray) -> tuple[float, np.ndarray]:
        """(mass [kg], centre of mass (3,) in E [m]) of gripper and part together,
        the part frame P at X_EP (4, 4) in E."""
        mass = self.gripper_mass_kg + self.part_mass_kg
        p_EC = X_EP[:3, :3] @ self.p_PC + X_EP[:3, 3]
        weighted = self.gripper_mass_kg * self.p_EG + self.part_mass_kg * p_EC
        return mass, weighted / mass if mass > 0 else np.zeros(3)


def payload(record: dict | None) -> Payload | None:
    """The Payload of a stored record, or None unless both masses are given."""
    record = record or {}
    if "gripper_mass_kg" not in record or "part_mass_kg" not in record:
        return None
    zero = np.zeros((3, 3))
    total = record.get("total")
    return Payload(
        float(record["gripper_mass_kg"]),
        np.asarray(record["gripper_com_E_m"], float),
        float(record["part_mass_kg"]),
        np.asarray(record["part_com_P_m"], float),
        np.asarray(record.get("gripper_inertia_E_kgm2", zero), float),
        np.asarray(record.get("part_inertia_P_kgm2", zero), float),
        None
        if total is None
        else Principal(
            np.asarray(total["principal_inertia_kgm2"], float),
            np.asarray(total["R_E_principal"], float),
        ),
    )


def missing_keys(record: dict | None) -> list[str]:
    """The cell keys of the masses the record lacks, as the user writes them."""
    return [
        cell_key
        for key, cell_key in (
            ("gripper_mass_kg", "gripper.mass_kg"),
            ("part_mass_kg", "part.mass_kg"),
        )
        if key not in (record or {})
    ]


def refusal(record: dict | None) -> str:
    """Why export refuses a controller program of a plan without both masses, and the
    way out ("" when the record has them)."""
    if payload(record) is not None:
        return ""
    return (
        f"the cell gives no {' / '.join(missing_keys(record))}: add the masses to the cell "
        "and plan again, or export with --no-payload (no load statement; the controller's "
        "active load is used)"
    )


def payload_note(record: dict | None, X_EP: np.ndarray, *, written: bool = True) -> str:
    """One header line: the payload written, or a warning naming the missing keys;
    ``written`` False: the user asked for no load statement (``--no-payload``)."""
    load = payload(record)
    if load is None:
        return (
            f"WARNING: PAYLOAD NOT SET (the cell gives no {' / '.join(missing_keys(record))}): "
            "no load statement, the controller's active load is used: set the load of "
            "gripper and part on the controller before running."
        )
    if not written:
        return (
            "Payload: not written (--no-payload): the controller's active load is used; "
            "set the load of gripper and part on the controller before running."
        )
    mass, p_EC = load.total(X_EP)
    return (
        f"Payload: gripper {load.gripper_mass_kg:g} kg + part {load.part_mass_kg:g} kg = "
        f"{mass:g} kg, centre of mass [{', '.join(f'{v:.1f}' for v in p_EC * 1e3)}] mm in the "
        "flange frame; "
        + (
            "inertia not given (point mass)."
            if load.total_inertia is None
            else "principal moments of inertia about it ["
            + ", ".join(f"{v:.4g}" for v in load.total_inertia.moments)
            + "] kg m²."
        )
    )
