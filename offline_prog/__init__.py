"""offline_prog: robot path and trajectory planning with a spatially fixed TCP.

Implements Rameder et al., "Robot Path and Trajectory Planning Considering a
Spatially Fixed TCP" (../shared/paper): B-spline processing path (§2), process
orientation frames and the flange path X_IE = X_IT · X_PF⁻¹ · X_PE (§3), and a
jerk-limited sin² time law (§4).

Frames: I inertial (Drake's world), B robot base, E flange, P part, F process
frame on the path, T fixed tool (TCP).
"""

import importlib
import logging
import os
import sys
import types

# One BLAS thread unless the user says otherwise (before numpy loads, if it has not):
# the least-squares fits and 6×6 solves here are small, and OpenBLAS's spinning threads
# cost 6–10× on a machine whose cores are busy (the preview drawn on the second core,
# placement workers, other jobs). Results are the same bit for bit (scripts/compare_outputs.py).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

__version__ = "0.1.0"

logging.getLogger(__name__).addHandler(logging.NullHandler())

# The Python API (offline_prog.api), imported on first use: `import offline_prog` stays
# cheap (no pydrake) for the command's flag parsing and for `__version__`.
__all__ = ["Calibrated", "Plan", "calibrate", "export_programs", "load_cell", "place", "plan"]


def _api_name(name: str) -> property:
    """``offline_prog.<name>``: the API's, loaded on first use. A data descriptor on the
    package's class: importing the submodule ``offline_prog.plan`` (the pipeline), which
    Python records as the package attribute ``plan``, does not hide the function (the
    submodule stays in ``sys.modules``, where ``from offline_prog.plan import ...``
    finds it)."""

    def get(package: types.ModuleType):
        # By name: the modules that read __version__ do not depend on the API.
        return getattr(importlib.import_module("offline_prog.api"), name)

    def set_submodule(package: types.ModuleType, value) -> None:
        if not isinstance(value, types.ModuleType):
            raise AttributeError(f"offline_prog.{name} is the API's; it cannot be set")

    return property(get, set_submodule, doc=f"offline_prog.api.{name}")


class _Package(types.ModuleType):
    """The package module, with the API's names (see :func:`_api_name`)."""

    Calibrated = _api_name("Calibrated")
    Plan = _api_name("Plan")
    calibrate = _api_name("calibrate")
    export_programs = _api_name("export_programs")
    load_cell = _api_name("load_cell")
    place = _api_name("place")
    plan = _api_name("plan")


sys.modules[__name__].__class__ = _Package
