"""The pure parts of `fatswarm sweep`: the grid and its runs, the CSV schema and row keys, the
optimal-assignment bound and the summary of rows. No I/O: the pool, the CSV file, the progress bar
and the figures are `deploy/sweep_run.py` and `deploy/sweep_plot.py`.
"""

from __future__ import annotations

import csv
import io
import itertools
import math
import re
import shlex
import statistics
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from fatswarm.agent.path import Points
from fatswarm.agent.registry import DEFAULT as DEFAULT_ALGORITHM
from fatswarm.agent.seam import Algorithm, ParamValue, parse_assignments, resolve_values
from fatswarm.world.outcome import Status

ERROR: Final = "error"  # the status of a run that raised instead of ending (the `error` column)
MAX_RUNS: Final = 1_000_000  # a larger grid is a typo (`--seeds 0..10000000`), not a sweep
RANGE: Final = re.compile(r"(\d+)\.\.(\d+)(?::(\d+))?")  # 4..16 or 4..16:4 (inclusive)
NO_BOUND: Final = 1e-9  # a bound this small (nobody had to move) has no meaningful ratio

ParamText = tuple[tuple[str, str], ...]  # (name, canonical value text), sorted by name
Key = tuple[str, ...]  # a row's KEY_COLUMNS values, as written in the CSV

# The CSV schema. The key (configuration) columns first: with the fatswarm version they say all a
# lock-step run depends on; `command` repeats the run.
KEY_COLUMNS: Final = ("algorithm", "n", "start", "scheduler", "seed", "params", "max_rounds")
RESULT_COLUMNS: Final = (
    "status", "rounds", "epochs", "looks", "moves", "collisions", "total_distance", "bound",
    "ratio", "wall_s",
)
CONTEXT_COLUMNS: Final = (
    "values", "round_cap", "error", "warning", "fatswarm_version", "command",
)
COLUMNS: Final = KEY_COLUMNS + RESULT_COLUMNS + CONTEXT_COLUMNS


class SweepInputError(ValueError):
    """A grid argument or an output the sweep cannot use (the message says what to fix)."""


class TableError(SweepInputError):
    """An existing CSV file that is not a sweep table of this schema."""


# -- the grid ---------------------------------------------------------------------------------


def split_values(texts: Iterable[str]) -> tuple[str, ...]:
    """Repeated flags and comma lists as one tuple: order kept, repeats and blanks dropped."""
    out: dict[str, None] = {}
    for text in texts:
        for item in text.split(","):
            if item.strip():
                out.setdefault(item.strip(), None)
    return tuple(out)


def parse_ints(texts: Iterable[str], flag: str, *, least: int) -> tuple[int, ...]:
    """`4,8,16`, `4..16` or `4..16:4` (inclusive ranges, a step after ':'), repeatable: whole
    numbers >= `least`, in the order given, without repeats; raises SweepInputError."""
    out: dict[int, None] = {}
    for item in split_values(texts):
        match = RANGE.fullmatch(item)
        if match is not None:
            lo, hi, step = int(match[1]), int(match[2]), int(match[3] or 1)
            if lo > hi or step < 1:
                raise SweepInputError(f"{flag} {item}: a range is LOW..HIGH or LOW..HIGH:STEP "
                                      "with LOW <= HIGH and STEP >= 1")
            if (hi - lo) // step >= MAX_RUNS:
                raise SweepInputError(f"{flag} {item}: more than {MAX_RUNS} values")
            values: Iterable[int] = range(lo, hi + 1, step)
        else:
            try:
                values = (int(item),)
            except ValueError:
                raise SweepInputError(f"{flag} takes whole numbers, LOW..HIGH ranges or comma "
                                      f"lists of them, got {item!r}") from None
        for value in values:
            if value < least:
                raise SweepInputError(f"{flag} values must be >= {least}, got {value}")
            out.setdefault(value, None)
    if not out:
        raise SweepInputError(f"{flag} needs at least one value")
    return tuple(out)


