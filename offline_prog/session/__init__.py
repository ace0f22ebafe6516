"""The interactive offline-programming session (``offline-prog session CELL.yaml``).

The engineer moves the tool stand, turns the grasp, changes the speed, the free tool
rotation, the clearance or the active seam in a browser panel next to a live MeshCat
scene; the session re-plans what the change invalidates, shows the result, and saves
the changed cell or exports the plan folder exactly as ``offline-prog plan`` would.

- ``state``: the editable parameters, typed-value checks, and the Cell they make;
- ``replan``: the cached pipeline (which stages a change re-runs);
- ``heap``: the process keeps freed memory for the next re-plan (glibc);
- ``sample_states``: each sample's state for the path colours;
- ``cell_text``: Save: the changed values written into the original file's text;
- ``scene_view``: the MeshCat scene (cell, coloured path, closest pair, pose at σ);
- ``panel``: the HTTP panel page and its JSON endpoints;
- ``guard``: who may drive the panel (Host, Origin, the session's token);
- ``request``: request bodies and values checked before they reach the session;
- ``launch``: the ports, the printed URL with its token, the main loop;
- ``server``: the session loop tying them together.
"""
