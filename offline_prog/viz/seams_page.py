"""The page of ``offline-prog seams PART``: the model in 3D with the number of every
face (F), loop (L) and edge chain (C) drawn on it, so a user picks a seam by looking.

A standalone MeshCat page (the same viewer as preview.html, :mod:`viz.static_scene`):
the model's triangles, each loop and chain as a coloured line, and each number as a
sprite that always faces the camera and is never hidden behind the part.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.config.cad_keys import model_kind
from offline_prog.constants import UNIT_SCALE
from offline_prog.errors import InputError
from offline_prog.viz.static_scene import StaticScene

MM = 1e-3
# The page says who wrote it: ``seams`` replaces its own page and no other file.
PAGE_MARK = '<meta name="generator" content="offline-prog seams">'
PAGE_HEAD_BYTES = 8192  # the mark is in the page's head, before the inlined viewer
MODEL_RGBA = (0.75, 0.75, 0.78, 1.0)
LINE_RGBA = {"loop": (0.1, 0.35, 0.9, 1.0), "chain": (0.95, 0.45, 0.05, 1.0)}
PREFIX = {"face": "F", "loop": "L", "chain": "C"}
LABEL_SIZE = 0.09  # of the view's height: the same on screen near and far
LABEL_FONT_PX = 110


def _label(scene: StaticScene, path: str, text: str, p_I: np.ndarray, size: float) -> None:
    """A text sprite centred at p_I [m], ``size`` of the view tall, over everything."""
    texture, material = f"{path}#t", f"{path}#m"
    matrix = np.diag([size, size, size, 1.0])
    matrix[:3, 3] = p_I
    scene._add(
        {
            "type": "set_object",
            "path": path,
            "object": {
                "metadata": {"version": 4.5, "type": "Object"},
                "textures": [
                    {
                        "uuid": texture,
                        "type": "_text",
                        "text": text,
                        "font_size": LABEL_FONT_PX,
                        "font_face": "sans-serif",
                    }
                ],
                "materials": [
                    {
                        "uuid": material,
                        "type": "SpriteMaterial",
                        "map": texture,
                        "transparent": True,
                        "depthTest": False,
                        "color": 0xFFFFFF,
                        "sizeAttenuation": False,
                    }
                ],
                "object": {
                    "uuid": f"{path}#o",
                    "type": "Sprite",
                    "material": material,
                    "matrix": matrix.T.ravel().tolist(),
                    "renderOrder": 10,
                },
            },
        }
    )


def seams_html(catalog) -> str:
    """The page of a :class:`~offline_prog.cad.catalog.Catalog`: the model, its loops and
    chains as lines and every number as a label."""
    scene = StaticScene()
    vertices = np.asarray(catalog.vertices) * MM
    scene.set_mesh("/seams/model", vertices, np.asarray(catalog.triangles), MODEL_RGBA)
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    extent = float(max(high - low))
    for entry in catalog.entries:
        name = f"{PREFIX[entry.kind]}{entry.number}"
        if len(entry.polyline) > 1:
            scene.set_lines(f"/seams/lines/{name}", entry.polyline * MM, LINE_RGBA[entry.kind])
        _label(scene, f"/seams/labels/{name}", name, np.asarray(entry.label_at) * MM, LABEL_SIZE)
    centre = (low + high) / 2
    scene.set_camera(centre + extent * np.array([0.45, -0.6, 0.5]), centre)
    scene.set_property("/Grid", "visible", False)
    scene.set_property("/Axes", "visible", False)
    page = scene.html(f"seams of {Path(catalog.file).name}")
    return page.replace("</title>", f"</title>\n  {PAGE_MARK}", 1)


def model_catalog(part: Path, mesh_units: str = "m", *, set_units: str = "set mesh_units: mm"):
    """The :class:`~offline_prog.cad.catalog.Catalog` of a STEP or mesh file
    (``set_units``: how the user gives a mesh's unit, the hint for one too large).

    Raises:
        InputError: not a model file, unreadable, not a solid, or a mesh larger than a
            cell (one line).
    """
    from offline_prog.cad.catalog import mesh_catalog, step_catalog
    from offline_prog.cad.step_model import ModelError

    part = Path(part)
    kind = model_kind(part.name)
    if kind is None:
        raise InputError(part, "", "not a STEP (.step, .stp) or mesh (.stl, .obj, .ply) file")
    if not part.is_file():
        raise InputError(part, "", "no such file")
    try:
        if kind == "step":
            return step_catalog(part)
        return mesh_catalog(part, UNIT_SCALE[mesh_units] / MM, set_units=set_units)
    except ModelError as error:
        raise InputError(part, "", str(error)) from None


def page_file(part: Path, out: Path | None) -> Path:
    """Where ``seams`` writes its page: ``out``, or ``out/<part stem>_seams.html``.

    Raises:
        InputError: the file is the part model (an input), a folder, not named .html,
            or a file this command did not write (nothing is replaced but its own page).
    """
    target = Path(out) if out is not None else Path("out") / f"{Path(part).stem}_seams.html"
    if target.exists() and Path(part).exists() and os.path.samefile(target, part):
        raise InputError(target, "--out", "is the part model itself (an input)")
    if target.is_dir():
        raise InputError(target, "--out", "is a folder: give the page's file name (.html)")
    if target.suffix.lower() not in (".html", ".htm"):
        raise InputError(target, "--out", "the page is HTML: give a file name ending in .html")
    if not target.exists():
        return target
    try:
        with open(target, "rb") as stream:
            head = stream.read(PAGE_HEAD_BYTES)
    except OSError as error:
        raise InputError(target, "--out", f"cannot read ({error.strerror})") from None
    if PAGE_MARK.encode() not in head:
        raise InputError(
            target, "--out", "exists and is not a page offline-prog seams wrote (not replaced)"
        )
    return target


def run_seams(part: Path, out: Path | None, mesh_units: str, say) -> Path:
    """``offline-prog seams``: list the model's faces, loops and chains (numbers, sizes,
    the cell-file keys that pick each) through ``say`` and write the page (``out``, by
    default ``out/<part stem>_seams.html``: :func:`page_file`).

    Raises:
        InputError: not a model file, unreadable, not a solid, a mesh larger than a
            cell, or an ``out`` that :func:`page_file` refuses (one line; nothing
            written).
    """
    target = page_file(part, out)
    catalog = model_catalog(part, mesh_units, set_units="give --mesh-units mm")
    unit = {"face": "mm²", "loop": "mm", "chain": "mm"}
    for entry in catalog.entries:
        name = f"{PREFIX[entry.kind]}{entry.number}"
        keys = str(entry.keys).replace("'", "")
        say(
            f"  {entry.kind:<5} {name:<4} {entry.size:10.2f} {unit[entry.kind]:<3}  "
            f"{entry.description:<40} cad: {keys}",
            highlight=False,
        )
    write_atomic(target, seams_html(catalog))
    say(f"page      {target}", highlight=False)
    return target
