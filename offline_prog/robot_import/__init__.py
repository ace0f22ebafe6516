"""``offline-prog robots import``: a robot folder from a URDF or xacro description.

Stages, each a module: :mod:`.sources` (``package://`` and ``$(find ...)``, and the
folders a description may read), :mod:`.xacro_sandbox` with :mod:`.xacro_eval` (xacro
expanded as data: no code runs), :mod:`.chain` (the serial chain base_link → tool0, six
revolute joints), :mod:`.plausible` (units and names), :mod:`.derive` (OPW parameters
from the chain's geometry), :mod:`.verify` (Drake FK of the description against the
derived model), :mod:`.meshes` (meshes converted into the link frames), :mod:`.record`
(robot.yaml, README), :mod:`.folder` (the folder it owns, written whole) and :mod:`.run`
(the whole import).
"""
