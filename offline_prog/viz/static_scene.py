"""A MeshCat scene written straight to a standalone HTML file, with no server.

Drake's ``Meshcat.StaticHtml()`` needs a live MeshCat server (a port, a thread) just to
collect the commands it sends; here the same MeshCat commands (``set_object`` with a
three.js JSON object, ``set_transform``, ``set_property``, ``set_animation``,
``set_target``) are built as plain dicts, packed with msgpack (arrays as MeshCat's
typed-array extensions), and embedded in Drake's own viewer page
(``pydrake/share/drake/geometry/meshcat.html`` with ``meshcat.js`` inlined: the same
viewer, lights and background as the live preview). The page replays the commands
synchronously on load, then plays the animation.

Paths are MeshCat tree paths like ``/drake/robot/link_1``; poses are 4×4 arrays in the
parent's frame, I (Drake's world) at the root, z up. three.js cylinders and capsules run
along y and its cameras are y up: both are converted at this edge.
"""

from __future__ import annotations

import base64
import html
import json
import re
from pathlib import Path

import numpy as np
import pydrake
import umsgpack
from scipy.spatial.transform import Rotation

DRAKE_VIEWER = Path(pydrake.__file__).parent / "share" / "drake" / "geometry"
_SCRIPT_TAG = '<script type="text/javascript" src="meshcat.js"></script>'
_BLOCK = ("<!-- CONNECTION BLOCK BEGIN -->", "<!-- CONNECTION BLOCK END -->")
# MeshCat's msgpack extension codes for typed arrays (meshcat-python's threejs_type).
_EXT = {np.dtype(np.float32): (0x17, "Float32Array"), np.dtype(np.uint32): (0x16, "Uint32Array")}
# three.js along-y primitives to Drake's along-z: a quarter turn about x.
_Y_TO_Z = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])


def _array(values: np.ndarray, dtype, item_size: int) -> dict:
    """A three.js BufferAttribute: (K, item_size) values, row by row."""
    data = np.ascontiguousarray(values, dtype=dtype)
    code, name = _EXT[np.dtype(dtype)]
    return {
        "itemSize": item_size,
        "type": name,
        "array": umsgpack.Ext(code, data.tobytes()),
        "normalized": False,
    }


def _color(rgba) -> int:
    r, g, b = (int(round(float(v) * 255)) for v in rgba[:3])
    return (r << 16) + (g << 8) + b


def _material(uuid: str, kind: str, rgba, *, vertex_colors: bool = False) -> dict:
    opacity = float(rgba[3])
    return {
        "uuid": uuid,
        "type": kind,
        "color": _color(rgba),
        "side": 2,
        "transparent": opacity < 1.0,
        "opacity": opacity,
        "vertexColors": vertex_colors,
        "linewidth": 2.0,
    }


