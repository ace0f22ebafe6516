"""A description's link geometry converted as the bundled robots' was.

For each link on the chain, its ``<visual>`` and ``<collision>`` meshes are read with
trimesh (STL, OBJ, PLY, GLB; COLLADA needs pycollada), scaled, moved from the mesh's
``<origin>`` into the link frame (the transform is applied to the vertices, so the
written URDF's origins are zero) and written as Wavefront OBJ in metres, coordinates
rounded to 10 µm: ``meshes/visual/<link>.obj`` (+ ``.mtl`` with the URDF material's
colour, normals split at edges sharper than 30°) and ``meshes/collision/<link>.obj``.
Drake uses a collision mesh's convex hull, so a concave collision mesh is written as
CoACD convex pieces ``<link>_<k>.obj`` instead. Nothing is simplified. Each file's
source, checksum and transform go to ``meshes/SOURCES.md``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from offline_prog.errors import InputError
from offline_prog.robot_import.chain import Chain, floats, origin
from offline_prog.robot_import.plausible import MAX_CHAIN_LENGTH_M
from offline_prog.robot_import.sources import Packages, resolve_uri

DIGITS = 5  # 10 µm in metres, as the bundled meshes
SMOOTH_ANGLE_DEG = 30.0
CONVEX_VOLUME_RATIO = 0.999  # mesh volume / hull volume above this: convex already
DEFAULT_RGBA = (0.7, 0.7, 0.7, 1.0)


@dataclasses.dataclass(frozen=True)
class MeshSource:
    """One converted file: the link, its role (visual | collision), the written files
    (relative to the robot folder), the source file, its sha256, the mesh origin in the
    link frame (xyz [m], rpy [rad]), scale, triangles and whether it was decomposed."""

    link: str
    role: str
    written: tuple[str, ...]
    source: Path
    sha256: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    scale: tuple[float, float, float]
    triangles: int
    pieces: int


def convert_meshes(
    chain: Chain, packages: Packages, out: Path
) -> tuple[dict[str, dict[str, list[str]]], list[MeshSource]]:
    """Write every chain link's meshes under ``out/meshes``.

    Returns:
        (files, sources): files[link][role] = the written OBJ paths relative to
        ``out`` (the URDF's ``<mesh filename>``), and one MeshSource per source mesh.

    Raises:
        InputError: a mesh file that is missing or unreadable, a package not found.
    """
    import trimesh

    files: dict[str, dict[str, list[str]]] = {}
    sources: list[MeshSource] = []
    links = {link.get("name"): link for link in chain.root.findall("link")}
    materials = {m.get("name"): m for m in chain.root.findall("material")}
    for name in chain.links:
        for role in ("visual", "collision"):
            meshes, colours = [], []
            for element in links[name].findall(role):
                loaded = _load(element, chain, packages, name, role, trimesh)
                if loaded is None:
                    continue
                mesh, source = loaded
                meshes.append(mesh)
                visual = role == "visual"
                colours.append(
                    material_rgba(element, materials, chain.file) if visual else DEFAULT_RGBA
                )
                sources.append(source)
            if meshes:
                written = _write(out, name, role, meshes, colours, trimesh)
                files.setdefault(name, {})[role] = written
                for index, source in enumerate(sources[-len(meshes) :]):
                    sources[-len(meshes) + index] = dataclasses.replace(
                        source, written=tuple(written), pieces=len(written)
                    )
    return files, sources


def _load(element: ET.Element, chain: Chain, packages, link: str, role: str, trimesh):
    geometry = element.find("geometry")
    mesh_element = geometry.find("mesh") if geometry is not None else None
    if mesh_element is None:
        return None  # primitives are kept as they are (see record.write_urdf)
    uri = mesh_element.get("filename", "")
    file = resolve_uri(uri, packages, base_dir=chain.file.parent, file=chain.file)
    scale = floats(mesh_element.get("scale", "1 1 1"), 3, chain.file, f"{uri} scale")
    try:
        mesh = trimesh.load(file, force="mesh")
    except Exception as error:  # trimesh raises many kinds for unreadable files
        raise InputError(
            chain.file, uri, f"mesh unreadable ({' '.join(str(error).split())})"
        ) from None
    if not len(getattr(mesh, "faces", ())):
        raise InputError(chain.file, uri, "mesh has no triangles")
    X_LG = origin(element.find("origin"), chain.file, f"link {link} {role}")
    mesh.apply_scale(scale)
    mesh.apply_transform(X_LG.GetAsMatrix4())
    if mesh.extents.max() > MAX_CHAIN_LENGTH_M:
        raise InputError(
            chain.file,
            uri,
            f"the mesh is {mesh.extents.max():.4g} m across, more than {MAX_CHAIN_LENGTH_M:g} m: "
            'a mesh in millimetres needs <mesh scale="0.001 0.001 0.001">',
        )
    rpy = X_LG.rotation().ToRollPitchYaw().vector()
    source = MeshSource(
        link,
        role,
        (),
        file,
        hashlib.sha256(file.read_bytes()).hexdigest(),
        tuple(X_LG.translation()),
        tuple(rpy),
        tuple(scale),
        len(mesh.faces),
        1,
    )
    return mesh, source


def material_rgba(element: ET.Element, materials: dict, file: Path) -> tuple[float, ...]:
    """The colour (r, g, b, a) of a ``<visual>``: its material's ``<color rgba>``, or
    the named top-level material's; DEFAULT_RGBA when neither gives one.

    Raises:
        InputError: an rgba that is not four numbers in [0, 1].
    """
    material = element.find("material")
    if material is not None and material.find("color") is None:
        material = materials.get(material.get("name"), material)
    colour = material.find("color") if material is not None else None
    if colour is None:
        return DEFAULT_RGBA
    text = colour.get("rgba", "")
    key = f"material {material.get('name') or ''} color rgba".replace("  ", " ")
    try:
        rgba = tuple(float(v) for v in text.split())
    except ValueError:
        rgba = ()
    if len(rgba) != 4 or not all(0.0 <= v <= 1.0 for v in rgba):
        raise InputError(file, key, f"expected four numbers in [0, 1], got {text!r}")
    return rgba


def _write(out: Path, link: str, role: str, meshes, colours, trimesh) -> list[str]:
    folder = out / "meshes" / role
    folder.mkdir(parents=True, exist_ok=True)
    header = f"# {link}: {role} mesh, metres, in the URDF link frame '{link}' (see ../SOURCES.md)\n"
    if role == "visual":
        groups = [
            (f"m{k}", trimesh.graph.smooth_shade(m, angle=np.radians(SMOOTH_ANGLE_DEG)))
            for k, m in enumerate(meshes)
        ]
        (folder / f"{link}.mtl").write_text(
            header
            + "".join(
                f"newmtl {name}\nKa 0 0 0\nKd {r:g} {g:g} {b:g}\nd {a:g}\n"
                "Ks 0.05 0.05 0.05\nNs 10\nillum 2\n\n"
                for (name, _), (r, g, b, a) in zip(groups, colours, strict=True)
            ),
            encoding="utf-8",
        )
        (folder / f"{link}.obj").write_text(
            header + f"mtllib {link}.mtl\n" + _obj(groups, True), encoding="utf-8"
        )
        return [f"meshes/visual/{link}.obj"]
    merged = trimesh.util.concatenate(meshes)
    hull = merged.convex_hull
    if merged.is_watertight and merged.volume >= CONVEX_VOLUME_RATIO * hull.volume:
        pieces = [merged]
    else:
        import coacd

        coacd.set_log_level("error")
        parts = coacd.run_coacd(coacd.Mesh(merged.vertices, merged.faces), seed=0)
        pieces = [trimesh.Trimesh(v, f, process=False) for v, f in parts]
    names = [f"{link}.obj"] if len(pieces) == 1 else [f"{link}_{k}.obj" for k in range(len(pieces))]
    for name, piece in zip(names, pieces, strict=True):
        (folder / name).write_text(header + _obj([(None, piece)], False), encoding="utf-8")
    return [f"meshes/collision/{name}" for name in names]


def _obj(groups, normals: bool) -> str:
    """OBJ text of (material or None, mesh) groups; 1-based indices across groups."""
    lines, base = [], 0
    for material, mesh in groups:
        if material:
            lines.append(f"usemtl {material}")
        v = np.round(mesh.vertices, DIGITS) + 0.0
        lines += [f"v {x:g} {y:g} {z:g}" for x, y, z in v]
        if normals:
            n = np.round(mesh.vertex_normals, 4) + 0.0
            lines += [f"vn {x:g} {y:g} {z:g}" for x, y, z in n]
        f = mesh.faces + base + 1
        lines += [f"f {a}//{a} {b}//{b} {c}//{c}" if normals else f"f {a} {b} {c}" for a, b, c in f]
        base += len(v)
    return "\n".join(lines) + "\n"
