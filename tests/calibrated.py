"""A frame as a calibration on the controller might change it (test helper)."""

import numpy as np
from scipy.spatial.transform import Rotation


def moved(X: np.ndarray, rng) -> np.ndarray:
    """X (4, 4) [m] moved by a calibration-sized error: up to 3 mm along each axis and
    1.2 deg about each, in X's own frame."""
    delta = np.eye(4)
    delta[:3, :3] = Rotation.from_rotvec(rng.uniform(-1, 1, 3) * np.deg2rad(1.2)).as_matrix()
    delta[:3, 3] = rng.uniform(-3e-3, 3e-3, 3)
    return X @ delta
