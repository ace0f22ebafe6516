"""STEP parts built with Open CASCADE, with their exact seams: for the tests (tests/cad)
and scripts/cad_accuracy.py.

Each builder returns the solid; the tests write it to STEP, read it back through the
cell file and compare the planned seam with the analytic edge (the ``*_profile`` and
``rounded_rectangle`` truths below). Lengths in mm.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

PLATE = (300.0, 200.0, 10.0)  # filleted plate: x, y, z sizes [mm]
PLATE_R = 20.0  # the vertical corners' fillet radius [mm]
BRACKET = (100.0, 60.0, 10.0)  # L-bracket: leg length, width (y), thickness [mm]
BRACKET_R = 10.0  # the fillet between the legs [mm]
CYLINDER = (50.0, 40.0, 5.0)  # radius, height, chamfer of the top rim [mm]


def _edges(shape):
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    explorer, found = TopExp_Explorer(shape, TopAbs_EDGE), []
    while explorer.More():
        found.append(TopoDS.Edge(explorer.Current()))
        explorer.Next()
    return found


def _ends(edge):
    from OCP.BRepAdaptor import BRepAdaptor_Curve

    curve = BRepAdaptor_Curve(edge)
    a, b = curve.Value(curve.FirstParameter()), curve.Value(curve.LastParameter())
    return np.array([a.X(), a.Y(), a.Z()]), np.array([b.X(), b.Y(), b.Z()])


def filleted_plate():
    """A 300 x 200 x 10 mm plate, x, y, z ≥ 0, its four vertical edges filleted R20."""
    from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

    box = BRepPrimAPI_MakeBox(*PLATE).Shape()
    fillet = BRepFilletAPI_MakeFillet(box)
    for edge in _edges(box):
        a, b = _ends(edge)
        if np.allclose(a[:2], b[:2]):
            fillet.Add(PLATE_R, edge)
    return fillet.Shape()


def l_bracket():
    """An L of two 100 x 60 x 10 mm legs (horizontal: z ∈ [0, 10]; vertical: x ∈ [0, 10]),
    y ∈ [0, 60], the inside corner filleted R10 (fillet centre line x = z = 20)."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse
    from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.ShapeUpgrade import ShapeUpgrade_UnifySameDomain

    length, width, thick = BRACKET
    horizontal = BRepPrimAPI_MakeBox(length, width, thick).Shape()
    vertical = BRepPrimAPI_MakeBox(thick, width, length).Shape()
    unify = ShapeUpgrade_UnifySameDomain(BRepAlgoAPI_Fuse(horizontal, vertical).Shape())
    unify.Build()
    solid = unify.Shape()
    fillet = BRepFilletAPI_MakeFillet(solid)
    for edge in _edges(solid):
        a, b = _ends(edge)
        if np.allclose([a[0], a[2], b[0], b[2]], thick) and abs(a[1] - b[1]) > 1:
            fillet.Add(BRACKET_R, edge)
    return fillet.Shape()


def chamfered_cylinder():
    """A cylinder R50, 40 mm high on z = 0, its top rim chamfered 5 mm x 45°."""
    from OCP.BRepFilletAPI import BRepFilletAPI_MakeChamfer
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder

    radius, height, chamfer = CYLINDER
    cylinder = BRepPrimAPI_MakeCylinder(radius, height).Shape()
    maker = BRepFilletAPI_MakeChamfer(cylinder)
    for edge in _edges(cylinder):
        a, b = _ends(edge)
        if np.isclose(a[2], height) and np.isclose(b[2], height) and np.allclose(a, b):
            maker.Add(chamfer, edge)
    return maker.Shape()


def write_step(shape, file: Path) -> Path:
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    writer = STEPControl_Writer()
    writer.Transfer(shape, STEPControl_AsIs)
    assert writer.Write(str(file)) == IFSelect_RetDone
    return file


def write_stl(shape, file: Path, tolerance_mm: float) -> Path:
    """The solid tessellated within tolerance_mm, as a binary STL [mm]."""
    import trimesh

    from offline_prog.cad.step_geometry import tessellate

    vertices, triangles, _ = tessellate(shape, tolerance_mm)
    trimesh.Trimesh(vertices, triangles).export(file)
    return file


