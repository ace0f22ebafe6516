"""offline_prog: robot path and trajectory planning with a spatially fixed TCP.

Implements Rameder et al., "Robot Path and Trajectory Planning Considering a
Spatially Fixed TCP" (../shared/paper): B-spline processing path (§2), process
orientation frames and the flange path X_IE = X_IT · X_PF⁻¹ · X_PE (§3), and a
jerk-limited sin² time law (§4).

Frames: I inertial (Drake's world), B robot base, E flange, P part, F process
frame on the path, T fixed tool (TCP).
"""

import logging

__version__ = "0.1.0"

logging.getLogger(__name__).addHandler(logging.NullHandler())
