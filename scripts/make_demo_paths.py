"""Regenerate the demo path files in cells/data (committed; run only to change them).

- tape_cylinder.csv: a tape lane on a cylinder (R = 300 mm, axis along x of P),
  points in mm with the surface normal into the cylinder.
- weld_seam.dxf: an open fillet-weld seam drawn as a SPLINE in the x-y plane of P (mm).

Run: ``python scripts/make_demo_paths.py [--out FOLDER]`` (default: cells/data).
"""

import argparse
from pathlib import Path

import ezdxf
import numpy as np

DATA = Path(__file__).resolve().parents[1] / "cells" / "data"


def tape_cylinder(out: Path, radius_mm: float = 300.0) -> None:
    x = np.linspace(-200.0, 200.0, 161)
    theta = 0.35 * np.sin(np.pi * x / 400.0)  # lane wanders 0.35 rad over the shell
    points = np.stack([x, radius_mm * np.sin(theta), radius_mm * (np.cos(theta) - 1.0)], axis=1)
    normals = -np.stack([np.zeros_like(x), np.sin(theta), np.cos(theta)], axis=1)
    rows = ["x,y,z,nx,ny,nz"] + [
        ",".join(f"{v:.6f}" for v in row) for row in np.hstack([points, normals])
    ]
    (out / "tape_cylinder.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")


def weld_seam(out: Path) -> None:
    document = ezdxf.new(units=ezdxf.units.MM)
    fit_points = [(-150, -40, 0), (-80, 10, 0), (0, 30, 0), (80, 5, 0), (150, -35, 0)]
    document.modelspace().add_spline(fit_points, dxfattribs={"layer": "SEAM"})
    document.modelspace().add_line((-160, -60), (160, -60), dxfattribs={"layer": "OUTLINE"})
    document.saveas(out / "weld_seam.dxf")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DATA, help="folder (cells/data)")
    out = parser.parse_args().out
    out.mkdir(parents=True, exist_ok=True)
    tape_cylinder(out)
    weld_seam(out)