class StaticScene:
    """MeshCat commands in the order they are added, and the HTML page that replays them."""

    def __init__(self):
        # Commands in order: msgpack bytes (typed arrays), or JSON text for the large
        # array-free animation (the C JSON encoder packs it 10× faster than umsgpack).
        self.messages: list[bytes | str] = []

    def _add(self, command: dict) -> None:
        self.messages.append(umsgpack.packb(command))

    def _set_object(self, path: str, kind: str, geometry: dict, material: dict, matrix=None):
        geometry["uuid"], material_uuid = f"{path}#g", material["uuid"]
        matrix = np.eye(4) if matrix is None else matrix
        self._add(
            {
                "type": "set_object",
                "path": path,
                "object": {
                    "metadata": {"version": 4.5, "type": "Object"},
                    "geometries": [geometry],
                    "materials": [material],
                    "object": {
                        "uuid": f"{path}#o",
                        "type": kind,
                        "geometry": geometry["uuid"],
                        "material": material_uuid,
                        "matrix": np.asarray(matrix, dtype=float).T.ravel().tolist(),
                    },
                },
            }
        )

    def set_mesh(self, path: str, vertices, faces, rgba, colors=None) -> None:
        """A triangle mesh: vertices (V, 3) [m], faces (F, 3), optional colours (V, 3)."""
        attributes = {"position": _array(vertices, np.float32, 3)}
        if colors is not None:
            attributes["color"] = _array(colors, np.float32, 3)
        geometry = {
            "type": "BufferGeometry",
            "data": {"attributes": attributes, "index": _array(faces, np.uint32, 1)},
        }
        material = _material(
            f"{path}#m", "MeshPhongMaterial", rgba, vertex_colors=colors is not None
        )
        self._set_object(path, "Mesh", geometry, material)

    def set_primitive(self, path: str, kind: str, size: tuple[float, ...], rgba) -> None:
        """A box (x, y, z), sphere (r,), cylinder or capsule (r, length along z) [m]."""
        matrix = None
        if kind == "box":
            geometry = {
                "type": "BoxGeometry",
                "width": size[0],
                "height": size[1],
                "depth": size[2],
            }
        elif kind == "sphere":
            geometry = {
                "type": "SphereGeometry",
                "radius": size[0],
                "widthSegments": 24,
                "heightSegments": 16,
            }
        elif kind == "cylinder":
            geometry = {
                "type": "CylinderGeometry",
                "radiusTop": size[0],
                "radiusBottom": size[0],
                "height": size[1],
                "radialSegments": 32,
            }
            matrix = _Y_TO_Z
        elif kind == "capsule":
            geometry = {
                "type": "CapsuleGeometry",
                "radius": size[0],
                "length": size[1],
                "capSegments": 12,
                "radialSegments": 24,
            }
            matrix = _Y_TO_Z
        else:
            raise ValueError(f"preview: no primitive {kind!r}")
        material = _material(f"{path}#m", "MeshPhongMaterial", rgba)
        self._set_object(path, "Mesh", geometry, material, matrix)

    def set_lines(self, path: str, points: np.ndarray, rgba, *, segments: bool = False):
        """A polyline (or separate segments, point pairs) through points (K, 3) [m]."""
        geometry = {
            "type": "BufferGeometry",
            "data": {"attributes": {"position": _array(points, np.float32, 3)}},
        }
        material = _material(f"{path}#m", "LineBasicMaterial", rgba)
        self._set_object(path, "LineSegments" if segments else "Line", geometry, material)

    def set_transform(self, path: str, X: np.ndarray) -> None:
        """The pose (4, 4) of the node at ``path`` in its parent's frame."""
        matrix = np.asarray(X, dtype=float).T.ravel().tolist()  # column-major
        self._add({"type": "set_transform", "path": path, "matrix": matrix})

    def set_property(self, path: str, key: str, value) -> None:
        self._add({"type": "set_property", "path": path, "property": key, "value": value})

    def set_camera(self, p_I_camera: np.ndarray, p_I_target: np.ndarray) -> None:
        """Look from p_I_camera at p_I_target (both in I, z up) [m]."""
        self.set_transform("/Cameras/default", np.eye(4))
        x, y, z = (float(v) for v in np.subtract(p_I_camera, p_I_target))
        self.set_property("/Cameras/default/rotated/<object>", "position", [x, z, -y])
        tx, ty, tz = (float(v) for v in p_I_target)
        self._add({"type": "set_target", "value": [tx, tz, -ty]})

    def set_animation(
        self,
        paths: list[str],
        times: np.ndarray,
        poses: np.ndarray,
        fps: float,
        scales: dict[str, np.ndarray] | None = None,
    ):
        """Animate each node: poses (n_nodes, n_times, 4, 4) in its parent, at frame
        ⌊t · fps⌋ for each of ``times`` [s] (one pose per frame: the later one).
        ``scales``: node path ↦ (n_times,) uniform scale (0 hides the node)."""
        frames = np.floor(np.asarray(times) * fps + 1e-9).astype(int)
        keep = np.r_[frames[1:] != frames[:-1], True]
        frames, poses = frames[keep].tolist(), np.asarray(poses)[:, keep]
        keys = _Keys(frames)
        animations = []
        for path, scale in (scales or {}).items():
            values = np.asarray(scale, dtype=float)[keep]
            track = {"name": ".scale", "type": "vector3", "keys": keys.uniform(values)}
            animations.append(
                {"path": path, "clip": {"fps": fps, "name": "default", "tracks": [track]}}
            )
        for path, X in zip(paths, poses, strict=True):
            quaternions = Rotation.from_matrix(X[:, :3, :3]).as_quat()  # x, y, z, w
            tracks = [
                {"name": ".position", "type": "vector3", "keys": keys(X[:, :3, 3])},
                {"name": ".quaternion", "type": "quaternion", "keys": keys(quaternions)},
            ]
            clip = {"fps": fps, "name": "default", "tracks": tracks}
            animations.append({"path": path, "clip": clip})
        options = {"play": True, "repetitions": 1}
        command = {"type": "set_animation", "animations": animations, "options": options}
        self.messages.append(keys.dumps(command))

    def html(self, title: str) -> str:
        """The standalone page: Drake's viewer with meshcat.js inlined and these commands."""
        page = (DRAKE_VIEWER / "meshcat.html").read_text(encoding="utf-8")
        script = (
            (DRAKE_VIEWER / "meshcat.js")
            .read_text(encoding="utf-8")
            .replace("</script", "<\\/script")
        )
        page = page.replace(_SCRIPT_TAG, f"<script>{script}</script>")
        start, end = page.index(_BLOCK[0]), page.index(_BLOCK[1]) + len(_BLOCK[1])
        replay = "\n".join(
            f"    viewer.handle_command({m});"
            if isinstance(m, str)
            else f'    viewer.handle_command_bytearray(_b("{base64.b64encode(m).decode()}"));'
            for m in self.messages
        )
        block = (
            "const _b = s => Uint8Array.from(atob(s), c => c.charCodeAt(0));\n"
            f"{replay}\n"
            '    document.getElementById("status-message").style.display = "none";'
        )
        page = page[:start] + block + page[end:]
        escaped = html.escape(title, quote=True)
        return page.replace("<title>Drake MeshCat</title>", f"<title>{escaped}</title>")


