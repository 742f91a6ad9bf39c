"""The CSV schema of a sweep table: its columns, one run's row (its figures, the bound and ratio,
how to repeat it) and the text of the file, read back strictly. Pure: `deploy/sweep/pool.py`
writes and reads the file."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Final

import numpy as np

from fatswarm.deploy.sweep.grid import KEY_COLUMNS, MODEL_COLUMNS, Key, RunSpec, SweepInputError
from fatswarm.domain import figures
from fatswarm.domain.path import Points

ERROR: Final = "error"  # the status of a run that raised instead of ending (the `error` column)
NO_BOUND: Final = 1e-9  # a bound this small (nobody had to move) has no meaningful ratio

# The CSV schema. The key (configuration) columns (`grid.KEY_COLUMNS`) first: with the fatswarm
# version they say all a lock-step run depends on; then the run's figures (those of
# fatswarm.domain.figures with Place.CSV, in its order); `command` repeats the run.
CONTEXT_COLUMNS: Final = (
    "values",
    "round_cap",
    "error",
    "warning",
    "outside",
    "fatswarm_version",
    "command",
)
# The columns of the first sweep tables (fatswarm 0.1): every table has them. A table whose header
# has these and only others of `columns()` is one of ours, of an earlier fatswarm: it resumes with
# the columns it lacks filled in (`upgraded`).
FIRST_COLUMNS: Final = (
    "algorithm", "n", "start", "scheduler", "seed", "params", "max_rounds", "status", "rounds",
    "epochs", "looks", "moves", "collisions", "total_distance", "bound", "ratio", "wall_s",
    "values", "round_cap", "error", "warning", "fatswarm_version", "command",
)  # fmt: skip


def result_columns() -> tuple[str, ...]:
    """The figure columns, from the declaration (read now: a test may add a figure)."""
    return figures.names(figures.place(figures.Place.CSV))


def columns() -> tuple[str, ...]:
    """Every column of a table with the robot model's columns."""
    return KEY_COLUMNS + result_columns() + CONTEXT_COLUMNS


def plain_columns() -> tuple[str, ...]:
    """The columns of a table of the paper's robot model alone: `columns()` less MODEL_COLUMNS.
    A grid without a robot-model axis writes (and resumes) this table, as sweeps did before those
    axes; a row read from it has the MODEL_COLUMNS blank (the paper's model)."""
    return tuple(c for c in columns() if c not in MODEL_COLUMNS)


RESULT_COLUMNS: Final = result_columns()
COLUMNS: Final = columns()
PLAIN_COLUMNS: Final = plain_columns()
# The header of the tables written before the non_rigid, crash and time columns (fatswarm 0.1
# sweeps): they resume, those columns blank (rigid, no crash, a round model).
PRE_MODEL_COLUMNS: Final = FIRST_COLUMNS


class TableError(SweepInputError):
    """An existing CSV file that is not a sweep table of this schema."""


# -- one run's row ----------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class RunFigures:
    """What one run gave (a worker's answer): its outcome and cost, or the error it raised."""

    status: str  # a world.outcome.Status that ended the run, or ERROR
    rounds: int = 0  # committed rounds; ended Look-Compute-Move cycles under an async model
    epochs: int = 0
    looks: int = 0
    moves: int = 0
    collisions: int = 0
    total_distance: float = 0.0
    bound: float | None = None  # None: no scipy, or an error
    wall_s: float = 0.0
    values: str = ""  # values_text of every parameter
    round_cap: int | None = None
    error: str = ""  # what the run raised (status ERROR)
    warning: str = ""  # the first warning the run logged (a robot's compute failed...)
    outside: str = ""  # how the run is outside its algorithm's assumptions ('' if within)
    time: float | None = None  # async models: the virtual time the run ended; None: rounds
    # the run's figures that follow from the positions (fatswarm.domain.figures), by name
    derived: Mapping[str, figures.FigureValue] = field(default_factory=dict)

    @property
    def ratio(self) -> float | None:
        return distance_ratio(self.total_distance, self.bound)

    def value(self, name: str) -> figures.FigureValue:
        """The figure `name` of the declaration: a field of this class, else a derived one."""
        if name in self.derived or not hasattr(self, name):
            return self.derived.get(name)
        value: figures.FigureValue = getattr(self, name)
        return value


def assignment_bound(initial: Points, final: Points) -> float:
    """Least total straight-line distance from the (n, 2) `initial` centres to the (n, 2) `final`
    ones over every assignment of robots to final spots (one each): a lower bound on the distance
    of any run from `initial` that ends on `final`, whoever ends where. Needs scipy."""
    # scipy is an optional extra (fatswarm[sweep]; ImportError without it), ~0.3 s to import
    from scipy.optimize import linear_sum_assignment

    start = np.asarray(initial, dtype=np.float64)
    end = np.asarray(final, dtype=np.float64)
    if start.shape != end.shape or start.ndim != 2 or start.shape[1:] != (2,):
        raise ValueError(
            f"initial and final must both be (n, 2), got {start.shape} and {end.shape}"
        )
    cost = np.hypot(start[:, None, 0] - end[None, :, 0], start[:, None, 1] - end[None, :, 1])
    rows, cols = linear_sum_assignment(cost)
    return float(math.fsum(cost[rows, cols].tolist()))


def distance_ratio(total_distance: float, bound: float | None) -> float | None:
    """total_distance / bound, or None when there is no bound or it is ~0 (nobody had to move)."""
    if bound is None or bound < NO_BOUND:
        return None
    return total_distance / bound


