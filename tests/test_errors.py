"""The package's errors travel between processes intact (offline_prog.errors): pickled
and read back, each is its class with its message and its fields, whatever its
``__init__`` takes (a forked process's InputError reached the parent as exit 3)."""

import importlib
import pickle
import pkgutil

import offline_prog
from offline_prog.errors import (
    Failure,
    InputError,
    PlanFailedError,
    PlanFailure,
    TravellingError,
)
from offline_prog.joints.joint_plan import JointPlanError


def _travelled(error: BaseException) -> BaseException:
    return pickle.loads(pickle.dumps(error))


def test_an_input_error_keeps_its_file_key_and_reason():
    error = _travelled(InputError("cells/a.yaml", "seams[1].cad.chain.near_mm[0]", "two edges"))
    assert type(error) is InputError
    assert (error.file, error.key, error.reason) == (
        "cells/a.yaml",
        "seams[1].cad.chain.near_mm[0]",
        "two edges",
    )
    assert str(error) == "cells/a.yaml: seams[1].cad.chain.near_mm[0]: two edges"


def test_a_plan_failure_keeps_its_kind_place_and_reason():
    failure = PlanFailure(Failure.SINGULARITY, 0.125, 1.5, "wrist singularity")
    for error in (
        PlanFailedError(failure),
        JointPlanError(0.125, 1.5, "wrist singularity", Failure.SINGULARITY),
    ):
        back = _travelled(error)
        assert type(back) is type(error)
        assert back.failure == failure  # the record, not its text
        assert str(back) == str(error)


def _package_errors() -> list[type]:
    for module in pkgutil.walk_packages(offline_prog.__path__, "offline_prog."):
        if not module.name.endswith("__main__"):  # the command itself
            importlib.import_module(module.name)
    found, stack = [], [BaseException]
    while stack:
        cls = stack.pop()
        stack.extend(cls.__subclasses__())
        if cls.__module__.startswith("offline_prog."):
            found.append(cls)
    return found


def test_every_error_with_its_own_arguments_travels():
    """An error class whose ``__init__`` takes other arguments than the message pickles
    through TravellingError (BaseException's pickling calls ``cls(*args)``)."""
    errors = _package_errors()
    assert InputError in errors and JointPlanError in errors
    own_init = [
        cls
        for cls in errors
        if any("__init__" in vars(base) for base in cls.__mro__ if base.__module__ != "builtins")
    ]
    stranded = [cls.__qualname__ for cls in own_init if not issubclass(cls, TravellingError)]
    assert own_init and not stranded, f"errors that cannot travel: {stranded}"