def parse_seeds(texts: Iterable[str]) -> tuple[int, ...]:
    """`--seeds`: one bare number K is a count (seeds 0..K-1); else seeds as `parse_ints` reads
    them (`0..19`, `3,7`; one seed S is `S..S`)."""
    items = split_values(texts)
    if len(items) == 1 and items[0].isdigit():
        count = int(items[0])
        if not 1 <= count <= MAX_RUNS:
            raise SweepInputError(f"--seeds COUNT must be 1..{MAX_RUNS}, got {count}")
        return tuple(range(count))
    return parse_ints(items, "--seeds", least=0)


def sweep_schedulers() -> tuple[str, ...]:
    """The scheduler (or model) names a sweep takes: those of `coordinator.schedule.NAMES` that
    need no file (all but scripted, which replays one given schedule)."""
    from fatswarm.coordinator.schedule import NAMES, ScheduleError, make_scheduler

    names = []
    for name in NAMES:
        try:
            make_scheduler(name, 2, 0)
        except ScheduleError:
            continue
        names.append(name)
    return tuple(names)


def value_text(value: ParamValue) -> str:
    """A parameter value as `--param NAME=TEXT` gives it back exactly (floats by repr)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def params_text(algorithm: Algorithm[Any], assignments: Sequence[str]) -> ParamText:
    """The `--param NAME=VALUE` texts as `algorithm` types them, canonical (so `a=4` and `a=4.0`
    are one key); raises AlgorithmParamsError for a parameter it does not have or a bad value."""
    given = parse_assignments(list(assignments))
    values = resolve_values(algorithm, given)
    return tuple(sorted((name, value_text(values[name])) for name in given))


def values_text(values: Mapping[str, ParamValue]) -> str:
    """Every parameter of a run (defaults included) as `a=4.0;b=true`, for the `values` column."""
    return ";".join(f"{name}={value_text(v)}" for name, v in sorted(values.items()))


@dataclass(frozen=True, slots=True)
class RunSpec:
    """One run of the grid: everything a lock-step run depends on (with the fatswarm version)."""

    algorithm: str  # a registered name, module:attribute or path/to/file.py:attribute
    n: int
    start: str  # a random start kind (world.starts.KINDS)
    scheduler: str  # coordinator.schedule.NAMES: a scheduler or, later, a weaker model
    seed: int  # the start, the private frames and the scheduler's draws
    params: ParamText = ()  # the parameters asked for; the others take their defaults
    max_rounds: int | None = None  # None: the scheduler's default cap

    def key(self) -> Key:
        """The row's KEY_COLUMNS, as the CSV holds them: equal keys are the same run."""
        cells = self.key_cells()
        return tuple(cells[c] for c in KEY_COLUMNS)

    def key_cells(self) -> dict[str, str]:
        return {
            "algorithm": self.algorithm,
            "n": str(self.n),
            "start": self.start,
            "scheduler": self.scheduler,
            "seed": str(self.seed),
            "params": ";".join(f"{k}={v}" for k, v in self.params),
            "max_rounds": "" if self.max_rounds is None else str(self.max_rounds),
        }

    def command(self) -> str:
        """The `fatswarm run --lockstep` command that repeats this run (shell-quoted)."""
        argv = ["fatswarm", "run", "--lockstep", "-n", str(self.n), "--seed", str(self.seed),
                "--start", self.start, "--scheduler", self.scheduler]
        if self.algorithm != DEFAULT_ALGORITHM:
            argv += ["--algorithm", self.algorithm]
        for name, text in self.params:
            argv += ["--param", f"{name}={text}"]
        if self.max_rounds is not None:
            argv += ["--max-rounds", str(self.max_rounds)]
        return shlex.join(argv)


