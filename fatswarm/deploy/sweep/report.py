"""What `fatswarm sweep` shows: its progress while it runs (a rich bar on a terminal, plain
lines otherwise, with an ETA) and, at the end, the summary table of its cells."""

from __future__ import annotations

import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final, TextIO

from rich import box
from rich.console import Console
from rich.table import Table

from fatswarm.deploy.sweep.summary import Cell
from fatswarm.deploy.sweep.table import ERROR, RunFigures
from fatswarm.domain.outcome import Status

PROGRESS_SECONDS: Final = 5.0  # at most one plain progress line per this many seconds


# -- progress ---------------------------------------------------------------------------------


class _Progress:
    """Counts finished runs; shown by a subclass (plain lines, a rich bar) or not at all."""

    def __init__(self, total: int) -> None:
        self.total = total
        self.done = self.formed = self.collided = self.errors = 0
        self.started = time.monotonic()

    def advance(self, figures: RunFigures) -> None:
        self.done += 1
        self.formed += figures.status == Status.FORMED
        self.collided += figures.collisions > 0
        self.errors += figures.status == ERROR
        self.show()

    def show(self) -> None:
        """Nothing to show (quiet)."""

    def counts(self) -> str:
        return f"formed {self.formed}  collided {self.collided}  errors {self.errors}"

    def __enter__(self) -> _Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        return None


class _PlainProgress(_Progress):
    """A line on stderr every PROGRESS_SECONDS (for a log file or a pipe) and at the end."""

    def __init__(self, total: int, out: TextIO) -> None:
        super().__init__(total)
        self.out = out
        self.last = self.started

    def show(self) -> None:
        now = time.monotonic()
        if now - self.last >= PROGRESS_SECONDS or self.done == self.total:
            self.last = now
            rate = self.done / max(now - self.started, 1e-9)
            eta = (self.total - self.done) / rate if rate > 0 else 0.0
            print(
                f"sweep: {self.done}/{self.total} runs  {self.counts()}  ETA {_duration(eta)}",
                file=self.out,
                flush=True,
            )


class _RichProgress(_Progress):
    """A rich progress bar on the terminal (stderr), with the counts beside it."""

    def __init__(self, total: int) -> None:
        # rich's progress bar brings its Live machinery: the CLI imports this module (through
        # deploy.sweep.command) to build its parser, and only a sweep on a terminal draws one
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        super().__init__(total)
        self.bar = Progress(
            TextColumn("sweep"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[counts]}"),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=Console(stderr=True),
            transient=False,
        )
        self.task = self.bar.add_task("sweep", total=total, counts=self.counts())

    def show(self) -> None:
        self.bar.update(self.task, completed=self.done, counts=self.counts())

    def __enter__(self) -> _Progress:
        self.bar.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.bar.stop()


def make_progress(total: int, *, quiet: bool) -> _Progress:
    """What shows the sweep's progress: nothing (quiet), a rich bar on a terminal, else lines."""
    if quiet:
        return _Progress(total)
    if sys.stderr.isatty():
        return _RichProgress(total)
    return _PlainProgress(total, sys.stderr)


def _duration(seconds: float) -> str:
    whole = round(seconds)
    if whole < 60:
        return f"{whole}s"
    if whole < 3600:
        return f"{whole // 60}m{whole % 60:02d}s"
    return f"{whole // 3600}h{whole // 60 % 60:02d}m"


# -- the summary ------------------------------------------------------------------------------


def summary_table(cells: Sequence[Cell]) -> Table:
    """The sweep's summary, one line per (algorithm, start, model, n) (`sweep.summarize`, the
    groups of the Markdown table split by n): how many runs formed, collided and stalled (hit the
    round cap or raised, when any did), and the median rounds, distance ratio and (async models,
    when any) virtual time of the formed ones. The model is `sweep.model_label`'s (`fsync`,
    `ssync+nr1`, `async+crash2`). Algorithm and start columns only when the grid has several, so
    that the common table fits 80 columns."""
    shown = _Shown.of(cells)
    table = Table(box=box.SIMPLE_HEAD, pad_edge=False, show_edge=False)
    for name in shown.lead():
        table.add_column(name)
    table.add_column("model")
    for name in shown.figures():
        table.add_column(name, justify="right")
    for c in cells:
        table.add_row(*shown.row(c))
    return table


@dataclass(frozen=True, slots=True)
class _Shown:
    """Which columns the summary table shows besides the model and the common figures: the
    algorithm and start when the grid has several, capped, errors and time when any run has one."""

    algorithm: bool
    start: bool
    capped: bool
    errors: bool
    time: bool

    @staticmethod
    def of(cells: Sequence[Cell]) -> _Shown:
        return _Shown(
            algorithm=len({c.algorithm for c in cells}) > 1,
            start=len({c.start for c in cells}) > 1,
            capped=any(c.capped for c in cells),
            errors=any(c.errors for c in cells),
            time=any(c.time is not None for c in cells),
        )

    def lead(self) -> list[str]:
        """The columns before the model."""
        return (["algorithm"] if self.algorithm else []) + (["start"] if self.start else [])

    def figures(self) -> list[str]:
        """The columns after the model: counts, then medians."""
        counts = ["n", "runs", "formed", "collided", "stalled"]
        counts += ["capped"] if self.capped else []
        counts += ["errors"] if self.errors else []
        medians = ["median\nrounds", "median\nratio"] + (["median\ntime"] if self.time else [])
        return [*counts, *medians]

    def row(self, c: Cell) -> list[str]:
        """The cells of one line of the table."""
        lead = ([c.algorithm] if self.algorithm else []) + ([c.start] if self.start else [])
        figures = [c.n, c.runs, c.formed, c.collided, c.stalled]
        figures += [c.capped] if self.capped else []
        figures += [c.errors] if self.errors else []
        times = ["-" if c.time is None else f"{c.time[1]:.1f}"] if self.time else []
        return [
            *lead,
            c.model,
            *map(str, figures),
            "-" if c.rounds is None else f"{c.rounds[1]:g}",
            "-" if c.ratio is None else f"{c.ratio[1]:.3f}",
            *times,
        ]


def print_summary(cells: Sequence[Cell], out: TextIO) -> None:
    """Print the summary table to `out` (no colour nor wrapping off a terminal)."""
    tty = out.isatty()
    console = Console(file=out, width=None if tty else 200, no_color=not tty, highlight=False)
    console.print(summary_table(cells))


__all__ = ["make_progress", "print_summary", "summary_table"]