_STAND_IN = re.compile(r'"\\u0000keys (\d+)\\u0000"')  # _Keys' stand-ins, as JSON writes them


class _Keys:
    """Animation keyframes [{time: frame, value: [...]}, ...] written as JSON text at
    once per track (a long job has ~10⁶ keys: as dicts through ``json.dumps`` they were
    most of its preview's time). ``keys(values)`` stands for one track's keys in a
    command; :meth:`dumps` writes the command as ``json.dumps(command,
    separators=(",", ":"))`` writes it with the keys as dicts, character for character.
    """

    def __init__(self, frames: list[int]):
        self._starts = [f'{{"time":{f:d},"value":[' for f in frames]
        self._tracks: list[str] = []

    def __call__(self, values: np.ndarray) -> str:
        """A stand-in for the keys of (len(frames), k) ``values``, one row per frame."""
        text = json.dumps(np.asarray(values, dtype=float).tolist(), separators=(",", ":"))
        return self._track(text[2:-2].split("],["))  # each row's numbers, as JSON writes them

    def uniform(self, values: np.ndarray) -> str:
        """The stand-in for a uniform scale's keys: [v, v, v] for each of ``values``
        (len(frames),), each distinct value written once (a seam's highlight: 0 or 1)."""
        bits, inverse = np.unique(
            np.asarray(values, dtype=float).view(np.int64), return_inverse=True
        )
        texts = [",".join([json.dumps(v)] * 3) for v in bits.view(float).tolist()]
        return self._track(list(map(texts.__getitem__, inverse.ravel().tolist())))

    def _track(self, rows: list[str]) -> str:
        keys = "]},".join(map(str.__add__, self._starts, rows))
        self._tracks.append(f"[{keys}]}}]" if self._starts else "[]")
        return f"\x00keys {len(self._tracks) - 1}\x00"

    def dumps(self, command: dict) -> str:
        """``command`` as JSON, each stand-in replaced by its track's keys."""
        text = json.dumps(command, separators=(",", ":"))
        return _STAND_IN.sub(lambda match: self._tracks[int(match[1])], text)