def one_line(text: str) -> str:
    """`text` on one line (a CSV row is one line, so a torn one can be told and cut)."""
    return " ".join(text.split())


def make_row(spec: RunSpec, run: RunFigures, version: str) -> dict[str, str]:
    """The CSV row of one run: its key cells, its figures (blank where a run that raised has
    none) and how to repeat it."""
    failed = run.status == ERROR
    return {
        **spec.key_cells(),
        **{
            f.name: "" if failed and not f.kept_on_error else figures.cell(f, run.value(f.name))
            for f in figures.place(figures.Place.CSV)
        },
        "values": one_line(run.values),
        "round_cap": "" if run.round_cap is None else str(run.round_cap),
        "error": one_line(run.error),
        "warning": one_line(run.warning),
        "outside": one_line(run.outside),
        "fatswarm_version": version,
        "command": spec.command(),
    }


# -- the CSV text -----------------------------------------------------------------------------


def format_line(cells: Sequence[str]) -> str:
    """One CSV line (quoted where needed), ending in a newline."""
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerow(cells)
    return out.getvalue()


def header_line(columns: Sequence[str] | None = None) -> str:
    return format_line(COLUMNS if columns is None else columns)


def row_line(row: Mapping[str, str], columns: Sequence[str] | None = None) -> str:
    return format_line([row.get(column, "") for column in (columns or COLUMNS)])


def header_columns(line: str) -> tuple[str, ...] | None:
    """The columns of a header `line` of a sweep table of this fatswarm or an earlier one (every
    column of FIRST_COLUMNS, the others known to `columns()`, none twice); None for another."""
    try:
        (cells,) = list(csv.reader([line.rstrip("\r")]))
    except (csv.Error, ValueError):
        return None
    known = set(columns())
    if len(set(cells)) != len(cells) or not set(FIRST_COLUMNS) <= set(cells) <= known:
        return None
    return tuple(cells)


def table_columns(data: bytes, name: str, *, models: bool) -> tuple[str, ...]:
    """The columns of the table file `name` whose bytes are `data` once resumed: those of a grid
    with robot `models` (`columns()`) or without (`plain_columns()`); a table that has the model
    columns keeps them. An earlier table lacks some (`upgraded` fills them in); a new, empty or
    torn-header file gets them. Raises TableError for a file that is no sweep table."""
    every, plain = columns(), plain_columns()
    if b"\n" not in data:  # empty, or a header torn by a crash: (re)written
        if any(header_line(c).encode().startswith(data) for c in (every, plain)):
            return every if models else plain
        raise header_error(data.decode("utf-8", errors="replace"), name)
    first = data.split(b"\n", 1)[0].decode("utf-8", errors="replace")
    found = header_columns(first)
    if found is None:
        raise header_error(first, name)
    return every if models or set(MODEL_COLUMNS) & set(found) else plain


def upgraded(text: str, name: str, columns: Sequence[str]) -> str | None:
    """The table's `text` (whole lines) with the header of `columns` and each row filled in,
    when its header lacks some of them (a table of an earlier fatswarm, or of the paper's model
    alone when a grid adds model axes): the key and figure columns it lacks are blank (the
    paper's model; a figure not measured then). None when its header is that of `columns`."""
    if text.split("\n", 1)[0] == header_line(columns).rstrip("\n"):
        return None
    rows = parse_table(text, name)
    return header_line(columns) + "".join(row_line(row, columns) for row in rows)


def kept_length(data: bytes) -> int:
    """How much of a table file to keep: everything up to its last newline (a row torn by a
    crash mid-write has none)."""
    return data.rfind(b"\n") + 1


def parse_table(text: str, name: str) -> list[dict[str, str]]:
    """The rows of a table's text (whole lines only), each with every one of `columns()` (those
    its header lacks blank); raises TableError if its header is no sweep table's (this
    fatswarm's or an earlier one's: `header_columns`), or a row is malformed."""
    lines = text.split("\n")  # rows are single lines (one_line); not splitlines: \r, \x1c...
    if lines[-1] == "":
        lines.pop()
    if not lines:
        return []
    found = header_columns(lines[0])
    if found is None:
        raise header_error(lines[0], name)
    blank = dict.fromkeys(columns(), "")
    rows: list[dict[str, str]] = []
    for number, cells in enumerate(csv.reader(lines[1:]), start=2):
        if len(cells) != len(found):
            raise TableError(
                f"{name} line {number}: {len(cells)} cells where the header has "
                f"{len(found)}; mend or remove that line"
            )
        rows.append({**blank, **dict(zip(found, cells, strict=True))})
    return rows


def header_error(first_line: str, name: str) -> TableError:
    """Why the file `name`, whose first line is `first_line`, is not a table to append to."""
    return TableError(
        f"{name} has other columns than a fatswarm sweep table (another file, or "
        "another fatswarm version); name a new --out"
    )


def row_key(row: Mapping[str, str]) -> Key:
    return tuple(row[c] for c in KEY_COLUMNS)


__all__ = [
    "COLUMNS",
    "CONTEXT_COLUMNS",
    "ERROR",
    "FIRST_COLUMNS",
    "PLAIN_COLUMNS",
    "PRE_MODEL_COLUMNS",
    "RESULT_COLUMNS",
    "RunFigures",
    "TableError",
    "assignment_bound",
    "columns",
    "distance_ratio",
    "format_line",
    "header_columns",
    "header_error",
    "header_line",
    "kept_length",
    "make_row",
    "one_line",
    "parse_table",
    "plain_columns",
    "result_columns",
    "row_key",
    "row_line",
    "table_columns",
    "upgraded",
]
