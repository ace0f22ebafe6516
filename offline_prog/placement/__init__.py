"""``offline-prog place``: where the fixed tool should stand (X_IT) and how the gripper
should hold the part (X_PE), searched with the planning pipeline (the paper's outlook).

Modules in the order of a run: ``space`` (the ``place:`` block and the candidates),
``payload`` (the cell as it travels to the workers), ``context`` (a worker's loaded
cell, a candidate's cell), ``objective`` (the lexicographic objective), ``screen`` (the
analytic path IK), ``evaluate`` (``plan``'s pipeline), ``engine`` (this process or
Dask), ``search`` (grid screen, then CMA-ES), ``outputs`` and ``search_map`` (the
folder), ``run`` (the command's stages).
"""
