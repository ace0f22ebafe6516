"""``offline-prog place``: where the fixed tool should stand (X_IT) and how the gripper
should hold the part (X_PE), searched with the planning pipeline (the paper's outlook).

Modules in the order of a run: ``space`` (the ``place:`` block and the candidates),
``stand`` (a stand that stands with the tool, its foot on the floor), ``payload``
(the cell as it travels to the workers), ``context`` (a worker's loaded cell, a
candidate's cell), ``objective`` (the lexicographic objective), ``variants`` (every
tool turn and branch the planner may take, by the analytic IK), ``bound`` (the cycle
time's lower bound and estimate), ``cheap_law`` (TOPP-RA on the planner's variant),
``collision_look`` (a coarse collision check), ``screen`` (the screen and the rank),
``evaluate`` (``plan``'s pipeline), ``engine`` (this process or Dask), ``search``
(the two stages: screen, rank, plan with branch and bound), ``outputs``,
``top_view`` and ``search_map`` (the folder), ``run`` (the command's stages).
"""
