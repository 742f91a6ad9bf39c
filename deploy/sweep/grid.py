"""The pure parts of `fatswarm sweep`: the grid and its runs, the CSV schema and row keys, the
optimal-assignment bound, the summary of rows and its Markdown table. No I/O: the pool, the CSV
file, the progress bar and the figures are `deploy/sweep/pool.py` and `deploy/sweep/figures.py`.
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

from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Points
from fatswarm.domain.registry import DEFAULT as DEFAULT_ALGORITHM
from fatswarm.domain.seam import Algorithm, ParamValue, parse_assignments, resolve_values

ERROR: Final = "error"  # the status of a run that raised instead of ending (the `error` column)
MAX_RUNS: Final = 1_000_000  # a larger grid is a typo (`--seeds 0..10000000`), not a sweep
RANGE: Final = re.compile(r"(\d+)\.\.(\d+)(?::(\d+))?")  # 4..16 or 4..16:4 (inclusive)
NO_BOUND: Final = 1e-9  # a bound this small (nobody had to move) has no meaningful ratio

ParamText = tuple[tuple[str, str], ...]  # (name, canonical value text), sorted by name
Key = tuple[str, ...]  # a row's KEY_COLUMNS values, as written in the CSV

# The CSV schema. The key (configuration) columns first: with the fatswarm version they say all a
# lock-step run depends on; `command` repeats the run.
KEY_COLUMNS: Final = (
    "algorithm",
    "n",
    "start",
    "scheduler",
    "seed",
    "params",
    "max_rounds",
    "non_rigid",
    "crash",
)
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
# The header of the tables written before the non_rigid, crash and time columns (fatswarm 0.1
# sweeps): refused with a line of its own, as appending rows of another shape would mix schemas.
PRE_MODEL_COLUMNS: Final = tuple(c for c in COLUMNS if c not in ("non_rigid", "crash", "time"))
RIGID: Final = "rigid"  # --non-rigid's word for rigid moves (the default)
NO_CRASH: Final = ("0", "none")  # --crash's words for no crash (the default)


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
                raise SweepInputError(
                    f"{flag} {item}: a range is LOW..HIGH or LOW..HIGH:STEP "
                    "with LOW <= HIGH and STEP >= 1"
                )
            if (hi - lo) // step >= MAX_RUNS:
                raise SweepInputError(f"{flag} {item}: more than {MAX_RUNS} values")
            values: Iterable[int] = range(lo, hi + 1, step)
        else:
            try:
                values = (int(item),)
            except ValueError:
                raise SweepInputError(
                    f"{flag} takes whole numbers, LOW..HIGH ranges or comma "
                    f"lists of them, got {item!r}"
                ) from None
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


def parse_non_rigid(texts: Iterable[str]) -> tuple[float | None, ...]:
    """`--non-rigid`: deltas (finite distances > 0, robot radii) and/or `rigid` (None), in the
    order given, without repeats (`1` and `1.0` are one); default (None,), rigid moves only."""
    out: dict[float | None, None] = {}
    for item in split_values(texts):
        if item.lower() == RIGID:
            out.setdefault(None, None)
            continue
        try:
            delta = float(item)
        except ValueError:
            delta = math.nan
        if not (math.isfinite(delta) and delta > 0):
            raise SweepInputError(
                f"--non-rigid takes distances > 0 (robot radii) or {RIGID}, got {item!r}"
            )
        out.setdefault(delta, None)
    return tuple(out) or (None,)


def parse_crash(texts: Iterable[str]) -> tuple[int | None, ...]:
    """`--crash`: crash counts f >= 1 (lists and ranges as `parse_ints`) and/or `0`/`none` (None,
    no crash), in the order given, without repeats; default (None,), no crash."""
    out: dict[int | None, None] = {}
    for item in split_values(texts):
        if item.lower() in NO_CRASH:
            out.setdefault(None, None)
            continue
        for f in parse_ints([item], "--crash", least=0):
            out.setdefault(f or None, None)  # 0 inside a range is no crash too
    return tuple(out) or (None,)


def model_label(scheduler: str, non_rigid: float | None, crash: int | None) -> str:
    """The model a run ran under, in one word: the scheduler, `+nrDELTA` for non-rigid moves and
    `+crashF` for crash faults (`fsync`, `ssync+nr0.1`, `async+crash2`, `fsync+nr1+crash1`)."""
    label = scheduler
    if non_rigid is not None:
        label += f"+nr{non_rigid:g}"
    if crash is not None:
        label += f"+crash{crash}"
    return label


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
    non_rigid: float | None = None  # the non-rigid adversary's delta; None: rigid moves
    crash: int | None = None  # f robots crashed for good (0 < f < n); None: no crash

    @property
    def model(self) -> str:
        """The model label (`model_label`): the scheduler, non-rigid moves and crash faults."""
        return model_label(self.scheduler, self.non_rigid, self.crash)

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
            "non_rigid": non_rigid_cell(self.non_rigid),
            "crash": crash_cell(self.crash),
        }

    def command(self) -> str:
        """The `fatswarm run --lockstep` command that repeats this run (shell-quoted)."""
        argv = [
            "fatswarm",
            "run",
            "--lockstep",
            "-n",
            str(self.n),
            "--seed",
            str(self.seed),
            "--start",
            self.start,
            "--scheduler",
            self.scheduler,
        ]
        if self.algorithm != DEFAULT_ALGORITHM:
            argv += ["--algorithm", self.algorithm]
        for name, text in self.params:
            argv += ["--param", f"{name}={text}"]
        if self.max_rounds is not None:
            argv += ["--max-rounds", str(self.max_rounds)]
        if self.non_rigid is not None:
            argv += ["--non-rigid", value_text(self.non_rigid)]  # repr: reads back exactly
        if self.crash is not None:
            argv += ["--crash", str(self.crash)]
        return shlex.join(argv)


@dataclass(frozen=True, slots=True)
class Grid:
    """algorithms x starts x schedulers x non-rigid deltas x crash counts x sizes x seeds, each
    algorithm with its parameters. A crash count f needs f < n robots: the (n, f) cells with
    f >= n are left out of the grid (`left_out` counts their runs), not refused, so that one
    `-n 3..12 --crash 0,1,2` asks for every cell that exists."""

    algorithms: tuple[tuple[str, ParamText], ...]  # (reference, canonical --param texts)
    sizes: tuple[int, ...]
    starts: tuple[str, ...]
    schedulers: tuple[str, ...]
    seeds: tuple[int, ...]
    max_rounds: int | None = None
    non_rigids: tuple[float | None, ...] = (None,)  # None: rigid moves
    crashes: tuple[int | None, ...] = (None,)  # None: no crash

    def __post_init__(self) -> None:
        if self.size > MAX_RUNS:
            raise SweepInputError(
                f"the grid has {self.size} runs, more than {MAX_RUNS}; sweep it in parts"
            )
        if self.size == 0 and self.left_out:
            raise SweepInputError(
                "every --crash F is >= every -n, so the grid has no run "
                "(F of n robots crash: 0 < F < n); ask for fewer crashes or "
                "more robots"
            )

    @property
    def size(self) -> int:
        """The runs of the grid (the (n, f) cells with f >= n left out)."""
        return self._others() * len(self._pairs())

    @property
    def left_out(self) -> int:
        """The runs left out of the grid because their crash count f is >= their n."""
        return self._others() * len(self.sizes) * len(self.crashes) - self.size

    def _others(self) -> int:
        return math.prod(
            len(axis)
            for axis in (self.algorithms, self.starts, self.schedulers, self.non_rigids, self.seeds)
        )

    def _pairs(self) -> list[tuple[int | None, int]]:
        """The (crash, n) cells that exist: no crash, or fewer crashes than robots."""
        return [(f, n) for f in self.crashes for n in self.sizes if f is None or f < n]

    def runs(self) -> list[RunSpec]:
        """Every run, seed by seed: a sweep stopped early has every other cell equally deep."""
        return [
            RunSpec(algorithm, n, start, scheduler, seed, params, self.max_rounds, delta, f)
            for seed, (algorithm, params), start, scheduler, delta, (f, n) in itertools.product(
                self.seeds,
                self.algorithms,
                self.starts,
                self.schedulers,
                self.non_rigids,
                self._pairs(),
            )
        ]


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
        raise header_error(lines[0], name)
    rows: list[dict[str, str]] = []
    for number, cells in enumerate(csv.reader(lines[1:]), start=2):
        if len(cells) != len(COLUMNS):
            raise TableError(
                f"{name} line {number}: {len(cells)} cells where the header has "
                f"{len(COLUMNS)}; mend or remove that line"
            )
        rows.append(dict(zip(COLUMNS, cells, strict=True)))
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


# -- the summary ------------------------------------------------------------------------------

Quartiles = tuple[float, float, float]  # (25th percentile, median, 75th percentile)
# What a summary groups rows by: (algorithm, start, scheduler, non_rigid, crash, n) as the CSV
# writes them; n is None in a group over every n (the Markdown table).
GroupKey = tuple[str, str, str, str, str, int | None]


@dataclass(frozen=True, slots=True)
class Cell:
    """The runs of one (algorithm, start, scheduler, non-rigid delta, crash count, n), summed up;
    `n` is None for a cell over every n (whose sizes are `sizes`)."""

    algorithm: str
    start: str
    scheduler: str
    n: int | None
    runs: int
    formed: int
    clean: int  # formed with no collision
    collided: int  # runs with at least one collision
    stalled: int
    capped: int  # stopped at the round cap
    errors: int
    rounds: Quartiles | None  # of the formed runs
    ratio: Quartiles | None  # distance / bound, of the formed runs that have one
    non_rigid: str = ""  # the non_rigid column: the delta, "" for rigid moves
    crash: str = ""  # the crash column: f, "" for no crash
    time: Quartiles | None = None  # virtual time of the formed runs (async models only)
    sizes: tuple[int, ...] = ()  # the n of its runs, in the grid's order

    @property
    def model(self) -> str:
        """The model label (`model_label`) of the cell's runs."""
        return model_label(
            self.scheduler,
            float(self.non_rigid) if self.non_rigid else None,
            int(self.crash) if self.crash else None,
        )


