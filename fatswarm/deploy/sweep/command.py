"""`fatswarm sweep`: a grid of lock-step runs on every core, one CSV row per run, resumable.

Flags build the grid (`deploy/sweep/grid.py`), `deploy/sweep/pool.py` runs it and keeps the table;
`deploy/sweep/report.py` shows progress (a rich bar on a terminal, plain lines otherwise) and the
summary; this module says the runs to look at and draws the figures (`deploy/sweep/figures.py`).
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import signal
import sys
from collections.abc import Sequence
from contextlib import suppress
from dataclasses import replace
from typing import TYPE_CHECKING, Final

from fatswarm.coordinator.schedule import NAMES
from fatswarm.deploy.engine.config import DEFAULT_START, check_lights, input_errors
from fatswarm.deploy.flags import add_robot_model_arguments, check_writable
from fatswarm.deploy.scenarios.starts import KINDS
from fatswarm.deploy.sweep.batch_flags import (
    add_adversary_arguments,
    add_jobs_argument,
    add_max_rounds_argument,
    add_param_argument,
    add_quiet_argument,
    add_scheduler_argument,
    add_sizes_argument,
    jobs_of,
    stop_on_signals,
)
from fatswarm.deploy.sweep.executor import ClusterError, Workers, absolute_ref, open_workers
from fatswarm.deploy.sweep.figures import draw_figures
from fatswarm.deploy.sweep.grid import (
    Grid,
    Key,
    RunSpec,
    SweepInputError,
    params_text,
    parse_crash,
    parse_ints,
    parse_non_rigid,
    parse_seeds,
    robot_models_of,
    split_values,
    sweep_schedulers,
)
from fatswarm.deploy.sweep.report import make_progress, print_summary
from fatswarm.deploy.sweep.summary import Cell, is_clean, markdown_table, summarize
from fatswarm.deploy.sweep.table import ERROR, RunFigures, make_row, row_key
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.registry import DEFAULT as DEFAULT_ALGORITHM
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import Configured
from fatswarm.domain.version import __version__
from fatswarm.domain.words import counted, unit

if TYPE_CHECKING:
    from fatswarm.deploy.sweep.pool import RunTable

DEFAULT_SIZES: Final = "4,8,16"
DEFAULT_SEEDS: Final = "10"
DEFAULT_OUT: Final = "runs.csv"
SHOWN_FAILURES: Final = 5  # commands printed for runs that did not form collision-free
MISSING_MATPLOTLIB: Final = (
    "fatswarm sweep: --plot needs matplotlib: install it with `pip install 'fatswarm[plot]'` "
    "(or `pip install matplotlib`)"
)
MISSING_SCIPY: Final = (
    "fatswarm sweep: scipy is not installed, so the bound and ratio columns stay empty "
    "(`pip install 'fatswarm[sweep]'` fills them)"
)
DESCRIPTION: Final = (
    "Run a grid of lock-step runs (algorithm x n x start kind x scheduler x non-rigid delta x "
    "robot model (its axes: docs/model.md) x crash count x seeds) "
    "on every core, appending one CSV row per run (outcome, cost, the "
    "distance's ratio to the optimal-assignment bound, the virtual time of async runs, wall "
    "time, the configuration and the `fatswarm run --lockstep` command that repeats it). "
    "Resumable: interrupted (Ctrl-C), the same command goes on where it stopped, as rows already "
    "in the CSV are skipped. Docs: docs/sweep.md."
)
EPILOG: Final = (
    "Lists: a flag takes a comma list and can be repeated; numbers also take inclusive ranges "
    "LOW..HIGH[:STEP] (-n 4..16:4 is 4,8,12,16). exit codes: 0 every run of the grid is in the "
    "CSV (whatever its outcome); 1 a worker process died, or every run of the grid failed "
    "(status error); 2 bad input (one line on stderr says "
    "what to fix); 4 the CSV could not be written; 130 interrupted (the rows written stay: run "
    "the same command again to go on); 143 terminated."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm sweep`."""
    p.description = DESCRIPTION
    p.epilog = EPILOG
    _add_grid_arguments(p)
    add_param_argument(p, "the algorithms")
    add_max_rounds_argument(p)
    add_robot_model_arguments(p, lists=True)
    _add_output_arguments(p)


