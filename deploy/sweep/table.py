"""The CSV schema of a sweep table: its columns, one run's row (its figures, the bound and ratio,
how to repeat it) and the text of the file, read back strictly. Pure: `deploy/sweep/pool.py`
writes and reads the file."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np

from fatswarm.deploy.sweep.grid import KEY_COLUMNS, MODEL_COLUMNS, Key, RunSpec, SweepInputError
from fatswarm.domain.path import Points

ERROR: Final = "error"  # the status of a run that raised instead of ending (the `error` column)
NO_BOUND: Final = 1e-9  # a bound this small (nobody had to move) has no meaningful ratio

# The CSV schema. The key (configuration) columns (`grid.KEY_COLUMNS`) first: with the fatswarm
# version they say all a lock-step run depends on; `command` repeats the run.
RESULT_COLUMNS: Final = (
    "status",
    "rounds",
    "time",
    "epochs",
    "looks",
    "moves",
    "collisions",
    "total_distance",
    "bound",
    "ratio",
    "wall_s",
)
CONTEXT_COLUMNS: Final = (
    "values",
    "round_cap",
    "error",
    "warning",
    "fatswarm_version",
    "command",
)
COLUMNS: Final = KEY_COLUMNS + RESULT_COLUMNS + CONTEXT_COLUMNS
# The columns of a table of the paper's robot model alone: COLUMNS less the MODEL_COLUMNS. A grid
# without a robot-model axis writes (and resumes) this table, as sweeps did before those axes; a
# row read from it has the MODEL_COLUMNS blank (the paper's model).
PLAIN_COLUMNS: Final = tuple(c for c in COLUMNS if c not in MODEL_COLUMNS)
# The header of the tables written before the non_rigid, crash and time columns (fatswarm 0.1
# sweeps): refused with a line of its own, as appending rows of another shape would mix schemas.
PRE_MODEL_COLUMNS: Final = tuple(
    c for c in PLAIN_COLUMNS if c not in ("non_rigid", "crash", "time")
)
SCHEMAS: Final = (COLUMNS, PLAIN_COLUMNS)  # the tables a sweep appends to


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
    time: float | None = None  # async models: the virtual time the run ended; None: rounds


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


def make_row(spec: RunSpec, figures: RunFigures, version: str) -> dict[str, str]:
    """The CSV row of one run: its key cells, its figures and how to repeat it."""
    f = figures
    ratio = distance_ratio(f.total_distance, f.bound)
    failed = f.status == ERROR
    return {
        **spec.key_cells(),
        "status": f.status,
        "rounds": "" if failed else str(f.rounds),
        "time": "" if failed or f.time is None else f"{f.time:.6f}",
        "epochs": "" if failed else str(f.epochs),
        "looks": "" if failed else str(f.looks),
        "moves": "" if failed else str(f.moves),
        "collisions": "" if failed else str(f.collisions),
        "total_distance": "" if failed else f"{f.total_distance:.6f}",
        "bound": "" if f.bound is None else f"{f.bound:.6f}",
        "ratio": "" if ratio is None else f"{ratio:.6f}",
        "wall_s": f"{f.wall_s:.3f}",
        "values": one_line(f.values),
        "round_cap": "" if f.round_cap is None else str(f.round_cap),
        "error": one_line(f.error),
        "warning": one_line(f.warning),
        "fatswarm_version": version,
        "command": spec.command(),
    }


# -- the CSV text -----------------------------------------------------------------------------


def format_line(cells: Sequence[str]) -> str:
    """One CSV line (quoted where needed), ending in a newline."""
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerow(cells)
    return out.getvalue()


def header_line(columns: Sequence[str] = COLUMNS) -> str:
    return format_line(columns)


def row_line(row: Mapping[str, str], columns: Sequence[str] = COLUMNS) -> str:
    return format_line([row.get(column, "") for column in columns])


def table_columns(data: bytes, name: str, *, models: bool) -> tuple[str, ...]:
    """The columns (SCHEMAS) of the table file `name` whose bytes are `data`: its header's, or,
    for a new, empty or torn-header file, those of a grid with robot `models` (COLUMNS) or
    without (PLAIN_COLUMNS). Raises TableError for a file that is no sweep table, or a table
    without the model columns when `models` are asked for."""
    for columns in SCHEMAS:
        if data.startswith(header_line(columns).encode()):
            if models and columns is PLAIN_COLUMNS:
                raise TableError(
                    f"{name} has no robot-model columns (a sweep of the paper's model only); "
                    "a grid with --visibility, --sight, --lights, --frames or --frame-change "
                    "needs a new --out"
                )
            return columns
    if any(header_line(columns).encode().startswith(data) for columns in SCHEMAS):
        return COLUMNS if models else PLAIN_COLUMNS  # a header is (re)written
    first = data.split(b"\n", 1)[0].decode("utf-8", errors="replace")
    raise header_error(first, name)


def kept_length(data: bytes) -> int:
    """How much of a table file to keep: everything up to its last newline (a row torn by a
    crash mid-write has none)."""
    return data.rfind(b"\n") + 1


def parse_table(text: str, name: str) -> list[dict[str, str]]:
    """The rows of a table's text (whole lines only), each with every one of COLUMNS (those its
    schema lacks blank); raises TableError if its header is not one of SCHEMAS, or a row is
    malformed."""
    lines = text.split("\n")  # rows are single lines (one_line); not splitlines: \r, \x1c...
    if lines[-1] == "":
        lines.pop()
    if not lines:
        return []
    columns = next((c for c in SCHEMAS if lines[0] == header_line(c).rstrip("\n")), None)
    if columns is None:
        raise header_error(lines[0], name)
    blank = dict.fromkeys(COLUMNS, "")
    rows: list[dict[str, str]] = []
    for number, cells in enumerate(csv.reader(lines[1:]), start=2):
        if len(cells) != len(columns):
            raise TableError(
                f"{name} line {number}: {len(cells)} cells where the header has "
                f"{len(columns)}; mend or remove that line"
            )
        rows.append({**blank, **dict(zip(columns, cells, strict=True))})
    return rows


def header_error(first_line: str, name: str) -> TableError:
    """Why the file `name`, whose first line is `first_line`, is not a table to append to: a
    sweep table of an earlier fatswarm (no non_rigid, crash and time columns) is told apart, as
    its rows would read as rigid and crash-free but another schema cannot be appended to."""
    if first_line.rstrip("\r") == format_line(PRE_MODEL_COLUMNS).rstrip("\n"):
        return TableError(
            f"{name} is a sweep table of an earlier fatswarm (no non_rigid, "
            "crash and time columns); name a new --out"
        )
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
    "PLAIN_COLUMNS",
    "PRE_MODEL_COLUMNS",
    "RESULT_COLUMNS",
    "RunFigures",
    "TableError",
    "assignment_bound",
    "distance_ratio",
    "format_line",
    "header_error",
    "header_line",
    "kept_length",
    "make_row",
    "one_line",
    "parse_table",
    "row_key",
    "row_line",
    "table_columns",
]