def quartiles(values: Sequence[float]) -> Quartiles | None:
    """(q1, median, q3) of `values`, None if empty."""
    if not values:
        return None
    if len(values) == 1:
        return (values[0], values[0], values[0])
    q1, q2, q3 = statistics.quantiles(values, n=4, method="inclusive")
    return (q1, q2, q3)


def group_key(row: Mapping[str, str], *, by_n: bool) -> GroupKey:
    """The summary group of a row: its configuration less the seed, the parameters and the cap
    (one grid has one of each), and less n when not `by_n`. The one definition of a group, for
    the terminal summary (`by_n`), the Markdown table and the figures."""
    return (
        row["algorithm"],
        row["start"],
        row["scheduler"],
        row["non_rigid"],
        row["crash"],
        int(row["n"]) if by_n else None,
    )


def summarize(rows: Iterable[Mapping[str, str]], grid: Grid, *, by_n: bool = True) -> list[Cell]:
    """One Cell per (algorithm, start, scheduler, non-rigid delta, crash count, n) of `grid` with
    rows, in the grid's order; with `by_n` false, one per the same less n, over every n."""
    groups: dict[GroupKey, list[Mapping[str, str]]] = {}
    for row in rows:
        groups.setdefault(group_key(row, by_n=by_n), []).append(row)
    sizes: tuple[int | None, ...] = grid.sizes if by_n else (None,)
    cells = []
    for (algorithm, _), start, scheduler, delta, f, n in itertools.product(
        grid.algorithms, grid.starts, grid.schedulers, grid.non_rigids, grid.crashes, sizes
    ):
        key = (algorithm, start, scheduler, non_rigid_cell(delta), crash_cell(f), n)
        group = groups.get(key)
        if group:
            ns = {int(r["n"]) for r in group}
            cells.append(_cell(key, group, tuple(m for m in grid.sizes if m in ns)))
    return cells


