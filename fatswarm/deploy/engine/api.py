"""The Python API for notebooks and scripts: run a configuration, read a record, walk its rounds.

    import fatswarm
    result = fatswarm.run(n=8, seed=1, scheduler="fsync", record="run.jsonl")
    record = fatswarm.read_record("run.jsonl")
    for rnd in record.rounds:            # each committed round; positions are (n, 2) arrays
        print(rnd.round, rnd.active, rnd.positions.mean(axis=0))
    fatswarm.positions_at(record, 2.5)   # every centre half-way through round 3
    record.to_dataframe()                # one row per robot per round (pandas)

Runs here are lock-step runs (one process): the same world and coordinator cores as a networked
run, so their records are the same. `fatswarm run` is the networked emulator. The configuration
is the CLI's (`RunConfig`): its refusals name flags, which `run` words as its own keywords.
"""

from __future__ import annotations

import inspect
import numbers
import os
import re
import reprlib
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from fatswarm.deploy.engine.config import (
    DEFAULT_SCHEDULER,
    DEFAULT_START,
    RunConfig,
    RunInputError,
    RunSetup,
    input_errors,
)
from fatswarm.deploy.engine.lockstep import Lockstep, RoundReport, start_lockstep
from fatswarm.deploy.engine.lockstep import RunResult as LockstepResult
from fatswarm.deploy.engine.notebook import RunRecord, RunResult
from fatswarm.domain.figures import run_derived, summary_values
from fatswarm.domain.path import Points
from fatswarm.domain.robot_model import AXES, AXIS_NAMES, Axis, RobotModel, short_of_header
from fatswarm.world import record_read
from fatswarm.world.journal import Journal
from fatswarm.world.record import RecordWriter
from fatswarm.world.record import RunRecord as RecordLines
from fatswarm.world.timeline import Timeline


class RunArgumentError(RunInputError, TypeError):
    """A keyword of `fatswarm.run` of the wrong type (a ValueError, as every refused input, and a
    TypeError)."""


class TornRecordWarning(UserWarning):
    """`read_record` left out a torn last line (a crash mid-write), as replay and plot do."""


def run(
    n: int | None = None,
    *,
    algorithm: str = "uniform-circle",
    params: Mapping[str, object] | None = None,
    seed: int = 0,
    start: str = DEFAULT_START,
    positions: Points | None = None,
    init: str | os.PathLike[str] | None = None,
    scheduler: str = DEFAULT_SCHEDULER,
    fairness: int | None = None,
    schedule: str | os.PathLike[str] | None = None,
    max_rounds: int | None = None,
    non_rigid: float | None = None,
    crash: int | None = None,
    record_views: bool = False,
    record: str | os.PathLike[str] | None = None,
    on_round: Callable[[RoundReport], None] | None = None,
    **model: object,
) -> RunResult:
    """Run one configuration in lock step and return how it ended (`RunResult`).

    The start is `positions` ((n, 2) world coordinates), else the JSON file `init`, else a random
    start of kind `start` drawn from `seed`. `record`: write the run record there (overwritten).
    `on_round` is called after every committed round. `non_rigid`: the adversary's delta (a move
    may be stopped anywhere after the robot travelled delta, drawn from `seed`); None: rigid.
    `crash`: f robots the adversary crashes for good (which and when drawn from `seed`,
    `world.core.crash_plan`; the goal is then judged on the live robots); None: no crashes.
    `**model`: the robot model, one keyword per axis (`fatswarm.domain.robot_model.AXES`:
    visibility, sight, lights, frames, frame_change...), as the flags of `fatswarm run`
    (docs/model.md; the signature lists them); `record_views`: each record line names what each
    looker saw.
    Raises a ValueError in these keywords' words for what it refuses: one of `input_errors()`
    (fatswarm.deploy.engine.config), or `RunArgumentError` for a keyword of the wrong type.
    """
    asked = run_asked(locals())  # every keyword by name: this signature is their one list
    try:
        setup = asked.config.resolve()
        writer = None if asked.record is None else RecordWriter(asked.record)
        palette = Palette(asked.on_round)
        try:
            result = started(setup, writer, palette.committed).finish()
        finally:
            if writer is not None:
                writer.close()
        return api_result(result, asked, setup, palette.names)
    except input_errors() as exc:
        raise refusal(exc) from None


