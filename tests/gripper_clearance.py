"""An independent check of a plan's gripper clearance: python-fcl on the flange poses of
trajectory.csv, with shapes built here from the cell's keys (not the planner's Drake
SceneGraph, its convex pieces or its filters).

The gripper's shapes (``gripper.geometry``, in E) are posed at X_IE · X_EG on every row;
the tool's (in T) at X_IT · X_TG and the obstacles at X_IG. FCL's primitives are
centred on their frame, cylinders and capsules along z, as the cell file's.
"""

import csv
from pathlib import Path

import fcl
import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.config.cell import load_cell, transform

MM = 1e-3
# The rows are the planner's samples, where it held the clearance on the same shapes:
# FCL's GJK and the CSV's 10 digits agree with it to far better than this [m].
GRIPPER_CLEARANCE_TOL_M = 1e-5


def _geometry(shape) -> fcl.CollisionGeometry:
    if shape.shape == "box":
        return fcl.Box(*(v * MM for v in shape.size_mm))
    if shape.shape == "sphere":
        return fcl.Sphere(shape.radius_mm * MM)
    kind = {"cylinder": fcl.Cylinder, "capsule": fcl.Capsule}[shape.shape]
    return kind(shape.radius_mm * MM, shape.length_mm * MM)


def _objects(shapes, X_IO: np.ndarray) -> list[tuple[str, fcl.CollisionObject, np.ndarray]]:
    """(name, FCL object at X_IG, X_OG (4, 4)) of each primitive shape in frame O."""
    out = []
    for shape in shapes:
        X_OG = transform(shape.pose).GetAsMatrix4()
        X_IG = X_IO @ X_OG
        out.append(
            (
                shape.name,
                fcl.CollisionObject(_geometry(shape), fcl.Transform(X_IG[:3, :3], X_IG[:3, 3])),
                X_OG,
            )
        )
    return out


def flange_poses(trajectory_csv: Path) -> np.ndarray:
    """(N, 4, 4) X_IE of every row of trajectory.csv (x, y, z [m]; α, β, γ: XYZ Euler)."""
    with open(trajectory_csv, encoding="utf-8") as stream:
        rows = list(csv.reader(stream))
    col = {name: i for i, name in enumerate(rows[0])}
    table = np.array(
        [[float(r[col[k]]) for k in ("x", "y", "z", "alpha", "beta", "gamma")] for r in rows[1:]]
    )
    X = np.tile(np.eye(4), (len(table), 1, 1))
    X[:, :3, :3] = Rotation.from_euler("XYZ", table[:, 3:]).as_matrix()
    X[:, :3, 3] = table[:, :3]
    return X


def gripper_clearance(cell_file: Path, trajectory_csv: Path) -> tuple[float, tuple[str, str], int]:
    """(smallest distance [m] of any gripper shape to the tool's shapes and the
    obstacles, that pair's names, the row) over every row of the trajectory."""
    cell = load_cell(cell_file)
    X_IT = transform(cell.tool.X_IT).GetAsMatrix4()
    fixed = _objects(cell.tool.geometry, X_IT) + _objects(cell.obstacles, np.eye(4))
    gripper = _objects(cell.gripper.geometry, np.eye(4))
    request, best = fcl.DistanceRequest(), (np.inf, ("", ""), -1)
    for row, X_IE in enumerate(flange_poses(trajectory_csv)):
        for name, body, X_EG in gripper:
            X_IG = X_IE @ X_EG
            body.setTransform(fcl.Transform(X_IG[:3, :3], X_IG[:3, 3]))
            for other, obstacle, _ in fixed:
                d = fcl.distance(body, obstacle, request, fcl.DistanceResult())
                if d < best[0]:
                    best = (float(d), (name, other), row)
    return best
