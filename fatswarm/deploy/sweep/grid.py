"""The pure parts of `fatswarm sweep`: the grid and its runs, from the flags to each run's
configuration and key. The CSV schema is `deploy/sweep/table.py`, the summary of rows
`deploy/sweep/summary.py`. No I/O: the pool, the CSV file and the figures are
`deploy/sweep/pool.py` and `deploy/sweep/figures.py`.
"""

from __future__ import annotations

import argparse
import itertools
import math
import re
import shlex
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

from fatswarm.coordinator.schedule import NAMES, ScheduleError, make_scheduler
from fatswarm.domain.registry import DEFAULT as DEFAULT_ALGORITHM
from fatswarm.domain.robot_model import (
    AXES,
    AXIS_NAMES,
    PAPER_MODEL,
    Axis,
    ModelError,
    RobotModel,
    axis_named,
)
from fatswarm.domain.seam import Algorithm, ParamValue, parse_assignments, resolve_values

MAX_RUNS: Final = 1_000_000  # a larger grid is a typo (`--seeds 0..10000000`), not a sweep
RANGE: Final = re.compile(r"(\d+)\.\.(\d+)(?::(\d+))?")  # 4..16 or 4..16:4 (inclusive)

ParamText = tuple[tuple[str, str], ...]  # (name, canonical value text), sorted by name
Key = tuple[str, ...]  # a row's KEY_COLUMNS values, as written in the CSV

# The key (configuration) columns of the CSV schema (`deploy/sweep/table.py`): with the fatswarm
# version they say all a lock-step run depends on.
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
    *AXIS_NAMES,  # the robot model's axes (`robot_model.AXES`): visibility, sight, lights...
)
# The robot model's key columns, blank for an axis at the paper's value: a table of the paper's
# model alone has none of them (the table's schema, `deploy/sweep/table.py`).
MODEL_COLUMNS: Final = AXIS_NAMES
RIGID: Final = "rigid"  # --non-rigid's word for rigid moves (the default)
NO_CRASH: Final = ("0", "none")  # --crash's words for no crash (the default)
UNLIMITED: Final = "unlimited"  # --sight's word for unlimited sight (the default)


class SweepInputError(ValueError):
    """A grid argument or an output the sweep cannot use (the message says what to fix)."""


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


def model_flag(key: str) -> str:
    """The flag of a robot-model key: `--frame-change` for frame_change."""
    return axis_named(key).flag


def parse_axis(texts: Iterable[str], axis: Axis) -> tuple[Any, ...]:
    """A robot-model axis's values (`Axis.parse`: `--sight 6,unlimited`, `--frames chirality`),
    in the order given, without repeats (`6` and `6.0` are one); default (the paper's,);
    raises SweepInputError."""
    out: dict[Any, None] = {}
    for item in split_values(texts):
        try:
            out.setdefault(axis.parse(item), None)
        except ModelError as exc:
            if axis.choices is None:  # what the distances are, or the word for none
                raise SweepInputError(str(exc)) from None
            raise SweepInputError(
                f"{axis.flag} takes {', '.join(axis.words)} (a comma list), got {item!r}"
            ) from None
    return tuple(out) or (axis.check(axis.default),)


def parse_sight(texts: Iterable[str]) -> tuple[float | None, ...]:
    """`--sight`: distances (finite, > 0, robot radii) and/or `unlimited` (None) (`parse_axis`)."""
    return parse_axis(texts, axis_named("sight"))


def parse_choices(texts: Iterable[str], key: str) -> tuple[str, ...]:
    """A robot-model axis of words (`--visibility`, `--lights`, `--frames`, `--frame-change`):
    its values in the order given, without repeats; default the paper's (`parse_axis`)."""
    return tuple(str(value) for value in parse_axis(texts, axis_named(key)))


def parse_robot_models(given: Mapping[str, Iterable[str] | None]) -> tuple[RobotModel, ...]:
    """The robot models of the flags' texts by key (`AXES`; a key missing or None: the paper's
    value): every combination, the first axis slowest (visibility, then sight, lights, frames,
    frame change...), each axis in the order given. One model, the paper's, when no axis is
    given."""
    axes = [parse_axis(given.get(a.name) or (), a) for a in AXES]
    return tuple(RobotModel.of(*values) for values in itertools.product(*axes))


def robot_models_of(args: argparse.Namespace) -> tuple[RobotModel, ...]:
    """The robot models of `add_robot_model_arguments(p, lists=True)`'s flags
    (`parse_robot_models`); raises SweepInputError."""
    return parse_robot_models({a.name: getattr(args, a.name, None) for a in AXES})


def model_suffix(robot_model: RobotModel) -> str:
    """The robot model's axes that are not the paper's, each as `+TAGVALUE`: the visibility
    (`+opaque`, `+opaque-centres`), `+sightV`, `+lights-internal` / `+lights-external`, the
    frames (`+chirality`, `+disoriented`), `+every-look`...; "" for the paper's model."""
    return "" if robot_model.is_paper else "+" + robot_model.short


def model_label(
    scheduler: str,
    non_rigid: float | None,
    crash: int | None,
    robot_model: RobotModel = PAPER_MODEL,
) -> str:
    """The model a run ran under, in one word: the scheduler, `+nrDELTA` for non-rigid moves,
    `+crashF` for crash faults, then the robot model's axes that are not the paper's
    (`model_suffix`): `fsync`, `ssync+nr0.1`, `async+crash2`, `fsync+nr1+crash1`,
    `fsync+opaque+sight5+chirality`."""
    label = scheduler
    if non_rigid is not None:
        label += f"+nr{non_rigid:g}"
    if crash is not None:
        label += f"+crash{crash}"
    return label + model_suffix(robot_model)