def _add_grid_arguments(p: argparse.ArgumentParser) -> None:
    """The grid's axes: algorithms, sizes, start kinds, schedulers, adversaries and seeds."""
    usable = ", ".join(sweep_schedulers())
    p.add_argument(
        "--algorithm",
        action="append",
        default=[],
        metavar="NAMES",
        help=f"algorithms to run (default {DEFAULT_ALGORITHM}; a registered name, "
        "module:attribute or path/to/file.py:attribute)",
    )
    add_sizes_argument(p, "e.g. 4,8,16 or 4..32:4", DEFAULT_SIZES)
    p.add_argument(
        "--start",
        "--starts",
        action="append",
        default=[],
        metavar="KINDS",
        help=f"random start kinds: {', '.join(KINDS)} (default {DEFAULT_START}; --starts, "
        "hunt's name, is the same flag)",
    )
    add_scheduler_argument(p, "to run under", usable)
    add_adversary_arguments(p, lists=True)
    p.add_argument(
        "--seeds",
        action="append",
        default=[],
        metavar="SEEDS",
        help="seeds: a count K (seeds 0..K-1), a range 100..119 or a list 3,7 "
        f"(default {DEFAULT_SEEDS}: seeds 0..9)",
    )


def _add_output_arguments(p: argparse.ArgumentParser) -> None:
    """Where the rows, the summary and the figures go, and how the sweep runs."""
    p.add_argument(
        "--out",
        default=DEFAULT_OUT,
        metavar="CSV",
        help=f"the table to append to (default {DEFAULT_OUT}); its rows are skipped",
    )
    add_jobs_argument(p)
    p.add_argument(
        "--plot",
        metavar="DIR",
        help="write summary figures to DIR (created if missing; needs matplotlib)",
    )
    p.add_argument(
        "--summary-md",
        metavar="PATH",
        help="write the summary over every n as a Markdown table to PATH (replaced "
        "if it exists), a line per algorithm, scheduler, non-rigid delta, crash "
        "count and robot model",
    )
    add_quiet_argument(p)


def build_grid(args: argparse.Namespace) -> Grid:
    """The grid the flags ask for, checked; raises SweepInputError or one of
    `config.input_errors()` with a line saying what to fix."""
    sizes = parse_ints(args.n or [DEFAULT_SIZES], "-n", least=1)
    seeds = parse_seeds(args.seeds or [DEFAULT_SEEDS])
    starts = _start_kinds(args.start)
    schedulers = _schedulers(args.scheduler)
    if args.max_rounds is not None and args.max_rounds < 1:
        raise SweepInputError(f"--max-rounds must be at least 1, got {args.max_rounds}")
    non_rigids = parse_non_rigid(args.non_rigid)
    crashes = parse_crash(args.crash)
    models = robot_models_of(args)
    if getattr(args, "record_views", False):
        raise SweepInputError(
            "--record-views: a sweep keeps no records; add it to a row's command to see "
            "what each robot saw"
        )
    algorithms = []
    for ref in split_values(args.algorithm) or (DEFAULT_ALGORITHM,):
        algorithm = load_algorithm(ref)
        texts = params_text(algorithm, args.param)
        # refuse an n the algorithm refuses now, not once per run; and --lights without lights
        settings = [Configured.of(algorithm, n, dict(texts)) for n in sizes]
        for model in models:
            check_lights(model, settings[0])
        algorithms.append((ref, texts))
    return Grid(
        tuple(algorithms),
        sizes,
        starts,
        schedulers,
        seeds,
        args.max_rounds,
        non_rigids,
        crashes,
        models,
    )


def _start_kinds(given: Sequence[str]) -> tuple[str, ...]:
    """The --start kinds asked for (default DEFAULT_START); SweepInputError."""
    starts = split_values(given) or (DEFAULT_START,)
    for kind in starts:
        if kind not in KINDS:
            raise SweepInputError(
                f"--start {kind}: not a start kind; choose from {', '.join(KINDS)}"
            )
    return starts


def _schedulers(given: Sequence[str]) -> tuple[str, ...]:
    """The --scheduler models asked for (default: every one a sweep takes); SweepInputError."""
    usable = sweep_schedulers()
    schedulers = split_values(given) or usable
    for name in schedulers:
        if name not in usable:
            why = "needs a schedule file" if name in NAMES else "is not a scheduler"
            raise SweepInputError(f"--scheduler {name} {why}; a sweep takes {', '.join(usable)}")
    return schedulers


def main(args: argparse.Namespace) -> int:
    """`fatswarm sweep`: run what the CSV lacks of the grid, then summarise; the exit code."""
    # the pool brings the whole lock-step engine and multiprocessing: the CLI imports this
    # module to build its parser
    from fatswarm.deploy.sweep.pool import RunTable

    refused: tuple[type[Exception], ...] = (SweepInputError, *input_errors())
    try:
        grid = build_grid(args)
        jobs = jobs_of(args.jobs)
        _check_plot(args.plot)
        _check_summary_md(args.summary_md)
        table = RunTable.open(args.out, models=grid.has_models)
    except refused as exc:
        return _fail(str(exc))
    try:
        return _sweep(args, grid, jobs, table)
    finally:
        table.close()