PLACEMENT = """\
robot:
  model: kuka_kr16_2
  X_IB: {translation: [0, 0, 0]}
tool:
  X_IT: {translation: [1.0, 0.0, 0.5], rotation: !Rpy {deg: [90, 0, 0]}}
motion: {speed: 0.1, max_acceleration: 1.0, max_jerk: 10.0}
"""  # the KR 16 and nozzle of cells/seal_job_kr16.yaml


def cad_cell(tmp_path: Path, model: str, seams: list[dict], **part) -> Path:
    """A KR 16 cell (robot and nozzle as in cells/seal_job_kr16.yaml, the part held
    100 mm below the flange) whose part is ``model`` and whose seams are ``seams``
    (each a dict with a ``cad`` block)."""
    part = {"model": model, **part}
    seams = [
        {"name": f"s{k}", "fit_tolerance_mm": 0.005, "normal_tolerance_deg": 0.05, **s}
        for k, s in enumerate(seams)
    ]
    text = (
        PLACEMENT
        + "part:\n  X_PE: {translation: [0, 0, 0.1], rotation: !Rpy {deg: [180, 0, 0]}}\n"
        + yaml.safe_dump({"part": part}).removeprefix("part:\n")
        + yaml.safe_dump({"seams": seams}, sort_keys=False)
    )
    file = tmp_path / "cell.yaml"
    file.write_text(text)
    return file


def sampled(fit, spacing_m=2e-4):
    """Points [mm] and unit normals of the fitted seam every 0.2 mm."""
    s = np.linspace(0.0, fit.path.length, int(fit.path.length / spacing_m) + 1)
    n = fit.normal(s)[0]
    return fit.path(s, 0)[0] * 1e3, n / np.linalg.norm(n, axis=1, keepdims=True)


def angle_deg(a, b):
    return np.rad2deg(np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.sum(a * b, axis=1)))


def rounded_rectangle(p_mm, z):
    """Distance [mm] to the plate's rounded outline at height z, and the outline's
    outward normal (horizontal) at the nearest point."""
    half = np.array(PLATE[:2]) / 2
    q = np.abs(p_mm[:, :2] - half) - (half - PLATE_R)
    outside = np.maximum(q, 0.0)
    sdf = np.linalg.norm(outside, axis=1) + np.minimum(q.max(axis=1), 0.0) - PLATE_R
    grad = np.where(
        (q > 0).all(axis=1)[:, None],
        outside / np.linalg.norm(outside, axis=1, keepdims=True).clip(1e-12),
        np.eye(2)[np.argmax(q, axis=1)],
    ) * np.sign(p_mm[:, :2] - half)
    normal = np.column_stack([grad, np.zeros(len(grad))])
    return np.hypot(sdf, p_mm[:, 2] - z), normal


def bracket_profile(p_mm):
    """Distance [mm] to the bracket's inner profile at y = 0 (top of the horizontal leg,
    the R10 fillet, the inside of the vertical leg) and its outward normal there."""
    x, z = p_mm[:, 0], p_mm[:, 2]
    centre = 10.0 + BRACKET_R
    on_line_h = np.hypot(np.hypot(np.clip(x, centre, None) - x, z - 10.0), p_mm[:, 1])
    on_line_v = np.hypot(np.hypot(x - 10.0, np.clip(z, centre, None) - z), p_mm[:, 1])
    radial = np.column_stack([x - centre, z - centre])
    r = np.linalg.norm(radial, axis=1)
    in_arc = (x <= centre) & (z <= centre)
    on_arc = np.where(in_arc, np.hypot(r - BRACKET_R, p_mm[:, 1]), np.inf)
    d = np.min([on_line_h, on_line_v, on_arc], axis=0)
    which = np.argmin([on_line_h, on_line_v, on_arc], axis=0)
    towards_centre = -radial / r[:, None]
    normal = np.select(
        [which[:, None] == 0, which[:, None] == 1],
        [np.array([[0.0, 0.0, 1.0]]), np.array([[1.0, 0.0, 0.0]])],
        np.column_stack([towards_centre[:, 0], np.zeros(len(r)), towards_centre[:, 1]]),
    )
    return d, normal