def non_rigid_cell(delta: float | None) -> str:
    """The non_rigid column of a run: the delta as `--non-rigid` takes it back, "" if rigid."""
    return "" if delta is None else value_text(delta)


def crash_cell(f: int | None) -> str:
    """The crash column of a run: f, "" for no crash."""
    return "" if f is None else str(f)


def _cell(key: GroupKey, group: Sequence[Mapping[str, str]], sizes: tuple[int, ...]) -> Cell:
    algorithm, start, scheduler, non_rigid, crash, n = key
    status = [r["status"] for r in group]
    formed = [r for r in group if r["status"] == Status.FORMED]
    return Cell(
        algorithm,
        start,
        scheduler,
        n,
        runs=len(group),
        formed=len(formed),
        clean=sum(1 for r in formed if r["collisions"] == "0"),
        collided=sum(1 for r in group if r["collisions"] not in ("", "0")),
        stalled=status.count(Status.STALLED),
        capped=status.count(Status.MAX_ROUNDS),
        errors=status.count(ERROR),
        rounds=quartiles([float(r["rounds"]) for r in formed]),
        ratio=quartiles([float(r["ratio"]) for r in formed if r["ratio"]]),
        non_rigid=non_rigid,
        crash=crash,
        time=quartiles([float(r["time"]) for r in formed if r["time"]]),
        sizes=sizes,
    )


