"""Controller programs and trajectory files from a finished plan (issue: exports).

Layout, top to bottom (import contracts in pyproject.toml: no arrow back up, no vendor
folder importing another):

- ``formats``: the format registry and ``export`` (loads a writer by name);
- ``kuka/``, ``abb/``, ``ur/``, ``fanuc/``: one writer per controller (``KrlPost``,
  ``RapidPost``, ``UrScriptPost``, ``FanucPost``) with its vendor's conventions;
- ``post``: the writer protocol (header, frames, move joint, seam: move linear / call
  part, set output, follow speed, footer) and ``write_program``;
- ``record``: the program record a writer translates, built once from the plan's events;
- ``points``, ``densify``, ``density``, ``deviation``: which samples become a seam's
  points, against the continuous plan;
- ``header``, ``payload``, ``text``, ``joint_files``: what every program shares, and the
  joint-trajectory files;
- ``job_program``, ``program``: the plan as the writers read it (plan.npz + job.npz).
"""
