"""Where candidates are evaluated: in this process, or on Dask (``dask.distributed``).

Both engines have one method, :meth:`map`: the evaluations of a batch of candidates,
in the batch's order (so the search is the same whatever the number of workers).
On Dask the cell (:class:`~offline_prog.placement.payload.CellPayload`) is scattered
to every worker once; each task names it by its future, and each worker keeps the
cell it loaded from it (``evaluate.context``).

* default: a ``LocalCluster`` with one single-threaded worker process per core;
* ``--scheduler tcp://host:8786``: an existing cluster (``dask scheduler`` on one
  machine, ``dask worker tcp://host:8786`` on each; offline_prog installed on all).
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
from collections.abc import Callable, Sequence

from offline_prog.errors import InputError
from offline_prog.placement.context import context
from offline_prog.placement.evaluate import evaluate
from offline_prog.placement.objective import Evaluation
from offline_prog.placement.payload import CellPayload
from offline_prog.placement.screen import rank, screen
from offline_prog.placement.space import Candidate

CONNECT_TIMEOUT_S = 5  # an unreachable scheduler is an error within seconds
LOST_RETRIES = 3  # rounds of tasks run again after their worker was lost
# Candidates per task: a screen takes ~30 ms a seam, a rank ~0.15 s, a plan ~2 s.
CHUNKS = {"screen": 16, "rank": 2, "plan": 1}
STAGES = {"screen": screen, "rank": rank, "plan": evaluate}
# LocalCluster workers: a candidate is ~0.5 s of Python and Drake. The statistical
# profiler (a stack sample every 10 ms), glibc trimming every free above 64 kB and the
# frequent monitors cost 10–20 % of each worker's time on this machine
# (scripts/bench_place.py: parallel efficiency 0.73 with them).
WORKER_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
}


def run_chunk(
    stage: str, candidates: Sequence[Candidate], payload: CellPayload
) -> list[Evaluation]:
    """Evaluate candidates with ``stage`` ("screen" | "rank" | "plan") on this process's copy of
    the cell (loaded once per payload)."""
    ctx = context(payload)
    judge = STAGES[stage]
    return [judge(ctx, candidate) for candidate in candidates]


def _load(payload: CellPayload) -> None:
    context(payload)


class SerialEngine:
    """Every candidate in this process, one after the other."""

    scheduler = "in-process"
    workers = 1

    def __init__(self, payload: CellPayload):
        self.payload = payload

    def map(
        self,
        stage: str,
        candidates: Sequence[Candidate],
        done: Callable[[int], None] = lambda n: None,
    ) -> list[Evaluation]:
        results = []
        for candidate in candidates:
            results += run_chunk(stage, [candidate], self.payload)
            done(1)
        return results

    def close(self) -> None:
        pass


class DaskEngine:
    """Candidates as tasks on a Dask cluster: a new LocalCluster, or the scheduler at
    ``scheduler``.

    Raises:
        InputError: the scheduler cannot be reached, or has no worker, within
            CONNECT_TIMEOUT_S.
    """

    def __init__(
        self, payload: CellPayload, *, workers: int | None = None, scheduler: str | None = None
    ):
        import dask
        from dask.distributed import Client, LocalCluster

        self.cluster = None
        quiet = logging.ERROR
        for name in ("distributed", "tornado", "bokeh"):
            logging.getLogger(name).setLevel(quiet)
        if scheduler:
            try:
                with contextlib.redirect_stderr(io.StringIO()):
                    self.client = Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S}s")
            except (OSError, TimeoutError, ValueError) as error:
                reason = str(error).splitlines()[0] if str(error) else type(error).__name__
                raise InputError(scheduler, "--scheduler", f"cannot reach it: {reason}") from None
            self.scheduler = scheduler
        else:
            n = workers or os.cpu_count() or 1
            with dask.config.set(WORKER_CONFIG):
                self.cluster = LocalCluster(
                    n_workers=n,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                    # The scheduler's HTTP server on a free port: on 8787, taken by
                    # another cluster, it warns on stderr (place says one line there).
                    scheduler_kwargs={"dashboard": False, "dashboard_address": ":0"},
                    silence_logs=quiet,
                )
            self.client = Client(self.cluster)
            self.scheduler = "LocalCluster"
        self.source = payload
        try:
            self.workers = self._send_cell()
        except BaseException:  # Ctrl-C or a worker's error: no cluster left running
            self.close()
            raise

    def _send_cell(self) -> int:
        """Scatter the cell to every worker and have each load it now, in parallel (not
        on its first candidate); the number of workers.

        Raises:
            InputError: no worker joins the scheduler within CONNECT_TIMEOUT_S.
        """
        try:
            with contextlib.redirect_stderr(io.StringIO()):
                self.client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
        except TimeoutError:
            raise InputError(
                self.scheduler,
                "--scheduler",
                f"no worker joined it within {CONNECT_TIMEOUT_S} s: start "
                f"`dask worker {self.scheduler} --nthreads 1` where offline_prog is installed",
            ) from None
        addresses = list(self.client.scheduler_info()["workers"])
        self.payload = self.client.scatter(self.source, broadcast=True, hash=False)
        self.client.gather(
            [self.client.submit(_load, self.payload, workers=[a], pure=False) for a in addresses]
        )
        return len(addresses)

    def map(
        self,
        stage: str,
        candidates: Sequence[Candidate],
        done: Callable[[int], None] = lambda n: None,
    ) -> list[Evaluation]:
        """The evaluations in the candidates' order. A task whose worker was lost (the
        task or the cell with it: ``KilledWorker``, a cancelled future) is run again on
        the workers left, the cell sent to them again, up to LOST_RETRIES rounds.

        Raises:
            InputError: every worker is gone (none joins within CONNECT_TIMEOUT_S).
        """
        size = CHUNKS[stage]
        chunks = [list(candidates[i : i + size]) for i in range(0, len(candidates), size)]
        results: list = [None] * len(chunks)
        todo = list(range(len(chunks)))
        for _ in range(LOST_RETRIES + 1):
            todo = self._run(stage, chunks, todo, results, done)
            if not todo:
                return [e for chunk in results for e in chunk]
            self.workers = self._send_cell()  # the cell again, to the workers left
        raise InputError(
            self.scheduler, "--scheduler", f"workers kept being lost ({LOST_RETRIES} rounds)"
        )

    def _run(self, stage, chunks, todo, results, done) -> list[int]:
        """Run the chunks ``todo`` into ``results``; the indices whose worker was lost.

        Raises:
            InputError: no worker is left to run them (for 2 × CONNECT_TIMEOUT_S).
        """
        from concurrent.futures import CancelledError

        from dask.distributed import KilledWorker, wait

        futures = {
            self.client.submit(run_chunk, stage, chunks[i], self.payload, pure=False): i
            for i in todo
        }
        pending, lost, idle = set(futures), [], 0
        try:
            while pending:
                try:
                    finished, pending = wait(
                        pending, timeout=CONNECT_TIMEOUT_S, return_when="FIRST_COMPLETED"
                    )
                except TimeoutError:  # nothing finished: is anyone still working?
                    idle = 0 if self.client.scheduler_info()["workers"] else idle + 1
                    if idle >= 2:
                        raise InputError(
                            self.scheduler, "--scheduler", "every worker was lost"
                        ) from None
                    continue
                for future in sorted(finished, key=futures.get):
                    i = futures[future]
                    try:
                        results[i] = future.result()  # a worker's exception is raised here
                    except (KilledWorker, CancelledError):
                        lost.append(i)
                        continue
                    done(len(chunks[i]))
        except BaseException:
            self.client.cancel(list(futures))
            raise
        return sorted(lost)

    def close(self) -> None:
        with contextlib.suppress(Exception), contextlib.redirect_stderr(io.StringIO()):
            self.client.close(timeout=CONNECT_TIMEOUT_S)
            if self.cluster is not None:
                self.cluster.close(timeout=CONNECT_TIMEOUT_S)