@dataclass(frozen=True, slots=True)
class RunAsked:
    """What `run`'s keywords ask for, checked: the configuration, where its record goes (None:
    nowhere) and the round callback."""

    config: RunConfig
    record: str | None
    on_round: Callable[[RoundReport], None] | None


def run_asked(keywords: Mapping[str, Any]) -> RunAsked:
    """`run`'s keywords (each of its parameters by name, `model` the axes given) checked; raises
    as `run` does, in its words. `fatswarm.Swarm` takes the same keywords."""
    try:
        model = keywords["model"]
        return RunAsked(
            RunConfig(
                n=_whole("n", keywords["n"]),
                algorithm=_text("algorithm", keywords["algorithm"]),
                params=_params(keywords["params"]),
                seed=_seed(keywords["seed"]),
                start=_text("start", keywords["start"]),
                init=_path("init", keywords["init"]),
                positions=_positions(keywords["positions"]),
                scheduler=_text("scheduler", keywords["scheduler"]),
                schedule=_path("schedule", keywords["schedule"]),
                fairness=_whole("fairness", keywords["fairness"]),
                max_rounds=_whole("max_rounds", keywords["max_rounds"]),
                non_rigid=_number("non_rigid", keywords["non_rigid"]),
                crash=_whole("crash", keywords["crash"]),
                model=_model(model),
                record_views=_flag("record_views", keywords["record_views"]),
            ),
            _path("record", keywords["record"]),
            _callback(keywords["on_round"]),
        )
    except input_errors() as exc:
        raise refusal(exc) from None


def refusal(exc: Exception) -> Exception:
    """A refusal worded for the CLI's flags (one of `input_errors()`), worded for the API's
    keywords (`api_words`), to raise alone (no traceback into the checks)."""
    exc.args = (api_words(str(exc)), *exc.args[1:])
    return exc.with_traceback(None)


def started(
    setup: RunSetup, record: Journal | None, on_round: Callable[[RoundReport], None] | None
) -> Lockstep:
    """The lock step of the resolved run `setup`, started (its header to `record`, if not None)."""
    return start_lockstep(
        setup.initial,
        setup.params,
        setup.scheduler,
        seed=setup.seed,
        max_rounds=setup.max_rounds,
        record=record,
        on_round=on_round,
        settings=setup.settings,
    )


class Palette:
    """The colours a run's lines show (the picture's palette), gathered as its rounds commit;
    the user's round callback, if any, is called after."""

    def __init__(self, on_round: Callable[[RoundReport], None] | None) -> None:
        self.on_round = on_round
        self.seen: set[str] = set()

    def committed(self, report: RoundReport) -> None:
        lights = report.entry.extra.get("lights")
        self.seen.update(lights if isinstance(lights, list) else ())
        if self.on_round is not None:
            self.on_round(report)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(sorted(self.seen))


def api_result(
    result: LockstepResult, asked: RunAsked, setup: RunSetup, palette: tuple[str, ...] = ()
) -> RunResult:
    """The lock step's `result` of the run `asked` for, as the API hands it back (`palette`: the
    colours its lines showed, `Palette.names`)."""
    return RunResult.of(
        result,
        n=setup.params.n,
        seed=setup.seed,
        scheduler=asked.config.scheduler,
        algorithm=setup.params.name,
        params=dict(setup.params.values),
        record=asked.record,
        outside=setup.outside,
        robot_model=setup.robot_model,
        palette=palette,
    )


# --- the keywords, checked in the API's words ----------------------------------------------------


def _signature() -> inspect.Signature:
    """`run`'s signature with one keyword per axis of the robot model (`AXES`) in place of
    `**model`, each with its default: what `help(fatswarm.run)` and editors show."""
    shown = inspect.signature(run)
    kept = [p for p in shown.parameters.values() if p.kind is not p.VAR_KEYWORD]
    axes = [
        inspect.Parameter(
            a.name,
            inspect.Parameter.KEYWORD_ONLY,
            default=_plain_default(a),
            annotation="str" if a.choices else "float | None" if a.unset else "float",
        )
        for a in AXES
    ]
    return shown.replace(parameters=[*kept, *axes])