def cell_label(cell: Cell, cells: Sequence[Cell]) -> str:
    """The model label (`model_label`), with the algorithm and start kind when the cells have
    more than one: a series of the figures."""
    parts = [cell.model]
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
    `figure` is "rounds" or "ratio". Cells over every n (n None) have no point."""
    out: dict[str, list[tuple[int, Quartiles]]] = {}
    for cell in cells:
        line = out.setdefault(cell_label(cell, cells), [])
        q = cell.rounds if figure == "rounds" else cell.ratio
        if q is not None and cell.n is not None:
            line.append((cell.n, q))
    return {label: sorted(points) for label, points in out.items()}


def markdown_table(cells: Sequence[Cell]) -> str:
    """The summary as a Markdown table (`--summary-md`), a line per cell of `summarize(...,
    by_n=False)`: the configuration (a start column only when there are several), the sizes, the
    counts of runs, formed, collided (with at least one collision), stalled, max_rounds (stopped
    at the round cap) and errors, then the median rounds (cycles under an async model) and the
    median virtual time (async models; `-` for round models) of the formed runs. Text only, so
    that a results page can include it as it is."""
    several_start = len({c.start for c in cells}) > 1
    head = [
        "algorithm",
        *(["start"] if several_start else []),
        "scheduler",
        "non-rigid",
        "crash",
        "n",
        "runs",
        "formed",
        "collided",
        "stalled",
        "max_rounds",
        "errors",
        "median rounds",
        "median time",
    ]
    lines = [
        "| " + " | ".join(head) + " |",
        "|" + "|".join("---" if i < head.index("n") else "--:" for i in range(len(head))) + "|",
    ]
    for c in cells:
        row = [
            c.algorithm,
            *([c.start] if several_start else []),
            c.scheduler,
            f"{float(c.non_rigid):g}" if c.non_rigid else RIGID,
            c.crash or "none",
            ",".join(map(str, c.sizes)) if c.n is None else str(c.n),
            *map(str, (c.runs, c.formed, c.collided, c.stalled, c.capped, c.errors)),
            "-" if c.rounds is None else f"{c.rounds[1]:g}",
            "-" if c.time is None else f"{c.time[1]:.1f}",
        ]
        lines.append("| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |")
    return "\n".join(lines) + "\n"


def is_clean(row: Mapping[str, str]) -> bool:
    """Whether a row's run formed with no collision (what the paper guarantees)."""
    return row["status"] == Status.FORMED and row["collisions"] == "0"


__all__ = [
    "COLUMNS",
    "ERROR",
    "KEY_COLUMNS",
    "Cell",
    "Grid",
    "GroupKey",
    "RunFigures",
    "RunSpec",
    "SweepInputError",
    "TableError",
    "assignment_bound",
    "cell_label",
    "crash_cell",
    "curves",
    "distance_ratio",
    "group_key",
    "header_error",
    "is_clean",
    "kept_length",
    "make_row",
    "markdown_table",
    "model_label",
    "non_rigid_cell",
    "params_text",
    "parse_crash",
    "parse_ints",
    "parse_non_rigid",
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
