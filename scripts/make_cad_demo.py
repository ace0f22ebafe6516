"""Regenerate the demo STEP part in cells/data (committed; run only to change it).

Run: ``python scripts/make_cad_demo.py [--out FOLDER]`` (default: cells/data).

seal_plate.step: a 400 x 300 x 8 mm plate in the part frame P of the seal demos (P at
the centre of its underside, z up into the plate), its vertical corners rounded R30
and the rim of its underside chamfered 3 mm x 45°. cells/cad_seal_kr16.yaml seals the
underside's outer loop and runs a bead along the chamfer of one long side and its
corners, the nozzle square to the chamfer.
"""

import argparse
from pathlib import Path

from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.BRepFilletAPI import BRepFilletAPI_MakeChamfer, BRepFilletAPI_MakeFillet
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
from OCP.gp import gp_Pnt
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
from OCP.TopAbs import TopAbs_EDGE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

DATA = Path(__file__).resolve().parents[1] / "cells" / "data"
SIZE_MM = (400.0, 300.0, 8.0)
CORNER_RADIUS_MM = 30.0
CHAMFER_MM = 3.0


def _edges(shape):
    explorer = TopExp_Explorer(shape, TopAbs_EDGE)
    while explorer.More():
        edge = TopoDS.Edge(explorer.Current())
        curve = BRepAdaptor_Curve(edge)
        a, b = curve.Value(curve.FirstParameter()), curve.Value(curve.LastParameter())
        yield edge, (a.X(), a.Y(), a.Z()), (b.X(), b.Y(), b.Z())
        explorer.Next()


def seal_plate():
    x, y, z = SIZE_MM
    box = BRepPrimAPI_MakeBox(gp_Pnt(-x / 2, -y / 2, 0.0), x, y, z).Shape()
    fillet = BRepFilletAPI_MakeFillet(box)
    for edge, a, b in _edges(box):
        if abs(a[0] - b[0]) < 1e-9 and abs(a[1] - b[1]) < 1e-9:  # vertical
            fillet.Add(CORNER_RADIUS_MM, edge)
    rounded = fillet.Shape()
    chamfer = BRepFilletAPI_MakeChamfer(rounded)
    for edge, a, b in _edges(rounded):
        if abs(a[2]) < 1e-9 and abs(b[2]) < 1e-9:  # the underside's rim (propagates)
            chamfer.Add(CHAMFER_MM, edge)
            break
    return chamfer.Shape()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=DATA, help="folder for seal_plate.step (cells/data)"
    )
    out = parser.parse_args().out
    out.mkdir(parents=True, exist_ok=True)
    Interface_Static.SetCVal_s("write.step.schema", "AP214IS")
    writer = STEPControl_Writer()
    writer.Transfer(seal_plate(), STEPControl_AsIs)
    if writer.Write(str(out / "seal_plate.step")) != IFSelect_RetDone:
        raise SystemExit(f"error: {out / 'seal_plate.step'}: the STEP writer failed")


if __name__ == "__main__":
    main()