def _plain_default(axis: Axis) -> object:
    return str(axis.default) if isinstance(axis.default, str) else axis.default


run.__signature__ = _signature()  # type: ignore[attr-defined]
KEYWORDS: Final = frozenset(inspect.signature(run).parameters)
_PHRASES: Final = (  # whole phrases first, then every flag left (below) by its keyword
    (re.compile(r"^-n (\S+) disagrees with the (\d+) robots of "),
     r"n=\1 disagrees with the \2 robots of init "),
    (re.compile(r"\bdrop (--[a-z][a-z-]*[a-z]|-n)\b"), r"leave \1 out"),
    (re.compile(r"--lights (\S+) needs"), r"lights='\1' needs"),
    (re.compile(r"--scheduler ([a-z-]+) or ([a-z-]+)\b"), r"scheduler='\1' or '\2'"),
    (re.compile(r"--scheduler ([a-z-]+)\b"), r"scheduler='\1'"),
    (re.compile(r"\(--schedule PATH\)"), "(schedule=PATH)"),
    (re.compile(r"-a or --param a=\.\.\."), "params={'a': ...}"),
)  # fmt: skip
_FLAG: Final = re.compile(r"(?<![\w-])(--[a-z][a-z-]*[a-z]|-n)\b")


def api_words(message: str, keywords: frozenset[str] = KEYWORDS) -> str:
    """A refusal worded for `fatswarm run`'s flags, worded for `fatswarm.run`'s keywords (or
    those of another function of the API, `keywords`): `-n 5 disagrees with the 6 robots of
    s.json; drop -n` is `n=5 disagrees with the 6 robots of init s.json; leave n out`,
    `--max-rounds` is `max_rounds`."""
    for pattern, words in _PHRASES:
        message = pattern.sub(words, message)

    def keyword(match: re.Match[str]) -> str:
        name = match[1].lstrip("-").replace("-", "_")
        name = "params" if name == "param" else name
        return name if name in keywords else match[1]

    return _FLAG.sub(keyword, message)


def _shown(value: object) -> str:
    """`value` as a refusal shows it: its repr, cut short."""
    return reprlib.repr(value)


