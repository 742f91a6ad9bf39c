"""The summary of a sweep's rows: a Cell per configuration of the grid (counts and quartiles),
the labels and series the figures draw, and the Markdown table of `--summary-md`. Pure."""

from __future__ import annotations

import itertools
import statistics
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Final

from fatswarm.deploy.sweep.grid import (
    MODEL_COLUMNS,
    RIGID,
    Grid,
    crash_cell,
    model_cells,
    model_label,
    model_of_cells,
    model_suffix,
    non_rigid_cell,
)
from fatswarm.deploy.sweep.table import ERROR
from fatswarm.domain.outcome import Status
from fatswarm.domain.robot_model import PAPER_MODEL, RobotModel

Quartiles = tuple[float, float, float]  # (25th percentile, median, 75th percentile)
ModelKey = tuple[str, ...]  # a row's MODEL_COLUMNS cells
# What a summary groups rows by: (algorithm, start, scheduler, non_rigid, crash, the robot model's
# cells, n) as the CSV writes them; n is None in a group over every n (the Markdown table).
GroupKey = tuple[str, str, str, str, str, ModelKey, int | None]
PAPER: Final = "paper"  # the robot-model column of the Markdown table for the paper's model


@dataclass(frozen=True, slots=True)
class Cell:
    """The runs of one (algorithm, start, scheduler, non-rigid delta, crash count, robot model, n),
    summed up; `n` is None for a cell over every n (whose sizes are `sizes`)."""

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
    robot_model: RobotModel = PAPER_MODEL  # sight, obstruction, lights, frames

    @property
    def model(self) -> str:
        """The model label (`model_label`) of the cell's runs."""
        return model_label(
            self.scheduler,
            float(self.non_rigid) if self.non_rigid else None,
            int(self.crash) if self.crash else None,
            self.robot_model,
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
        tuple(row[c] for c in MODEL_COLUMNS),
        int(row["n"]) if by_n else None,
    )


def summarize(rows: Iterable[Mapping[str, str]], grid: Grid, *, by_n: bool = True) -> list[Cell]:
    """One Cell per (algorithm, start, scheduler, non-rigid delta, robot model, crash count, n)
    of `grid` with rows, in the grid's order; with `by_n` false, one per the same less n, over
    every n."""
    groups: dict[GroupKey, list[Mapping[str, str]]] = {}
    for row in rows:
        groups.setdefault(group_key(row, by_n=by_n), []).append(row)
    sizes: tuple[int | None, ...] = grid.sizes if by_n else (None,)
    cells = []
    for (algorithm, _), start, scheduler, delta, model, f, n in itertools.product(
        grid.algorithms,
        grid.starts,
        grid.schedulers,
        grid.non_rigids,
        grid.models,
        grid.crashes,
        sizes,
    ):
        model_key = tuple(model_cells(model).values())
        key = (algorithm, start, scheduler, non_rigid_cell(delta), crash_cell(f), model_key, n)
        group = groups.get(key)
        if group:
            ns = {int(r["n"]) for r in group}
            cells.append(_cell(key, group, tuple(m for m in grid.sizes if m in ns)))
    return cells


def _cell(key: GroupKey, group: Sequence[Mapping[str, str]], sizes: tuple[int, ...]) -> Cell:
    algorithm, start, scheduler, non_rigid, crash, model_key, n = key
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
        robot_model=model_of_cells(dict(zip(MODEL_COLUMNS, model_key, strict=True))),
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
    median virtual time (async models; `-` for round models) of the formed runs. A robot-model
    column (`model_suffix`'s words, `paper` for the paper's model) only when some cell has
    another model. Text only, so that a results page can include it as it is."""
    several_start = len({c.start for c in cells}) > 1
    models = any(not c.robot_model.is_paper for c in cells)
    head = [
        "algorithm",
        *(["start"] if several_start else []),
        "scheduler",
        "non-rigid",
        "crash",
        *(["robot model"] if models else []),
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
        row = _markdown_row(c, start=several_start, model=models)
        lines.append("| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |")
    return "\n".join(lines) + "\n"


def _markdown_row(c: Cell, *, start: bool, model: bool) -> list[str]:
    """The cells of one line of `markdown_table`, with the start and robot-model columns when
    asked for."""
    return [
        c.algorithm,
        *([c.start] if start else []),
        c.scheduler,
        f"{float(c.non_rigid):g}" if c.non_rigid else RIGID,
        c.crash or "none",
        *([model_suffix(c.robot_model).lstrip("+") or PAPER] if model else []),
        ",".join(map(str, c.sizes)) if c.n is None else str(c.n),
        *map(str, (c.runs, c.formed, c.collided, c.stalled, c.capped, c.errors)),
        "-" if c.rounds is None else f"{c.rounds[1]:g}",
        "-" if c.time is None else f"{c.time[1]:.1f}",
    ]


def is_clean(row: Mapping[str, str]) -> bool:
    """Whether a row's run formed with no collision (what the paper guarantees)."""
    return row["status"] == Status.FORMED and row["collisions"] == "0"


__all__ = [
    "Cell",
    "GroupKey",
    "ModelKey",
    "Quartiles",
    "cell_label",
    "curves",
    "group_key",
    "is_clean",
    "markdown_table",
    "quartiles",
    "success_rates",
    "summarize",
]
