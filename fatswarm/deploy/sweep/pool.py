"""The machinery of `fatswarm sweep`: lock-step runs in batches on the executor's workers, the
loop that runs a grid, and the CSV table it appends to row by row (resumable: a torn last row is
cut on open).
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import logging
import os
import signal
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Final

from fatswarm.deploy.engine.config import RunConfig, RunSetup
from fatswarm.deploy.engine.lockstep import default_max_rounds, run_lockstep
from fatswarm.deploy.sweep.executor import Batcher, Workers, init_worker, quiet_logs
from fatswarm.deploy.sweep.grid import Key, RunSpec, SweepInputError, values_text
from fatswarm.deploy.sweep.table import (
    COLUMNS,
    ERROR,
    RunFigures,
    TableError,
    assignment_bound,
    header_line,
    kept_length,
    parse_table,
    row_key,
    row_line,
    table_columns,
    upgraded,
)
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import resolve_values

POLL_S: Final = 0.2  # how often the pool loop looks at the stop flag


class WorkerDiedError(RuntimeError):
    """A worker process vanished mid-run (killed, out of memory): the pool cannot go on."""


class TableWriteError(OSError):
    """A row could not be appended to the table (a full disk, a permission)."""


# -- one run, in a worker ---------------------------------------------------------------------


class _FirstWarning(logging.Handler):
    """Keeps the first warning a run logs (a robot's compute that failed) and counts the rest."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.first = ""
        self.count = 0

    def emit(self, record: logging.LogRecord) -> None:
        self.count += 1
        if not self.first:
            self.first = record.getMessage()

    def text(self) -> str:
        more = f" (+{self.count - 1} more)" if self.count > 1 else ""
        return f"{self.first}{more}" if self.first else ""


def _resolved(spec: RunSpec) -> RunSetup:
    """The run `spec` describes, checked and built exactly as `fatswarm run --lockstep` does."""
    return RunConfig(
        n=spec.n,
        algorithm=spec.algorithm,
        params=dict(spec.params),
        seed=spec.seed,
        start=spec.start,
        scheduler=spec.scheduler,
        max_rounds=spec.max_rounds,
        non_rigid=spec.non_rigid,
        crash=spec.crash,
        model=spec.robot_model,
    ).resolve()


def run_spec(spec: RunSpec) -> RunFigures:
    """Run `spec` in lock step and measure it; a run that raises is an ERROR row, not a crash."""
    logger = logging.getLogger("fatswarm")
    warnings = _FirstWarning()
    logger.addHandler(warnings)
    t0 = time.perf_counter()
    values, cap = "", None
    try:
        # the parameters and the cap first, so that a row of a run refused below still has them
        values = values_text(resolve_values(load_algorithm(spec.algorithm), dict(spec.params)))
        cap = spec.max_rounds or default_max_rounds(spec.n, spec.scheduler)
        setup = _resolved(spec)
        values, cap = values_text(setup.params.values), setup.max_rounds
        result = run_lockstep(
            setup.initial,
            setup.params,
            setup.scheduler,
            seed=setup.seed,
            max_rounds=setup.max_rounds,
            algorithm_ref=setup.algorithm_ref,
            non_rigid=setup.non_rigid,
            crash=setup.crash,
            robot_model=setup.robot_model,
        )
        wall = time.perf_counter() - t0
        try:
            bound: float | None = assignment_bound(result.initial, result.positions)
        except ImportError:  # scipy is the optional `sweep` extra: the bound stays empty
            bound = None
    except Exception as exc:  # a run that raises is a finding: its row says what, the grid goes on
        return RunFigures(
            ERROR,
            wall_s=time.perf_counter() - t0,
            values=values,
            round_cap=cap,
            error=f"{type(exc).__name__}: {exc}",
            warning=warnings.text(),
        )
    finally:
        logger.removeHandler(warnings)
    return RunFigures(
        status=str(result.status),
        rounds=result.rounds,
        epochs=result.epochs,
        looks=result.looks,
        moves=result.moves,
        collisions=result.collisions,
        total_distance=result.total_distance,
        bound=bound,
        wall_s=wall,
        values=values,
        round_cap=cap,
        warning=warnings.text(),
        outside=setup.outside,
        time=result.time,
        derived=dict(result.derived),
    )


# -- the pool ---------------------------------------------------------------------------------


def run_batch(specs: Sequence[RunSpec]) -> list[RunFigures]:
    """Run `specs` one after the other (one task of the executor, in a worker)."""
    quiet_logs()
    return [run_spec(spec) for spec in specs]


def run_all(
    todo: Sequence[RunSpec],
    workers: Workers,
    on_done: Callable[[RunSpec, RunFigures], None],
    stop: Callable[[], bool],
) -> bool:
    """Run `todo` on `workers`, in batches of about a second (`Batcher`), calling `on_done` here
    for each run of a batch as the batch ends; True when all ran, False when `stop()` turned
    true first. On any way out but the end (a stop, an exception from `on_done`) the workers'
    runs are dropped (`Workers.kill`). Raises WorkerDiedError if a worker vanished.
    """
    if not todo:
        return True
    batcher = Batcher(workers.slots)
    pending: dict[cf.Future[list[RunFigures]], Sequence[RunSpec]] = {}
    left = list(reversed(todo))  # popped from the end: the grid's order
    finished = False
    try:
        _fill(workers, batcher, pending, left)
        while pending:
            if stop():
                return False
            done, _ = cf.wait(pending, timeout=POLL_S, return_when=cf.FIRST_COMPLETED)
            for future in done:
                specs = pending.pop(future)
                results = _results(future, specs, workers, stop)
                for spec, figures in zip(specs, results, strict=True):
                    batcher.observe(figures.wall_s)
                    on_done(spec, figures)
            _fill(workers, batcher, pending, left)
        finished = True
        return True
    except _Stopped:
        return False
    finally:
        if not finished:
            workers.kill()


class _Stopped(Exception):
    """A worker died of the very signal that stops the sweep."""


def _results(
    future: cf.Future[list[RunFigures]],
    specs: Sequence[RunSpec],
    workers: Workers,
    stop: Callable[[], bool],
) -> list[RunFigures]:
    try:
        return future.result()
    except workers.died:
        if stop():  # a worker killed by the same signal, say
            raise _Stopped from None
        raise WorkerDiedError(
            "a worker process died (killed, or out of memory?) with runs in flight, "
            f"such as {specs[0].command()!r}"
        ) from None


def _fill(
    workers: Workers,
    batcher: Batcher,
    pending: dict[cf.Future[list[RunFigures]], Sequence[RunSpec]],
    left: list[RunSpec],
) -> None:
    """Submit batches while fewer than `batcher.in_flight()` are in flight. A local pool spawns
    its workers in `submit`: with SIGINT blocked here, they start with it blocked, so a Ctrl-C
    during their start-up (before `init_worker` ignores it) cannot kill them with a traceback;
    this process gets it after."""
    with sigint_blocked():
        while left and len(pending) < batcher.in_flight():
            size = batcher.size(len(left))
            specs = [left.pop() for _ in range(min(size, len(left)))]
            pending[workers.executor.submit(run_batch, specs)] = specs


@contextlib.contextmanager
def sigint_blocked() -> Iterator[None]:
    if not hasattr(signal, "pthread_sigmask"):  # not POSIX
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


# -- the CSV table ----------------------------------------------------------------------------


class RunTable:
    """The sweep's CSV file, open for appending, locked against a second sweep on it.

    Opening it cuts a torn last row (a crash mid-write) and reads the rows there. Each row is
    appended with one write and no buffer: a Ctrl-C, which this process only acts on between
    Python steps, cannot leave half a row. Its `columns` are its header's (`table_columns`): a
    table of the paper's robot model alone has no model columns. A table of an earlier fatswarm
    (or of the paper's model alone, for a grid with model axes) is written again first, whole,
    with the columns it lacks filled in (`table.upgraded`), then resumed.
    """

    def __init__(
        self,
        path: str,
        fd: int,
        rows: list[dict[str, str]],
        cut: int,
        columns: tuple[str, ...] = COLUMNS,
    ) -> None:
        self.path = path
        self._fd = fd
        self.rows = rows  # the rows there when opened, then every row appended
        self.cut = cut  # bytes of a torn last row cut on opening (0: none)
        self.columns = columns

    @staticmethod
    def open(path: str, *, models: bool = False) -> RunTable:
        """Open (or create) the table at `path`, for a grid with robot `models` other than the
        paper's (`Grid.has_models`: a new table gets the model columns) or without; raises
        SweepInputError (TableError for a file that is not a sweep table, a table without the
        model columns when `models`, or one another sweep holds)."""
        _check_output(path)
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_CLOEXEC, 0o644)
        except OSError as exc:
            raise SweepInputError(f"--out {path}: cannot open it: {exc.strerror}") from None
        try:
            _lock(fd, path)
            data = _read_all(fd)
            columns = table_columns(data, path, models=models)  # ours, or a torn header
            keep = kept_length(data)
            if keep < len(data):
                os.ftruncate(fd, keep)
            text = data[:keep].decode("utf-8", errors="replace")
            new = upgraded(text, path, columns) if keep else None
            if new is not None:
                fd = _replaced(fd, path, new)
                text = new
            rows = parse_table(text, path)
            if keep == 0:
                _write_all(fd, header_line(columns).encode())
        except BaseException:
            os.close(fd)
            raise
        return RunTable(path, fd, rows, len(data) - keep, columns)

    def keys(self) -> set[Key]:
        return {row_key(row) for row in self.rows}

    def append(self, row: dict[str, str]) -> None:
        """Add one row at the end of the file; raises TableWriteError (a full disk...)."""
        dropped = [c for c in row if c not in self.columns and row.get(c)]
        assert not dropped, f"a row with {dropped} in a table without those columns"
        try:
            _write_all(self._fd, row_line(row, self.columns).encode())
        except OSError as exc:
            raise TableWriteError(f"cannot write {self.path}: {exc.strerror or exc}") from None
        self.rows.append(row)

    def close(self) -> None:
        if self._fd >= 0:
            os.close(self._fd)  # releases the lock
            self._fd = -1


