"""Where the runs of a sweep or a hunt go: the executor seam. The local process pool by default,
or a Dask distributed scheduler (`--cluster ADDRESS`); both are `concurrent.futures` executors,
and tasks are batches of runs sized to last about a second (`Batcher`).
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import contextlib
import importlib
import logging
import math
import multiprocessing
import os
import signal
from collections.abc import Iterator, Mapping
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any, Final

TASK_S: Final = 1.0  # a task's aim in seconds: Dask costs about 1 ms a task, so 0.1% of it
PER_SLOT: Final = 2  # tasks in flight per worker slot: one running, one queued behind it
CONNECT_S: Final = 5.0  # how long --cluster waits for its scheduler to answer
MISSING_DASK: Final = "--cluster needs dask: pip install 'fatswarm[cluster]'"


class ClusterError(Exception):
    """--cluster cannot be used: dask missing, or its scheduler does not answer (one line)."""


def add_cluster_argument(p: argparse.ArgumentParser) -> None:
    """`--cluster ADDRESS`, shared by `fatswarm sweep` and `fatswarm hunt`."""
    p.add_argument(
        "--cluster",
        metavar="ADDRESS",
        default=None,
        help="run on the Dask distributed scheduler at ADDRESS (e.g. tcp://host:8786; needs "
        "fatswarm[cluster]) instead of local worker processes; --jobs is then ignored",
    )


def init_worker() -> None:
    """A local worker ignores Ctrl-C (the sweep or hunt stops it), dies on SIGTERM, and logs
    to no terminal (a run's warnings go to its row)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    quiet_logs()


def quiet_logs() -> None:
    """fatswarm's log lines stay in the worker (a Dask worker runs no initializer: each task
    calls this)."""
    logging.getLogger("fatswarm").propagate = False


def absolute_ref(ref: str) -> str:
    """`path/file.py:attribute` with an absolute path, as runs travel to workers (a Dask worker
    started in another directory resolves a relative one against its own) and as a command
    written for another directory names it; any other reference as it is."""
    path, sep, attr = ref.rpartition(":")
    if sep and path.endswith(".py"):
        return f"{os.path.abspath(path)}:{attr}"
    return ref


@dataclass(slots=True)
class Workers:
    """An open executor and how many runs it runs at once (`slots`). `died` are the exceptions
    a future raises when its worker vanished; `kill` drops every run now, `close` ends it."""

    executor: cf.Executor
    slots: int
    where: str  # for the plan line: "2 worker processes", "the Dask cluster at ..."
    died: tuple[type[BaseException], ...]
    client: Any = None  # the Dask client, when on a cluster
    owns_client: bool = True  # False: the caller's Client (the API's `cluster=`), left open

    def kill(self) -> None:
        """Drop every run: local workers are terminated; on a cluster, the tasks are cancelled
        (a task running there ends its batch, about a second, and its result is dropped)."""
        if self.client is None:
            _kill_pool(self.executor)
        else:
            self.executor.shutdown(wait=False)

    def close(self) -> None:
        if self.client is None:
            self.executor.shutdown(wait=True, cancel_futures=True)
        else:
            self.executor.shutdown(wait=False)
            if self.owns_client:
                self.client.close(timeout=CONNECT_S)


@contextlib.contextmanager
def open_workers(jobs: int, cluster: object | None) -> Iterator[Workers]:
    """The executor runs go to: `jobs` local worker processes, or the Dask scheduler at
    `cluster` (its address, or a `distributed.Client` of the caller's, which stays open); raises
    ClusterError (one line) when that cannot be used. Closed on the way out."""
    workers = _dask_workers(cluster) if cluster is not None else _local_workers(jobs)
    try:
        yield workers
    finally:
        workers.close()


def _local_workers(jobs: int) -> Workers:
    """Spawned, not forked: the workers share no thread, lock or signal handler with this
    process (which runs a progress thread); they start on the first submits."""
    pool = cf.ProcessPoolExecutor(
        max_workers=jobs, mp_context=multiprocessing.get_context("spawn"), initializer=init_worker
    )
    where = f"{jobs} worker process{'' if jobs == 1 else 'es'}"
    return Workers(pool, jobs, where, (BrokenProcessPool,))


def _dask_workers(cluster: Any) -> Workers:
    try:  # the optional extra fatswarm[cluster], imported only when asked for (its API untyped)
        distributed: Any = importlib.import_module("distributed")
    except ImportError:
        raise ClusterError(MISSING_DASK) from None
    owned = not isinstance(cluster, distributed.Client)
    if owned and not isinstance(cluster, str):
        raise ClusterError(
            f"cluster must be a Dask scheduler's address or a distributed.Client, got "
            f"{type(cluster).__name__}"
        )
    address = cluster if isinstance(cluster, str) else cluster.scheduler.address
    try:
        client = (
            distributed.Client(address, timeout=CONNECT_S, set_as_default=False)
            if owned
            else cluster
        )
    except (OSError, TimeoutError, ValueError) as exc:
        raise ClusterError(
            f"--cluster {address}: no Dask scheduler answered within {CONNECT_S:g} s "
            f"({type(exc).__name__}); start one (dask scheduler) or check the address"
        ) from None
    threads = sum(client.nthreads().values())
    slots = max(1, threads)
    where = f"the Dask cluster at {address} ({threads} worker threads now)"
    executor = client.get_executor(pure=False)
    return Workers(executor, slots, where, (distributed.KilledWorker,), client, owned)


def _kill_pool(pool: cf.Executor) -> None:
    """Stop a local pool's workers now (a run can take minutes); Python 3.14 has
    `terminate_workers()`, before it the processes are only reachable as `_processes`."""
    processes: Mapping[int, multiprocessing.process.BaseProcess] = (
        getattr(pool, "_processes", None) or {}
    )
    for process in list(processes.values()):
        if process.is_alive():
            process.terminate()
    for process in list(processes.values()):
        process.join(timeout=5)


@dataclass(slots=True)
class Batcher:
    """How many runs go in the next task: one until a run has been timed, then enough for about
    TASK_S seconds at the mean time a run took so far, but no more than keeps every slot busy
    to the end (a share of the runs left). Batches change only how runs travel, not what a run
    computes: each is a pure function of its configuration."""

    slots: int
    seconds: float = 0.0
    runs: int = 0

    def observe(self, wall_s: float) -> None:
        self.seconds += wall_s
        self.runs += 1

    def size(self, left: int) -> int:
        if self.runs == 0 or left <= 0:
            return 1
        per_run = max(self.seconds / self.runs, 1e-6)
        share = max(1, left // (PER_SLOT * self.slots))
        return max(1, min(math.ceil(TASK_S / per_run), share))

    def in_flight(self) -> int:
        """Tasks kept in flight at once."""
        return PER_SLOT * self.slots


__all__ = [
    "CONNECT_S",
    "MISSING_DASK",
    "TASK_S",
    "Batcher",
    "ClusterError",
    "Workers",
    "absolute_ref",
    "add_cluster_argument",
    "init_worker",
    "open_workers",
    "quiet_logs",
]
