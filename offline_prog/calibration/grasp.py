"""The grasp X_PE (6 DoF) from part points touched on the tool's tip.

A part-point touch i puts the point p_PK of the gripped part on the tool's tip:
``X_IE_i X_EP p_PK = p_IT``, i.e. the tool's tip seen from the flange,
``p_E_i = X_EI_i p_IT``, is ``X_EP p_PK``. With p_IT known (the pivot, or the cell's),
the pairs (p_PK, p_E_i) give X_EP by Kabsch's rigid fit (scipy's
``Rotation.align_vectors``); it starts the joint estimate. Three points not on one line
fix the rotation; points on one line leave the turn about it free.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.calibration.limits import MIN_PART_POINTS, MIN_PART_SPREAD_MM
from offline_prog.errors import InputError


def grasp_start(
    X_IE: np.ndarray, p_PK: np.ndarray, p_IT: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(p_PE [mm], R_PE (3, 3)): the grasp that puts each touched part point on the tip.

    Args:
        X_IE: (N, 4, 4) flange poses of the part-point touches [m].
        p_PK: (N, 3) the touched points in P [mm].
        p_IT: (3,) the tool's tip in I [mm].
    """
    R_IE, p_IE = X_IE[:, :3, :3], X_IE[:, :3, 3] * 1e3
    p_E = np.einsum("nji,nj->ni", R_IE, p_IT - p_IE)  # the tip in E, per touch
    a, b = p_E - p_E.mean(axis=0), p_PK - p_PK.mean(axis=0)
    R_EP = Rotation.align_vectors(a, b)[0].as_matrix()
    p_EP = p_E.mean(axis=0) - R_EP @ p_PK.mean(axis=0)
    return -R_EP.T @ p_EP, R_EP.T


def check_grasp(file: str, names: list[str], points: dict[str, list[float]]) -> None:
    """At least MIN_PART_POINTS distinct part points, not on one line.

    Args:
        names: the part points touched (each touch's target).
        points: calibration.part_points {name: [x, y, z] mm in P}.

    Raises:
        InputError: one line saying what to touch.
    """
    touched = sorted(set(names))
    if len(touched) < MIN_PART_POINTS:
        others = sorted(set(points) - set(touched))
        raise InputError(
            file,
            "",
            f"{len(touched)} part point(s) touched ({', '.join(touched)}): the grasp needs "
            f"at least {MIN_PART_POINTS} not on one line; touch "
            + (", ".join(others[: MIN_PART_POINTS - len(touched)]) or "more points of the part"),
        )
    p = np.array([points[name] for name in touched], dtype=float)
    spread = np.linalg.svd(p - p.mean(axis=0), compute_uv=False)[1] / np.sqrt(len(p))
    if spread < MIN_PART_SPREAD_MM:
        raise InputError(
            file,
            "",
            f"the part points touched ({', '.join(touched)}) lie on one line ({spread:.1f} mm "
            f"rms off it, need ≥ {MIN_PART_SPREAD_MM:g} mm): touch a point off their line",
        )