@dataclass(frozen=True, slots=True)
class Grid:
    """algorithms x starts x schedulers x sizes x seeds, each algorithm with its parameters."""

    algorithms: tuple[tuple[str, ParamText], ...]  # (reference, canonical --param texts)
    sizes: tuple[int, ...]
    starts: tuple[str, ...]
    schedulers: tuple[str, ...]
    seeds: tuple[int, ...]
    max_rounds: int | None = None

    def __post_init__(self) -> None:
        if self.size > MAX_RUNS:
            raise SweepInputError(f"the grid has {self.size} runs, more than {MAX_RUNS}; "
                                  "sweep it in parts")

    @property
    def size(self) -> int:
        return math.prod(len(axis) for axis in (self.algorithms, self.sizes, self.starts,
                                                self.schedulers, self.seeds))

    def runs(self) -> list[RunSpec]:
        """Every run, seed by seed: a sweep stopped early has every other cell equally deep."""
        return [
            RunSpec(algorithm, n, start, scheduler, seed, params, self.max_rounds)
            for seed, (algorithm, params), start, scheduler, n in itertools.product(
                self.seeds, self.algorithms, self.starts, self.schedulers, self.sizes)
        ]


# -- one run's row ----------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class RunFigures:
    """What one run gave (a worker's answer): its outcome and cost, or the error it raised."""

    status: str  # a world.outcome.Status that ended the run, or ERROR
    rounds: int = 0
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


def assignment_bound(initial: Points, final: Points) -> float:
    """Least total straight-line distance from the (n, 2) `initial` centres to the (n, 2) `final`
    ones over every assignment of robots to final spots (one each): a lower bound on the distance
    of any run from `initial` that ends on `final`, whoever ends where. Needs scipy."""
    from scipy.optimize import linear_sum_assignment

    start = np.asarray(initial, dtype=np.float64)
    end = np.asarray(final, dtype=np.float64)
    if start.shape != end.shape or start.ndim != 2 or start.shape[1:] != (2,):
        raise ValueError(f"initial and final must both be (n, 2), got {start.shape} and "
                         f"{end.shape}")
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


def header_line() -> str:
    return format_line(COLUMNS)


def row_line(row: Mapping[str, str]) -> str:
    return format_line([row.get(column, "") for column in COLUMNS])


def kept_length(data: bytes) -> int:
    """How much of a table file to keep: everything up to its last newline (a row torn by a
    crash mid-write has none)."""
    return data.rfind(b"\n") + 1


def parse_table(text: str, name: str) -> list[dict[str, str]]:
    """The rows of a table's text (whole lines only); raises TableError if its header is not this
    schema's, or a row is malformed."""
    lines = text.split("\n")  # rows are single lines (one_line); not splitlines: \r, \x1c...
    if lines[-1] == "":
        lines.pop()
    if not lines:
        return []
    if lines[0] != header_line().rstrip("\n"):
        raise TableError(f"{name} has other columns than a fatswarm sweep table (another file, "
                         "or another fatswarm version); name a new --out")
    rows: list[dict[str, str]] = []
    for number, cells in enumerate(csv.reader(lines[1:]), start=2):
        if len(cells) != len(COLUMNS):
            raise TableError(f"{name} line {number}: {len(cells)} cells where the header has "
                             f"{len(COLUMNS)}; mend or remove that line")
        rows.append(dict(zip(COLUMNS, cells, strict=True)))
    return rows


def row_key(row: Mapping[str, str]) -> Key:
    return tuple(row[c] for c in KEY_COLUMNS)


# -- the summary ------------------------------------------------------------------------------

Quartiles = tuple[float, float, float]  # (25th percentile, median, 75th percentile)


@dataclass(frozen=True, slots=True)
class Cell:
    """The runs of one (algorithm, start, scheduler, n), summed up."""

    algorithm: str
    start: str
    scheduler: str
    n: int
    runs: int
    formed: int
    clean: int  # formed with no collision
    collided: int  # runs with at least one collision
    stalled: int
    capped: int  # stopped at the round cap
    errors: int
    rounds: Quartiles | None  # of the formed runs
    ratio: Quartiles | None  # distance / bound, of the formed runs that have one


def quartiles(values: Sequence[float]) -> Quartiles | None:
    """(q1, median, q3) of `values`, None if empty."""
    if not values:
        return None
    if len(values) == 1:
        return (values[0], values[0], values[0])
    q1, q2, q3 = statistics.quantiles(values, n=4, method="inclusive")
    return (q1, q2, q3)