def model_cells(robot_model: RobotModel) -> dict[str, str]:
    """The robot model's columns (MODEL_COLUMNS) of a run: each axis as its flag takes it back
    (numbers by repr), blank where it is the paper's (so a run of the paper's model has the key
    of a row of a table without these columns)."""
    changed = robot_model.changed()
    return {a.name: a.text(robot_model.value(a.name)) if a in changed else "" for a in AXES}


def model_of_cells(cells: Mapping[str, str]) -> RobotModel:
    """The robot model of a row's MODEL_COLUMNS cells (`model_cells` read back; blank or missing:
    the paper's value); raises ModelError for a cell no model writes."""
    return RobotModel.of(**{a.name: a.parse(cells[a.name]) for a in AXES if cells.get(a.name)})


def model_argv(robot_model: RobotModel) -> list[str]:
    """The `fatswarm run` flags of the robot model's axes that are not the paper's."""
    argv: list[str] = []
    for key, text in model_cells(robot_model).items():
        if text:
            argv += [model_flag(key), text]
    return argv


def sweep_schedulers() -> tuple[str, ...]:
    """The scheduler (or model) names a sweep takes: those of `coordinator.schedule.NAMES` that
    need no file (all but scripted, which replays one given schedule)."""
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
    robot_model: RobotModel = PAPER_MODEL  # sight, obstruction, lights, frames (docs/model.md)

    @property
    def model(self) -> str:
        """The model label (`model_label`): the scheduler, non-rigid moves, crash faults and the
        robot model."""
        return model_label(self.scheduler, self.non_rigid, self.crash, self.robot_model)

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
            **model_cells(self.robot_model),
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
        argv += model_argv(self.robot_model)
        return shlex.join(argv)


def non_rigid_cell(delta: float | None) -> str:
    """The non_rigid column of a run: the delta as `--non-rigid` takes it back, "" if rigid."""
    return "" if delta is None else value_text(delta)


def crash_cell(f: int | None) -> str:
    """The crash column of a run: f, "" for no crash."""
    return "" if f is None else str(f)


@dataclass(frozen=True, slots=True)
class Grid:
    """algorithms x starts x schedulers x non-rigid deltas x robot models x crash counts x sizes x
    seeds, each algorithm with its parameters. A crash count f needs f < n robots: the (n, f)
    cells with f >= n are left out of the grid (`left_out` counts their runs), not refused, so
    that one `-n 3..12 --crash 0,1,2` asks for every cell that exists."""

    algorithms: tuple[tuple[str, ParamText], ...]  # (reference, canonical --param texts)
    sizes: tuple[int, ...]
    starts: tuple[str, ...]
    schedulers: tuple[str, ...]
    seeds: tuple[int, ...]
    max_rounds: int | None = None
    non_rigids: tuple[float | None, ...] = (None,)  # None: rigid moves
    crashes: tuple[int | None, ...] = (None,)  # None: no crash
    models: tuple[RobotModel, ...] = (PAPER_MODEL,)  # `parse_robot_models`

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
    def has_models(self) -> bool:
        """Whether a run of the grid is under a robot model other than the paper's (its table
        needs the MODEL_COLUMNS)."""
        return any(not m.is_paper for m in self.models)

    @property
    def left_out(self) -> int:
        """The runs left out of the grid because their crash count f is >= their n."""
        return self._others() * len(self.sizes) * len(self.crashes) - self.size

    def _others(self) -> int:
        return math.prod(
            len(axis)
            for axis in (
                self.algorithms,
                self.starts,
                self.schedulers,
                self.non_rigids,
                self.models,
                self.seeds,
            )
        )

    def _pairs(self) -> list[tuple[int | None, int]]:
        """The (crash, n) cells that exist: no crash, or fewer crashes than robots."""
        return [(f, n) for f in self.crashes for n in self.sizes if f is None or f < n]

    def runs(self) -> list[RunSpec]:
        """Every run, seed by seed: a sweep stopped early has every other cell equally deep."""
        return [
            RunSpec(algorithm, n, start, scheduler, seed, params, self.max_rounds, delta, f, model)
            for seed, (algorithm, params), start, scheduler, delta, model, (f, n) in (
                itertools.product(
                    self.seeds,
                    self.algorithms,
                    self.starts,
                    self.schedulers,
                    self.non_rigids,
                    self.models,
                    self._pairs(),
                )
            )
        ]


__all__ = [
    "KEY_COLUMNS",
    "MODEL_COLUMNS",
    "UNLIMITED",
    "Grid",
    "Key",
    "ParamText",
    "RunSpec",
    "SweepInputError",
    "crash_cell",
    "model_argv",
    "model_cells",
    "model_flag",
    "model_label",
    "model_of_cells",
    "model_suffix",
    "non_rigid_cell",
    "params_text",
    "parse_choices",
    "parse_crash",
    "parse_ints",
    "parse_non_rigid",
    "parse_robot_models",
    "parse_seeds",
    "parse_sight",
    "robot_models_of",
    "split_values",
    "sweep_schedulers",
    "value_text",
    "values_text",
]
