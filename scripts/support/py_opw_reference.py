"""py-opw-kinematics as an independent reference for our OPW solver (tests and the
benchmark only; not part of the library)."""

from offline_prog.robot.kinematics_opw import OpwParameters


def py_opw_robot(params: OpwParameters):
    """The same robot in ``py-opw-kinematics`` (an independent implementation, for
    tests and benchmarks; radians). Raises ImportError when it is not installed."""
    import py_opw_kinematics as py_opw

    model = py_opw.KinematicModel(
        a1=params.a1,
        a2=params.a2,
        b=params.b,
        c1=params.c1,
        c2=params.c2,
        c3=params.c3,
        c4=params.c4,
        offsets=params.offsets,
        flip_axes=tuple(s < 0 for s in params.sign_corrections),
    )
    return py_opw.Robot(model, degrees=False)
