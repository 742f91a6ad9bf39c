"""What `fatswarm hunt` shows: its progress while it runs (a rich bar on a terminal, plain lines
otherwise) and, at the end, the counts of every kind found and the table of saved failures."""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Final, TextIO

from rich import box
from rich.console import Console
from rich.table import Table

from fatswarm.deploy.hunt.files import kind_counts
from fatswarm.deploy.sweep.grid import model_label
from fatswarm.domain.assumptions import Assumptions, Outside
from fatswarm.domain.robot_model import RobotModel
from fatswarm.domain.words import counted, unit

if TYPE_CHECKING:
    from fatswarm.deploy.hunt.pool import Budget, Saved, Tally

PROGRESS_SECONDS: Final = 5.0  # at most one plain progress line per this many seconds


# -- progress -------------------------------------------------------------------------------------


class _Progress:
    """Shows a tally (plain lines, a rich bar) or nothing (quiet)."""

    def __init__(self, budget: Budget) -> None:
        self.budget = budget

    def show(self, tally: Tally) -> None:
        """Nothing to show (quiet)."""

    @staticmethod
    def counts(tally: Tally) -> str:
        found = kind_counts(tally.kinds) or "none"
        shrinking = f"  shrinking {tally.shrinking}" if tally.shrinking else ""
        return (
            f"runs {tally.runs}  failures: {found}  saved {len(tally.saved)}{shrinking}  "
            f"refused {tally.refused}"
        )

    def done_fraction(self, tally: Tally) -> float:
        """How far the search is through its budget (the nearer of runs and seconds)."""
        parts = [0.0]
        if self.budget.runs is not None:
            parts.append(tally.runs / self.budget.runs)
        if self.budget.seconds is not None:
            parts.append((time.monotonic() - tally.started) / self.budget.seconds)
        return min(1.0, max(parts))

    def __enter__(self) -> _Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        return None


class _PlainProgress(_Progress):
    """A line on stderr every PROGRESS_SECONDS (for a log file or a pipe)."""

    def __init__(self, budget: Budget, out: TextIO) -> None:
        super().__init__(budget)
        self.out = out
        self.last = time.monotonic()

    def show(self, tally: Tally) -> None:
        now = time.monotonic()
        if now - self.last >= PROGRESS_SECONDS:
            self.last = now
            print(
                f"hunt: {self.done_fraction(tally):.0%}  {self.counts(tally)}",
                file=self.out,
                flush=True,
            )


class _RichProgress(_Progress):
    """A rich progress bar on the terminal (stderr): the budget spent, with the counts beside."""

    def __init__(self, budget: Budget) -> None:
        # rich's progress bar brings its Live machinery: the CLI imports this module (through
        # deploy.hunt.command) to build its parser, and only a hunt on a terminal draws one
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        super().__init__(budget)
        self.bar = Progress(
            TextColumn("hunt"),
            BarColumn(),
            TextColumn("{task.percentage:>3.0f}%"),
            TextColumn("{task.fields[counts]}"),
            TimeElapsedColumn(),
            console=Console(stderr=True),
            transient=False,
        )
        self.task = self.bar.add_task("hunt", total=1.0, counts="")

    def show(self, tally: Tally) -> None:
        self.bar.update(self.task, completed=self.done_fraction(tally), counts=self.counts(tally))

    def __enter__(self) -> _Progress:
        self.bar.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.bar.stop()


def make_progress(budget: Budget, *, quiet: bool) -> _Progress:
    """What shows the hunt's progress: nothing (quiet), a rich bar on a terminal, else lines."""
    if quiet:
        return _Progress(budget)
    if sys.stderr.isatty():
        return _RichProgress(budget)
    return _PlainProgress(budget, sys.stderr)


# -- the summary ----------------------------------------------------------------------------------


def summary_table(saved: Sequence[Saved]) -> Table:
    """One line per saved failure: its folder (index and kind), where the hunt found it (family,
    scheduler and robot model as a sweep labels them, n), where the saved run fails (`round 7`,
    `cycle 40` under an async model: `words.unit`) and what shrinking left (n, script rounds,
    decimals), the runs shrinking took, and whether the saved files replay to the same kind."""
    table = Table(box=box.SIMPLE_HEAD, pad_edge=False, show_edge=False)
    table.add_column("failure (folder)", no_wrap=True)
    table.add_column("found in")  # the one column that wraps on a narrow terminal
    table.add_column("fails in", no_wrap=True)
    for name in ("n", "script\nrounds", "decimals", "shrink\nruns"):
        table.add_column(name, justify="right", no_wrap=True)
    table.add_column("replays", no_wrap=True)
    for item in saved:
        s = item.summary
        found, small = s["found"], s["shrunk"]
        rounds = "-" if small["script_rounds"] is None else str(small["script_rounds"])
        replays = s["replayed"] is not None and s["replayed"]["kind"] == s["kind"]
        label = model_label(
            found["scheduler"], None, None, RobotModel.from_header(found.get("model"))
        )
        table.add_row(
            os.path.basename(item.folder),
            f"{found['family']} {label}",
            f"{unit(found['scheduler'])} {s['round']}",
            f"{found['n']}->{small['n']}",
            rounds,
            f"{found['decimals']}->{small['decimals']}",
            str(small["runs"]),
            "yes" if replays else "NO",
        )
    return table


def outside_text(
    algorithm: str,
    assumptions: Assumptions,
    schedulers: Sequence[str],
    robot_models: Sequence[RobotModel],
    non_rigid: float | None,
) -> str:
    """The line saying which of a hunt's draws are outside the algorithm's assumptions, each way
    once (`frames chirality`, `scheduler async`), '' when every draw is within them."""
    ways: dict[Outside, None] = {}
    for model in robot_models:
        for scheduler in schedulers:
            ways.update(dict.fromkeys(assumptions.outside(model, scheduler, non_rigid)))
    if not ways:
        return ""
    said = "; ".join(f"{o.what} {o.given} (it assumes {o.assumed})" for o in ways)
    return f"outside the assumptions of algorithm {algorithm}: {said}"


def print_summary(tally: Tally, out: TextIO, outside: str = "") -> None:
    """The counts of every kind found, the line saying which draws were outside the algorithm's
    assumptions (if any were), then the table of saved failures, to `out`."""
    tty = out.isatty()
    console = Console(file=out, width=None if tty else 200, no_color=not tty, highlight=False)
    found = kind_counts(tally.kinds) or "none"
    runs, refused = counted(tally.runs, "run"), counted(tally.refused, "start")
    console.print(f"{runs}, {refused} refused; failures found: {found}")
    if outside:
        console.print(outside)
    if tally.saved:
        console.print(summary_table(tally.saved))


__all__ = ["make_progress", "outside_text", "print_summary", "summary_table"]