def _sweep(args: argparse.Namespace, grid: Grid, jobs: int, table: RunTable) -> int:
    runs = grid.runs()
    todo = _todo(table, runs)
    try:
        # nothing to run asks nothing of a cluster (nor of dask)
        cluster = args.cluster if todo else None
        with open_workers(max(1, min(jobs, len(todo))), cluster) as workers:
            _plan(args, grid, table, runs, len(todo), workers.where)
            return _run(args, grid, table, (runs, todo), workers)
    except ClusterError as exc:
        return _fail(str(exc))


def _run(
    args: argparse.Namespace,
    grid: Grid,
    table: RunTable,
    runs_todo: tuple[Sequence[RunSpec], Sequence[RunSpec]],
    workers: Workers,
) -> int:
    """Run the `todo` of the grid's `runs` on `workers` into `table`, then summarise; the exit
    code."""
    # the lock-step engine: the CLI imports this module for its parser
    from fatswarm.deploy.sweep.pool import TableWriteError, WorkerDiedError, run_all

    runs, todo = runs_todo
    keys = {spec.key() for spec in runs}

    def record(spec: RunSpec, figures: RunFigures) -> None:
        table.append(make_row(spec, figures, __version__))
        progress.advance(figures)

    shipped = Shipped(todo)
    progress = make_progress(len(todo), quiet=args.quiet or not todo)
    try:
        with stop_on_signals() as stopped, progress:
            complete = run_all(
                shipped.runs,
                workers,
                lambda spec, figures: record(shipped.given(spec), figures),
                lambda: stopped[0] is not None,
            )
    except TableWriteError as exc:
        _say(
            f"fatswarm sweep: {exc}; the rows written stay, run the same command again once "
            "it is fixed"
        )
        return ExitCode.RECORD_FAILED
    except WorkerDiedError as exc:  # exit 1: the sweep did not finish, and not by a signal
        _say(f"fatswarm sweep: {exc}; the rows written stay, run the same command again to go on")
        return ExitCode.NOT_FORMED
    if not complete:
        return _stopped(args.out, table, keys, len(runs), stopped[0])
    return _finish(args, grid, [row for row in table.rows if row_key(row) in keys])


class Shipped:
    """The runs as they travel to the workers: an algorithm file's path made absolute (a Dask
    worker started in another directory would look for a relative one there, and every run would
    fail), each mapped back to the run as given, whose row keeps the reference as typed."""

    def __init__(self, todo: Sequence[RunSpec]) -> None:
        self.runs = [replace(spec, algorithm=absolute_ref(spec.algorithm)) for spec in todo]
        self._given: dict[RunSpec, list[RunSpec]] = {}
        for spec, sent in zip(todo, self.runs, strict=True):
            self._given.setdefault(sent, []).append(spec)

    def given(self, sent: RunSpec) -> RunSpec:
        """The run as given of a run as sent (each once: `a.py` and `/abs/a.py` are two rows)."""
        return self._given[sent].pop(0)


def _todo(table: RunTable, runs: Sequence[RunSpec]) -> list[RunSpec]:
    """The runs of the grid the table lacks."""
    present = table.keys()
    return [spec for spec in runs if spec.key() not in present]


def _plan(
    args: argparse.Namespace,
    grid: Grid,
    table: RunTable,
    runs: Sequence[RunSpec],
    todo: int,
    where: str,
) -> None:
    """The plan (and a torn row cut, runs left out, scipy missing), said on stderr."""
    keys = {spec.key() for spec in runs}
    other = sum(1 for row in table.rows if row_key(row) not in keys)
    if table.cut:
        _say(f"{args.out}: cut a torn last row ({table.cut} bytes); that run is done again")
    if not args.quiet:
        _say(_plan_text(args.out, len(runs), len(runs) - todo, other, where))
        if grid.left_out:
            left = counted(grid.left_out, "run")
            _say(f"sweep: {left} left out, whose --crash F is >= their n (0 < F < n)")
    if todo and importlib.util.find_spec("scipy") is None:
        _say(MISSING_SCIPY)