def _replaced(fd: int, path: str, text: str) -> int:
    """Put `text` in place of the table at `path` (open and locked as `fd`) in one step: written
    and synced beside it, then renamed over it, so a crash leaves the old table or the new one;
    the new file's descriptor, locked (the old one is closed)."""
    folder = os.path.dirname(os.path.abspath(path))
    spare, tmp = tempfile.mkstemp(prefix=".sweep-", suffix=".csv", dir=folder)
    try:
        os.fchmod(spare, os.fstat(fd).st_mode & 0o777)  # the old table's permissions
        _write_all(spare, text.encode())
        os.fsync(spare)
        os.replace(tmp, path)
    except OSError as exc:
        os.close(spare)
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise SweepInputError(
            f"--out {path}: cannot write its new columns: {exc.strerror}"
        ) from None
    os.close(fd)
    os.close(spare)
    fd = os.open(path, os.O_RDWR | os.O_APPEND | os.O_CLOEXEC)
    _lock(fd, path)
    return fd


def _check_output(path: str) -> None:
    if os.path.isdir(path):
        raise SweepInputError(f"--out {path} is a directory; name a CSV file")
    if os.path.exists(path) and not os.path.isfile(path):
        raise SweepInputError(f"--out {path} is not a regular file; name a CSV file")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise SweepInputError(
            f"--out {path}: the directory {folder} does not exist; create it first"
        )


def _lock(fd: int, path: str) -> None:
    try:
        import fcntl  # POSIX only: imported here so that a table opens (unlocked) elsewhere
    except ImportError:  # not POSIX: no lock, as no second sweep is expected there
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        raise TableError(
            f"another fatswarm sweep is writing {path}; let it finish or name another --out"
        ) from None


def _read_all(fd: int) -> bytes:
    chunks, offset = [], 0
    while chunk := os.pread(fd, 1 << 20, offset):
        chunks.append(chunk)
        offset += len(chunk)
    return b"".join(chunks)


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]


__all__ = [
    "RunTable",
    "TableWriteError",
    "WorkerDiedError",
    "init_worker",
    "run_all",
    "run_batch",
    "run_spec",
    "sigint_blocked",
]
