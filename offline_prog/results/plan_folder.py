"""What every plan folder shares: the ``--out`` check, the clearance table, a seam's
trajectory table, and a writer running on the second core (:class:`InParallel`).

The whole folder (``results.job_folder``) is written as a temporary sibling and swapped
in at the end (``atomic.staged_folder``): a crash or Ctrl-C leaves the previous complete
folder, and a re-plan leaves no file of an older run. The folder's manifest lists what
we wrote; a folder holding anything else is not replaced (we delete only our own files).
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np

from offline_prog.atomic import (
    MANIFEST,
    TEMP_PREFIX,
    read_manifest,
)
from offline_prog.errors import InputError
from offline_prog.job.records import Plan
from offline_prog.timing.trajectory import CSV_COLUMNS


def csv_columns(n_joints: int) -> list[str]:
    """CSV_COLUMNS then q1..qN [rad] and qd1..qdN [rad/s] in the URDF's joint order."""
    return [
        *CSV_COLUMNS,
        *(f"q{i + 1}" for i in range(n_joints)),
        *(f"qd{i + 1}" for i in range(n_joints)),
    ]


def trajectory_csv(plan: Plan) -> str:
    """CSV text: header csv_columns, one row per sample, SI units (s, m, rad)."""
    buffer = io.StringIO()
    joints = plan.joints
    np.savetxt(
        buffer,
        np.hstack([plan.trajectory.table(), joints.q, joints.qd]),
        delimiter=",",
        fmt="%.10g",
        header=",".join(csv_columns(joints.q.shape[1])),
        comments="",
    )
    return buffer.getvalue()


def clearance_csv(t: np.ndarray, profile: dict[str, np.ndarray]) -> str:
    """``t_s,<group>_m,...``: the smallest distance per pair group over time [m]."""
    buffer = io.StringIO()
    groups = list(profile)
    table = np.column_stack(
        [t, *(np.where(np.isfinite(profile[g]), profile[g], np.nan) for g in groups)]
    )
    np.savetxt(
        buffer,
        table,
        delimiter=",",
        fmt="%.9g",
        header=",".join(["t_s", *(f"{g}_m" for g in groups)]),
        comments="",
    )
    return buffer.getvalue()


def check_out_dir(out_dir: Path) -> None:
    """Refuse an --out that is a file, or a folder with files we did not write.

    Raises:
        InputError: naming the folder and what is in the way.
    """
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(out_dir, "--out", "exists and is not a folder")
    parent = out_dir.absolute().parent  # the folder is swapped in there
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(out_dir, "--out", f"cannot write into {parent} (permission denied)")
    if not out_dir.is_dir():
        return
    entries = {e.name for e in out_dir.iterdir() if not e.name.startswith(TEMP_PREFIX)}
    manifest = read_manifest(out_dir)
    owned = set((manifest or {}).get("files", {}).get("plan", [])) | {MANIFEST}
    foreign = sorted(entries - owned)
    if foreign:
        raise InputError(
            out_dir,
            "--out",
            f"holds files offline_prog did not write ({', '.join(foreign[:3])}"
            f"{', ...' if len(foreign) > 3 else ''}); choose an empty or new folder",
        )


class InParallel:
    """``function()`` running in a forked child process (the plan is shared
    copy-on-write: nothing is pickled); where fork is not available it runs at once.

    ``wait()`` blocks until it is done and returns its result (sent back pickled), or
    raises the child's error here, as it was (an OSError keeps its path; RuntimeError
    if it cannot travel). ``cancel()`` stops it:
    a folder is never removed while the child still writes into it. Used as a context
    manager, leaving the block by any error or Ctrl-C cancels it.
    """

    def __init__(self, function):
        import multiprocessing

        self.process, self.result = None, None
        if "fork" not in multiprocessing.get_all_start_methods():
            self.result = function()
            return
        context = multiprocessing.get_context("fork")
        self.receive, send = context.Pipe(duplex=False)

        def child() -> None:
            try:
                send.send(("done", function()))
            except BaseException as error:  # raised by wait(), in the parent
                try:
                    send.send(error)
                except Exception:  # not picklable: its text
                    send.send(f"{type(error).__name__}: {error}")

        self.process = context.Process(target=child, daemon=True)
        self.process.start()
        send.close()

    def wait(self):
        """The function's result (raises its error)."""
        if self.process is None:
            return self.result
        try:
            message = self.receive.recv()
        except EOFError:
            message = "the writer process ended without a word"
        self.process.join()
        self.process = None
        if isinstance(message, BaseException):
            raise message
        if not isinstance(message, tuple):
            raise RuntimeError(message)
        self.result = message[1]
        return self.result

    def cancel(self) -> None:
        if self.process is not None:
            self.process.terminate()
            self.process.join()
            self.process = None

    def __enter__(self) -> InParallel:
        return self

    def __exit__(self, *exc_info) -> None:
        self.cancel()
