"""The arrays a mesh file is drawn with, kept in the mesh cache (scene.mesh_cache.
drawn_arrays): the preview draws the same from the cache as from the file, a changed
file or material library is read again, and a cache that cannot be written still
draws."""

import shutil

import numpy as np
import pytest
from pydrake.geometry import Convex, Mesh

from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.scene.mesh_cache import mesh_cache_dir
from offline_prog.viz.preview import _mesh_file

LINK = ROBOTS_DIR / "kuka_kr16_2" / "meshes" / "visual" / "link_2.obj"  # with its .mtl
RAL2003 = np.round(np.array([1.0, 0.43, 0.0]) * 255) / 255  # link_2.mtl's Kd, 8-bit sRGB


@pytest.fixture()
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("OFFLINE_PROG_CACHE", str(tmp_path / "cache"))
    return mesh_cache_dir()


@pytest.fixture()
def link(tmp_path):
    """A copy of a bundled OBJ with its material library (edited by the tests)."""
    folder = tmp_path / "mesh"
    folder.mkdir()
    for file in (LINK, LINK.with_suffix(".mtl")):
        shutil.copy(file, folder / file.name)
    return folder / LINK.name


def linear(srgb: np.ndarray) -> np.ndarray:
    return np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)


def test_a_mesh_is_drawn_the_same_from_the_cache_as_from_its_file(cache, link):
    shape = Mesh(str(link), 0.5)
    drawn = _mesh_file(shape)  # read by trimesh, kept
    assert len(list(cache.glob("*.drawn.npz"))) == 1
    kept = _mesh_file(shape)  # from the cache
    for a, b in zip(drawn, kept, strict=True):
        np.testing.assert_array_equal(a, b)
    vertices, faces, colors = kept
    assert vertices.shape[1] == 3 and faces.max() < len(vertices)
    np.testing.assert_allclose(colors, np.tile(linear(RAL2003), (len(vertices), 1)))
    # The scale is the shape's, not the cache's: the same file at another scale.
    np.testing.assert_allclose(_mesh_file(Mesh(str(link), 1.0))[0], 2.0 * vertices, rtol=1e-15)
    hull = _mesh_file(Convex(str(link), 1.0))  # a hull is kept apart from the parts
    assert len(list(cache.glob("*.drawn.npz"))) == 2
    assert hull[2] is None and len(hull[0]) < len(vertices)


def test_a_changed_material_library_is_read_again(cache, link):
    before = _mesh_file(Mesh(str(link), 1.0))[2][0]
    mtl = link.with_suffix(".mtl")
    mtl.write_text(mtl.read_text().replace("Kd 1.0 0.43 0.0", "Kd 0.0 0.0 1.0"))
    after = _mesh_file(Mesh(str(link), 1.0))[2][0]
    np.testing.assert_allclose(before, linear(RAL2003))
    np.testing.assert_allclose(after, [0.0, 0.0, 1.0])
    assert len(list(cache.glob("*.drawn.npz"))) == 2


def test_a_cache_that_cannot_be_written_still_draws(tmp_path, monkeypatch, link):
    blocked = tmp_path / "not_a_folder"
    blocked.write_text("a file where the cache folder would be")
    monkeypatch.setenv("OFFLINE_PROG_CACHE", str(blocked))
    vertices, faces, colors = _mesh_file(Mesh(str(link), 1.0))
    assert len(vertices) > 100 and colors is not None


def test_a_kept_file_that_cannot_be_read_is_made_again(cache, link):
    drawn = _mesh_file(Mesh(str(link), 1.0))
    (kept,) = cache.glob("*.drawn.npz")
    kept.write_bytes(kept.read_bytes()[:100])  # cut short
    again = _mesh_file(Mesh(str(link), 1.0))
    for a, b in zip(drawn, again, strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(np.load(kept)["vertices"], drawn[0])  # kept anew
    assert [f.name for f in cache.iterdir()] == [kept.name]  # no temporary file left


def test_a_mesh_without_materials_is_drawn_without_vertex_colours(cache, tmp_path):
    import trimesh

    stl = tmp_path / "block.stl"
    trimesh.creation.box(extents=(0.1, 0.2, 0.3)).export(stl)
    for _ in range(2):  # from the file, then from the cache
        vertices, faces, colors = _mesh_file(Mesh(str(stl), 1.0))
        assert colors is None  # the shape's own colour, not a column of None
        np.testing.assert_allclose(np.ptp(vertices, axis=0), [0.1, 0.2, 0.3])
    assert len(list(cache.glob("*.drawn.npz"))) == 1