def summarize(rows: Iterable[Mapping[str, str]], grid: Grid) -> list[Cell]:
    """One Cell per (algorithm, start, scheduler, n) of `grid` with rows, in the grid's order."""
    groups: dict[tuple[str, str, str, int], list[Mapping[str, str]]] = {}
    for row in rows:
        groups.setdefault((row["algorithm"], row["start"], row["scheduler"], int(row["n"])),
                          []).append(row)
    cells = []
    for (algorithm, _), start, scheduler, n in itertools.product(
            grid.algorithms, grid.starts, grid.schedulers, grid.sizes):
        group = groups.get((algorithm, start, scheduler, n))
        if group:
            cells.append(_cell(algorithm, start, scheduler, n, group))
    return cells


def _cell(algorithm: str, start: str, scheduler: str, n: int,
          group: Sequence[Mapping[str, str]]) -> Cell:
    status = [r["status"] for r in group]
    formed = [r for r in group if r["status"] == Status.FORMED]
    return Cell(
        algorithm, start, scheduler, n,
        runs=len(group),
        formed=len(formed),
        clean=sum(1 for r in formed if r["collisions"] == "0"),
        collided=sum(1 for r in group if r["collisions"] not in ("", "0")),
        stalled=status.count(Status.STALLED),
        capped=status.count(Status.MAX_ROUNDS),
        errors=status.count(ERROR),
        rounds=quartiles([float(r["rounds"]) for r in formed]),
        ratio=quartiles([float(r["ratio"]) for r in formed if r["ratio"]]),
    )


def cell_label(cell: Cell, cells: Sequence[Cell]) -> str:
    """The scheduler, with the algorithm and start kind when the cells have more than one."""
    parts = [cell.scheduler]
    if len({c.start for c in cells}) > 1:
        parts.insert(0, cell.start)
    if len({c.algorithm for c in cells}) > 1:
        parts.insert(0, cell.algorithm)
    return " ".join(parts)


def success_rates(cells: Sequence[Cell]) -> list[tuple[str, int, int, int]]:
    """(label, runs, formed, formed collision-free) per label of `cell_label`, over every n."""
    totals: dict[str, list[int]] = {}
    for cell in cells:
        total = totals.setdefault(cell_label(cell, cells), [0, 0, 0])
        total[0] += cell.runs
        total[1] += cell.formed
        total[2] += cell.clean
    return [(label, runs, formed, clean) for label, (runs, formed, clean) in totals.items()]


def curves(cells: Sequence[Cell], figure: str) -> dict[str, list[tuple[int, Quartiles]]]:
    """Per label of `cell_label`: (n, quartiles of `figure`) for each n with formed runs;
    `figure` is "rounds" or "ratio"."""
    out: dict[str, list[tuple[int, Quartiles]]] = {}
    for cell in cells:
        line = out.setdefault(cell_label(cell, cells), [])
        q = cell.rounds if figure == "rounds" else cell.ratio
        if q is not None:
            line.append((cell.n, q))
    return {label: sorted(points) for label, points in out.items()}


def is_clean(row: Mapping[str, str]) -> bool:
    """Whether a row's run formed with no collision (what the paper guarantees)."""
    return row["status"] == Status.FORMED and row["collisions"] == "0"


__all__ = [
    "COLUMNS",
    "ERROR",
    "KEY_COLUMNS",
    "Cell",
    "Grid",
    "RunFigures",
    "RunSpec",
    "SweepInputError",
    "TableError",
    "assignment_bound",
    "cell_label",
    "curves",
    "distance_ratio",
    "is_clean",
    "kept_length",
    "make_row",
    "params_text",
    "parse_ints",
    "parse_seeds",
    "parse_table",
    "quartiles",
    "row_key",
    "row_line",
    "split_values",
    "success_rates",
    "summarize",
    "sweep_schedulers",
    "value_text",
    "values_text",
]