def _whole(name: str, value: object) -> int | None:
    """An int keyword or None (numpy's ints too); RunArgumentError otherwise."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise RunArgumentError(f"{name} must be an int or None, got {_shown(value)}")
    return int(value)


def _seed(value: object) -> int:
    if value is None or isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise RunArgumentError(f"seed must be an int, got {_shown(value)}")
    return int(value)


def _number(name: str, value: object) -> float | None:
    """A number keyword or None; RunArgumentError otherwise (its range is the config's)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise RunArgumentError(f"{name} must be a number or None, got {_shown(value)}")
    return value if isinstance(value, (int, float)) else float(value)  # as given, for refusals


def _text(name: str, value: object) -> str:
    if not isinstance(value, str):
        raise RunArgumentError(f"{name} must be a str, got {_shown(value)}")
    return value


def _flag(name: str, value: object) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise RunArgumentError(f"{name} must be True or False, got {_shown(value)}")
    return bool(value)


def _path(name: str, value: object) -> str | None:
    """A file name keyword (str or os.PathLike) or None; RunArgumentError otherwise."""
    if value is None:
        return None
    path = os.fspath(value) if isinstance(value, (str, os.PathLike)) else None
    if not isinstance(path, str):
        raise RunArgumentError(f"{name} must be a path (str or os.PathLike), got {_shown(value)}")
    return path


def _model(given: Mapping[str, object]) -> RobotModel:
    """The robot model of the axes' keywords (`AXES`; unset ones: the paper's); RunArgumentError
    for a keyword that is no axis or a value of the wrong type, ModelError for a bad value."""
    unknown = sorted(set(given) - set(AXIS_NAMES))
    if unknown:
        raise RunArgumentError(f"run() got an unexpected keyword argument {unknown[0]!r}")
    values = {
        axis.name: _text(axis.name, given[axis.name])
        if axis.choices is not None
        else _number(axis.name, given[axis.name])
        for axis in AXES
        if axis.name in given
    }
    return RobotModel.of(**values)


def _callback(value: object) -> Callable[[RoundReport], None] | None:
    if value is not None and not callable(value):
        raise RunArgumentError(f"on_round must be a function or None, got {_shown(value)}")
    return value


def _params(value: object) -> dict[str, object]:
    if value is None:
        return {}
    if not isinstance(value, Mapping) or not all(isinstance(k, str) for k in value):
        raise RunArgumentError(f"params must be a dict of names to values, got {_shown(value)}")
    return dict(value)


def _positions(value: object) -> Points | None:
    """The start as an array of numbers (its shape is the config's to check) or None."""
    if value is None:
        return None
    try:
        return np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise RunArgumentError(
            f"positions must be an (n, 2) array of numbers, got {_shown(value)}"
        ) from None


# --- records ------------------------------------------------------------------------------------


def read_record(path: str | os.PathLike[str], *, allow_torn_end: bool = True) -> RunRecord:
    """The whole record at `path`, validated (`RunRecord`); raises RecordFormatError naming the
    file, line and reason. A torn last line (a run that crashed mid-write) is left out with a
    `TornRecordWarning` saying how many complete rounds are kept, as `fatswarm replay` and
    `fatswarm plot` do; `allow_torn_end=False` refuses it instead."""
    name = _path("path", path)
    if name is None:
        raise RunArgumentError("path must be a path (str or os.PathLike), got None")
    lines = record_read.read_record(name, allow_torn_end=allow_torn_end)
    note = record_read.torn_end_note(name, lines)
    if note is not None:
        warnings.warn(note.removeprefix("note: "), TornRecordWarning, stacklevel=2)
    return RunRecord.of(lines, name)


Recorded = RecordLines | LockstepResult | str | os.PathLike[str]  # what the record readers take
PRINTED_DECIMALS: Final = 3  # the end time as the summary and the result's repr print it


def as_record(of: object, caller: str) -> RecordLines:
    """The record `of` names: a record as it is, a path (str or os.PathLike) read whole
    (`read_record`), or a `fatswarm.run` result's record (written with `record=`);
    RunArgumentError for anything else, or a result run without a record."""
    if isinstance(of, RecordLines):
        return of
    if isinstance(of, (str, os.PathLike)):
        return read_record(of)
    if isinstance(of, RunResult) and of.record is not None:
        return read_record(of.record)
    if isinstance(of, LockstepResult):
        raise RunArgumentError(
            f"{caller} needs the run's rounds, which a result does not keep: run it with "
            "record='run.jsonl' and pass the result (or the record, or its path)"
        )
    raise RunArgumentError(
        f"{caller} takes a record, its path (str or os.PathLike) or a fatswarm.run result, "
        f"got {type(of).__name__}"
    )


def positions_at(of: Recorded, t: float) -> Points:
    """Every robot's centre (n, 2) at time `t` of the run `of` (a record, its path, or a
    `fatswarm.run` result with its `record`): t in rounds for round-based records (t = k: round
    k's recorded positions, t = 2.5 half-way through round 3), virtual time for async ones
    (fatswarm.world.timeline). `t` runs from 0 to the run's end; the end as the summary prints
    it (3 decimals: 58.077 for 58.0771...) is the end. Raises ValueError naming the valid
    range for a `t` outside it. Builds a `Timeline` each call: to ask for many times, keep one
    `fatswarm.world.timeline.Timeline(record)`."""
    timeline = Timeline(as_record(of, "positions_at"))
    if isinstance(t, bool) or not isinstance(t, numbers.Real):
        raise RunArgumentError(f"t must be a number, got {_shown(t)}")
    slack = 0.5 * 10.0**-PRINTED_DECIMALS  # what rounding to the printed decimals may add
    if timeline.end < float(t) <= timeline.end + slack:
        t = timeline.end
    if not 0.0 <= float(t) <= timeline.end:
        unit = "virtual time" if timeline.is_async else "rounds"
        raise ValueError(
            f"t must be between 0 and the run's end, {timeline.end!r} ({unit}; as printed, "
            f"{timeline.end:.{PRINTED_DECIMALS}f}), got {t!r}"
        )
    return timeline.at(t)


def trajectory(of: Recorded) -> NDArray[np.float64]:
    """Every robot's centre at the start and after each committed round: (rounds + 1, n, 2), of
    a record, its path, or a `fatswarm.run` result with its `record`."""
    record = as_record(of, "trajectory")
    frames = [record.header.initial, *(entry.positions for entry in record.rounds)]
    return np.stack([np.asarray(f, dtype=np.float64) for f in frames])


def moved_by_round(of: Recorded) -> NDArray[np.bool_]:
    """(rounds, n): whether each robot asked for a move (a non-empty path) in each round (of
    a record, its path, or a `fatswarm.run` result with its `record`)."""
    record = as_record(of, "moved_by_round")
    out = np.zeros((len(record.rounds), record.header.n), dtype=bool)
    for k, entry in enumerate(record.rounds):
        out[k, [m.robot for m in entry.moves]] = True
    return out


def summary(of: LockstepResult | RecordLines) -> dict[str, str | int | float | None]:
    """A run's figures as plain values (a row of a table or a DataFrame), from its result or its
    record: status ("formed", "stalled", "max_rounds"; "unfinished" for a record without a
    result line), rounds, epochs, moves, total_distance, collisions, looks, time (the virtual
    time of an async run, else None), n, seed, scheduler, algorithm and model (the robot model in
    one word, `RobotModel.short`: "paper", "opaque+sight5"; None where unknown),
    then the figures that follow from the positions (fatswarm.domain.figures: min_gap...), and
    `outside`, the line saying how the run is outside its algorithm's assumptions, if it is."""
    if isinstance(of, RecordLines):
        return _record_summary(of)
    if not isinstance(of, LockstepResult):
        raise TypeError(f"summary takes a RunResult or a RunRecord, got {type(of).__name__}")
    known = of if isinstance(of, RunResult) else None  # the API's results know their run
    return {
        "status": str(of.status),
        "rounds": int(of.rounds),
        "epochs": int(of.epochs),
        "moves": int(of.moves),
        "total_distance": float(of.total_distance),
        "collisions": int(of.collisions),
        "looks": int(of.looks),
        "time": None if of.time is None else float(of.time),
        "n": len(of.positions) if known is None else known.n,
        "seed": None if known is None else known.seed,
        "scheduler": None if known is None else known.scheduler,
        "algorithm": None if known is None else known.algorithm,
        "model": None if known is None else known.robot_model.short,
        **summary_values(of.derived),
        **({"outside": known.outside} if known is not None and known.outside else {}),
    }


def _record_summary(record: RecordLines) -> dict[str, str | int | float | None]:
    """`summary` of a record: counted from its lines (the result line's figures where it has
    them: epochs and time are not counted), the derived figures from its positions."""
    res, outside = record.result, record.header.extra.get("assumption")
    return {
        "status": "unfinished" if res is None else str(res.status),
        "rounds": len(record.rounds) if res is None else int(res.rounds),
        "epochs": None if res is None else res.epochs,
        "moves": sum(len(entry.moves) for entry in record.rounds),
        "total_distance": float(sum(m.traveled for e in record.rounds for m in e.moves)),
        "collisions": sum(len(entry.collisions) for entry in record.rounds),
        "looks": sum(len(entry.active) for entry in record.rounds),
        "time": None if res is None else res.time,
        "n": record.header.n,
        "seed": record.header.seed,
        "scheduler": record.header.scheduler,
        "algorithm": record.header.algorithm,
        "model": short_of_header(record.header.extra.get("model")),
        **summary_values(run_derived(record.rounds)),
        **({"outside": outside} if isinstance(outside, str) and outside else {}),
    }


__all__ = [
    "RunArgumentError",
    "RunRecord",
    "RunResult",
    "TornRecordWarning",
    "api_words",
    "moved_by_round",
    "positions_at",
    "read_record",
    "run",
    "summary",
    "trajectory",
]
