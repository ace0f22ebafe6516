"""offline_prog: robot path and trajectory planning with a spatially fixed TCP.

Implements Rameder et al., "Robot Path and Trajectory Planning Considering a
Spatially Fixed TCP" (../shared/paper): B-spline processing path (§2), process
orientation frames and the flange path X_IE = X_IT · X_PF⁻¹ · X_PE (§3), and a
jerk-limited sin² time law (§4).

Frames: I inertial (Drake's world), B robot base, E flange, P part, F process
frame on the path, T fixed tool (TCP).
"""

import logging
import os

# One BLAS thread unless the user says otherwise (before numpy loads, if it has not):
# the least-squares fits and 6×6 solves here are small, and OpenBLAS's spinning threads
# cost 6–10× on a machine whose cores are busy (the preview drawn on the second core,
# placement workers, other jobs). Results are the same bit for bit (scripts/compare_outputs.py).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

__version__ = "0.1.0"

logging.getLogger(__name__).addHandler(logging.NullHandler())
