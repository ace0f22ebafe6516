"""``offline-prog robots import``: a robot folder from a URDF or xacro description.

Stages, each a module: :mod:`.sources` (xacro, ``package://`` and ``$(find ...)``),
:mod:`.chain` (the serial chain base_link → tool0, six revolute joints),
:mod:`.derive` (OPW parameters from the chain's geometry), :mod:`.verify` (Drake FK of
the description against the derived model), :mod:`.meshes` (meshes converted into the
link frames), :mod:`.record` (robot.yaml, README) and :mod:`.run` (the whole import).
"""
