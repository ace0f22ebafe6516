"""Seams from the part's CAD model (issue 26): STEP via Open CASCADE, meshes via trimesh.

Imported only when a cell names ``part.model`` or a seam's ``cad:``: Open CASCADE's
bindings take seconds to import and ``plan`` of any other cell must not pay for them.
"""
