"""Calibration of the cell from measurements (issue 38): the fixed tool's TCP X_IT and
the grasp X_PE from touched points, or the frames a technician calibrated on the
controller, written into a copy of the cell file.

From touches (``offline-prog calibrate CELL --touches touches.csv``), in the order a
technician works:

- ``touches``: the touches file, each row a target and the robot's six joint angles;
- ``measurement``: each touch as a flange pose (the plan's own kinematics) and the
  parameters its residual depends on;
- ``pivot``: the tool's tip and the pointer's tip from ``tool_tip`` touches (both
  unknown, the pivot method); ``tool_axis``: the tool's +z axis from ``tool_axis``
  touches; ``grasp``: X_PE from part points (Kabsch start values, degeneracy checks);
- ``estimate``: one least-squares problem over all of them (scipy), standard
  deviations from the Jacobian, the condition number; ``outliers``: one gross outlier
  found and named;
- ``path_shift``: how far the planned path on the part moves between the nominal and
  the calibrated cell; ``outputs``: ``calibrated.yaml`` and ``calibration.json``.

From the controller (``--from-controller FILE``): ``controller_kuka`` (``$config.dat``)
and ``controller_abb`` (a RAPID module) read the frames; ``controller_frames`` maps
them onto X_IT and X_PE through ``tool.controller_frame`` / ``part.controller_frame``.

``run`` is what the command and the session call. The method follows the least-squares
identification from measurements of Rameder, Gattringer, Müller, "Geometric Robot
Calibration Using a Calibration Plate", arXiv 2510.25338 (2025), here for the frames of
a fixed-TCP cell rather than the robot's own geometry.
"""
