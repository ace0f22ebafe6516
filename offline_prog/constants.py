"""Tolerances and defaults, named once (see toppra's constants.py)."""

import numpy as np

# B-spline fit (paper §2).
DEFAULT_SPLINE_DEGREE = 5
MIN_SPLINE_DEGREE = 5
DEFAULT_FIT_TOLERANCE_M = 1e-4  # max distance from a given point to the curve [m]

# Arc-length re-parameterization: Newton on s(u) stops below this [m].
ARC_LENGTH_TOLERANCE_M = 1e-12

# Process frames (paper §3.1): a normal closer than this to the tangent is rejected.
MIN_NORMAL_TANGENT_ANGLE_RAD = np.deg2rad(5.0)

# Workspace trajectory.
DEFAULT_SAMPLE_RATE_HZ = 250.0

# Cusps (paper §4): flange speed per unit TCP speed |dp_IE/ds| below this is a cusp,
# and a local peak above CUSP_PEAK_RATIO times the path median is a speed peak.
CUSP_MIN_FLANGE_RATIO = 0.05
CUSP_PEAK_RATIO = 3.0

# Length units a cell file may use, in metres per unit.
UNIT_SCALE = {"m": 1.0, "mm": 1e-3}
