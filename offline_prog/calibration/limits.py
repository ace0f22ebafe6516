"""Thresholds of calibration, named once (see ``offline_prog.constants``)."""

import numpy as np

# The touches file: a few kB; larger is not a touches file.
MAX_TOUCHES_BYTES = 1_000_000
MAX_TOUCHES = 10_000
# A controller file: a $config.dat is ~100 kB, a RAPID module with its robtargets a few MB.
MAX_CONTROLLER_FILE_BYTES = 5_000_000
# Angles all within ±this look like radians: a technician's touches turn some joint
# farther than 6.3° (the pivot needs the flange tilted by tens of degrees).
RADIANS_LIKE_DEG = 2.0 * np.pi + 0.01
# A touch may sit on a joint limit (angles are read to the decimals written).
LIMIT_SLACK_RAD = 1e-9

# Fewest touches per kind (the pivot has 6 unknowns; each touch gives 3 equations).
MIN_TOOL_TIP_TOUCHES = 4
MIN_TOOL_AXIS_TOUCHES = 2
MIN_PART_POINTS = 3
# The pivot separates tip and pointer only if the flange turns about two axes: the
# rms turn about the least-turned axis (sqrt of the spread matrix's smallest
# eigenvalue per touch) must reach this [deg].
MIN_PIVOT_SPREAD_DEG = 5.0
# Part points closer than this (rms) to one line do not fix the grasp's rotation [mm].
MIN_PART_SPREAD_MM = 5.0
# The tool_axis touches may tilt the axis at most this far from the cell's +z of T.
MAX_AXIS_TILT_DEG = 80.0
# The column-scaled Jacobian's condition number above which a parameter counts as
# not determined by the touches (Driels and Pathre's observability index).
MAX_CONDITION = 1e6

# One gross outlier: a touch whose distance from the fit of the others exceeds both
# OUTLIER_SIGMAS times their noise (per axis) and OUTLIER_FLOOR_MM. Only the
# OUTLIER_CANDIDATES touches farthest from the fit of all are tried.
OUTLIER_SIGMAS = 6.0
OUTLIER_FLOOR_MM = 0.2
OUTLIER_CANDIDATES = 5

# The path shift is measured every this many mm along each seam (at least 200 points).
SHIFT_STEP_MM = 1.0
MIN_SHIFT_POINTS = 200

# calibrated.yaml: translations to 0.1 µm, angles to 1e-6 deg.
WRITE_M_DIGITS, WRITE_DEG_DIGITS = 7, 6