def _stopped(out: str, table: RunTable, keys: set[Key], total: int, signum: int | None) -> int:
    """Say how far a sweep stopped by a signal got; its exit code."""
    done = sum(1 for row in table.rows if row_key(row) in keys)
    word = "interrupted" if signum == signal.SIGINT else "terminated"
    _say(
        f"{word}: {done} of {counted(total, 'run')} of the grid are in {out}; run the same "
        "command again to go on"
    )
    return ExitCode.INTERRUPTED if signum == signal.SIGINT else ExitCode.TERMINATED


def _finish(args: argparse.Namespace, grid: Grid, rows: Sequence[dict[str, str]]) -> int:
    """The end of a complete sweep, from the grid's `rows`: the summary, the runs to look at, the
    Markdown table and the figures asked for; the exit code (1 when every run raised)."""
    cells = summarize(rows, grid)
    print_summary(cells, sys.stdout)
    if rows and all(row["status"] == ERROR for row in rows):  # nothing to sum up or to draw
        _say(all_failed_text(rows, args.out))
        return ExitCode.NOT_FORMED
    _show_failures(rows, args.out)
    if args.summary_md:
        try:
            _write_text(args.summary_md, markdown_table(summarize(rows, grid, by_n=False)))
        except OSError as exc:
            return _fail(f"cannot write {args.summary_md}: {exc.strerror or exc}")
        _say(f"summary table: {args.summary_md}")
    if args.plot:
        return _plot(cells, args.plot)
    return ExitCode.OK


def all_failed_text(rows: Sequence[dict[str, str]], out: str) -> str:
    """The one line of a sweep in which every run raised (exit 1): how many, and the first
    error (`AlgorithmError: --algorithm: no file halfway.py`, say)."""
    every = "the run" if len(rows) == 1 else f"every one of the {len(rows)} runs"
    return (
        f"fatswarm sweep: {every} of the grid failed, none ran to an end (status error in "
        f"{out}); the first: {rows[0]['error'] or 'no error said'}"
    )


def _plan_text(out: str, total: int, present: int, other: int, where: str) -> str:
    there = f"{present} already in {out}" if present else f"none in {out} yet"
    others = f" (and {counted(other, 'row')} of other grids, left as they are)" if other else ""
    todo = total - present
    return f"sweep: {counted(total, 'run')}, {there}{others}; " + (
        f"{todo} to run on {where}" if todo else "nothing to run"
    )


def _check_plot(folder: str | None) -> None:
    if folder is None:
        return
    if importlib.util.find_spec("matplotlib") is None:
        raise SweepInputError(MISSING_MATPLOTLIB.removeprefix("fatswarm sweep: "))
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise SweepInputError(f"--plot {folder} is not a directory")
    parent = os.path.dirname(os.path.abspath(folder))
    if not os.path.isdir(parent):
        raise SweepInputError(f"--plot {folder}: the directory {parent} does not exist")


def _check_summary_md(path: str | None) -> None:
    """Refuse a --summary-md PATH that cannot be written, before anything runs."""
    if path is not None:
        check_writable("--summary-md", path)


def _write_text(path: str, text: str) -> None:
    """Write `text` to `path` whole: a temporary file beside it, renamed over it, so a reader
    (or a crash) never sees half a table."""
    partial = f"{path}.partial"
    try:
        with open(partial, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(partial, path)
    except OSError:
        with suppress(OSError):
            os.remove(partial)
        raise


def _plot(cells: Sequence[Cell], folder: str) -> int:
    try:
        written = draw_figures(cells, folder)
    except OSError as exc:
        return _fail(f"cannot write the figures in {folder}: {exc.strerror or exc}")
    _say("figures: " + ", ".join(written))
    return ExitCode.OK


def _show_failures(rows: Sequence[dict[str, str]], out_path: str) -> None:
    failed = [row for row in rows if not is_clean(row)]
    if not failed:
        return
    _say(
        f"{len(failed)} of {counted(len(rows), 'run')} did not form collision-free (see the "
        "status, "
        f"collisions and command columns of {out_path}); repeat one with, e.g.:"
    )
    for row in failed[:SHOWN_FAILURES]:
        _say(f"  {row['command']}    # {_outcome(row)}")


def _outcome(row: dict[str, str]) -> str:
    if row["status"] == ERROR:
        return f"error: {row['error']}"
    word = unit(row["scheduler"])  # cycles under an async model
    rounds, collisions = (
        counted(int(k), w) if k.isdigit() else f"{k} {w}s"
        for k, w in ((row["rounds"], word), (row["collisions"], "collision"))
    )
    return f"{row['status']} after {rounds}, {collisions}"


def _say(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _fail(message: str) -> int:
    _say(f"fatswarm sweep: {message}")
    return ExitCode.BAD_INPUT


__all__ = ["add_arguments", "build_grid", "main"]
