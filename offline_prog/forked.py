"""A map over items on this process and a forked child: the second core for the plan.

:func:`forked_map` computes ``function(item)`` for each item. This process and one
forked child take the items in turn from a shared counter (this process the first), so
a slow item does not hold up the rest. The child sends each outcome back pickled, with
the objects both processes already hold (``shared``: the cell's inputs, the Drake
scene, and everything reachable from them at the fork) sent as references, not copies.
So the caller gets the same objects, and nothing the child cannot pickle (a Drake
context) has to travel. An outcome the child cannot send, or this process cannot read
back, is computed here again (the package's own errors travel:
``errors.TravellingError``). Each outcome is the value or the exception the item
raised (:class:`Outcome`), so the caller raises them in the items' order, as a serial
loop would have.

Where fork is not available, or only one core is, the items run here, one after the
other.
"""

from __future__ import annotations

import dataclasses
import io
import os
import pickle
import threading
import types
from collections.abc import Callable, Iterable

import numpy as np

_ATOMS = (type(None), bool, int, float, complex, str, bytes)
_CHILD = [False]  # set in forked_map's child
_OPAQUE = (type, types.ModuleType, types.FunctionType, types.BuiltinFunctionType, np.ndarray)


@dataclasses.dataclass
class Outcome:
    """One item's value, or the exception it raised."""

    value: object = None
    error: BaseException | None = None

    def result(self):
        """The value; raises the item's exception."""
        if self.error is not None:
            raise self.error
        return self.value


def reachable(roots: Iterable[object]) -> list[object]:
    """Every object reachable from ``roots`` through dataclass fields, instance
    dictionaries, slots, lists, tuples, sets and dict keys and values (numpy arrays,
    classes, functions and extension objects are reached but not entered)."""
    found, seen, stack = [], set(), list(roots)
    while stack:
        obj = stack.pop()
        if isinstance(obj, _ATOMS) or id(obj) in seen:
            continue
        seen.add(id(obj))
        found.append(obj)
        if isinstance(obj, _OPAQUE):
            continue
        if isinstance(obj, dict):
            stack.extend(obj.keys())
            stack.extend(obj.values())
        elif isinstance(obj, list | tuple | set | frozenset):
            stack.extend(obj)
        else:
            stack.extend(getattr(obj, "__dict__", {}).values())
            for name in getattr(type(obj), "__slots__", ()):
                if hasattr(obj, name):
                    stack.append(getattr(obj, name))
    return found


def _pickler(file, index: dict[int, int]):
    """A cloudpickle pickler (closures such as a path's normal field travel by value)
    that sends the objects in ``index`` (id ↦ key) as their keys."""
    import cloudpickle

    class Pickler(cloudpickle.Pickler):
        def persistent_id(self, obj):
            return None if isinstance(obj, _ATOMS) else index.get(id(obj))

    return Pickler(file, protocol=pickle.HIGHEST_PROTOCOL)


class _Unpickler(pickle.Unpickler):
    def __init__(self, file, objects: list[object]):
        super().__init__(file)
        self.objects = objects

    def persistent_load(self, key: int):
        return self.objects[key]


def quiet(*args) -> None:
    """A progress callback that tells nothing (the child's; it travels by name)."""


def in_child() -> bool:
    """Whether this is :func:`forked_map`'s child (it tells no progress)."""
    return _CHILD[0]


def _workers() -> int:
    import multiprocessing

    if "fork" not in multiprocessing.get_all_start_methods():
        return 1
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return 2 if (cores or 1) > 1 else 1


def forked_map(
    function: Callable[[object], object],
    items: list,
    *,
    shared: Iterable[object],
) -> list[Outcome]:
    """``[Outcome of function(item) for item in items]``, on this process and a forked
    child (module doc).

    Args:
        function: computes one item; what it returns, and what it raises, must not
            depend on which process runs it.
        shared: the objects the items read (their reachable objects travel back as
            references).
    """
    if len(items) < 2 or _workers() < 2:
        return [_run(function, item) for item in items]
    import multiprocessing

    context = multiprocessing.get_context("fork")
    objects = reachable(shared)
    index = {id(obj): k for k, obj in enumerate(objects)}
    # The next item to take, under its lock. The first is this process's, whichever
    # process starts first: its progress is the terminal's (the child tells none).
    counter = context.Value("i", 1)
    receive, send = context.Pipe(duplex=False)

    def take() -> int:
        with counter.get_lock():
            i = counter.value
            counter.value += 1
        return i

    def child() -> None:
        _CHILD[0] = True
        while (i := take()) < len(items):
            outcome = _run(function, items[i])
            payload = io.BytesIO()
            try:
                _pickler(payload, index).dump(outcome)
            except Exception:  # it cannot travel: computed again by the parent
                payload = None
            send.send_bytes(
                i.to_bytes(4, "little") + (b"" if payload is None else payload.getvalue())
            )
        send.close()

    process = context.Process(target=child, daemon=True)
    process.start()
    send.close()
    received: list[bytes] = []
    reader = threading.Thread(target=_drain, args=(receive, received), daemon=True)
    reader.start()
    outcomes: list[Outcome | None] = [None] * len(items)
    try:
        i = 0
        while i < len(items):
            outcomes[i] = _run(function, items[i])
            i = take()
        reader.join()
        process.join()
    finally:
        if process.is_alive():  # an error or Ctrl-C here: the child stops too
            process.terminate()
            process.join()
    for message in received:
        i = int.from_bytes(message[:4], "little")
        if len(message) > 4:
            try:
                outcomes[i] = _Unpickler(io.BytesIO(message[4:]), objects).load()
            except Exception:  # a class that pickles but does not unpickle: computed here
                outcomes[i] = None
    return [
        outcome if outcome is not None else _run(function, items[i])
        for i, outcome in enumerate(outcomes)
    ]


def _run(function, item) -> Outcome:
    try:
        return Outcome(function(item))
    except Exception as error:  # raised by the caller, in the items' order
        return Outcome(error=error)


def _drain(receive, received: list[bytes]) -> None:
    """Every message until the child closes its end (a thread: the child never waits
    on a full pipe while this process works)."""
    try:
        while True:
            received.append(receive.recv_bytes())
    except EOFError:
        pass
