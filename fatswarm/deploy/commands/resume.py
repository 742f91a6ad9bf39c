"""`fatswarm run --resume`: the run a record continues, taken from its header, and the refusal of
a flag that contradicts it or of a record that cannot be continued (one line each)."""

from __future__ import annotations

import argparse
import os
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.config import (
    RunInputError,
    RunSetup,
    check_crash,
    check_fairness,
    check_non_rigid,
)
from fatswarm.deploy.flags import given_flags
from fatswarm.deploy.scenarios.starts import load_init, random_start
from fatswarm.deploy.view.stopped import stopped_line
from fatswarm.deploy.view.summary import counted, unit
from fatswarm.domain.outcome import Status
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.robot_model import AXES, AXIS_NAMES, Bodies, axis_named
from fatswarm.domain.seam import Configured, parse_assignments
from fatswarm.world.physics import validate_configuration
from fatswarm.world.record import DEFAULT_SCALE, RecordFormatError
from fatswarm.world.record_read import read_record
from fatswarm.world.setup import WorldSetup

if TYPE_CHECKING:
    from fatswarm.domain.path import Points
    from fatswarm.world.record import Header, Result, RunRecord


def resolve_resume(args: argparse.Namespace) -> RunSetup:
    """The run `--resume` continues: the --record file's header (n, a, seed, scheduler, start,
    round cap, adversary, robot model) and committed rounds; raises one of `input_errors()` for a
    record that cannot be continued, a flag that no run takes, or flags given that contradict the
    record (all of them named in one line, by `check_against_header`; flags that agree with it
    are fine)."""
    # the whole lock-step engine: the CLI imports this module (through deploy.commands.run) to
    # build its parser
    from fatswarm.deploy.engine.lockstep import LOCKSTEP_SWARM, default_max_rounds

    path: str = args.record
    record = read_resumable(path)
    h = record.header
    if h.seed is None:
        raise RunInputError(f"--resume: {path} does not say its seed; its run cannot be continued")
    recorded = WorldSetup.from_header(h, LOCKSTEP_SWARM, None)  # (its header is not written again)
    _check_values(args, h, path)
    check_against_header(args, recorded, path)
    params = Configured.of(load_algorithm(h.algorithm_ref), h.n, h.params)
    params.check_start(h.initial)
    initial = validate_configuration(
        h.initial, bodies_are_points=recorded.robot_model.bodies is Bodies.POINTS
    )
    fairness = args.fairness if args.fairness is not None else recorded.fairness
    # the script the run was made with, where it was, unless --schedule says where it is now
    schedule = args.schedule if args.schedule is not None else recorded.schedule
    scheduler = make_scheduler(h.scheduler, h.n, h.seed, schedule, fairness)
    cap = (
        recorded.max_rounds
        if recorded.max_rounds is not None and recorded.max_rounds >= 1
        else None
    )
    if cap is None:  # a header without its cap: as the run would have had it
        cap = args.max_rounds or default_max_rounds(h.n, h.scheduler)
    return RunSetup(replace(recorded, initial=initial, max_rounds=cap), params, scheduler, record)


def _check_values(args: argparse.Namespace, header: Header, path: str) -> None:
    """Refuse a flag given with --resume that no run takes (whatever the record says): a round
    cap < 1, a --schedule without the scripted scheduler, a fairness bound for a scheduler that
    ignores it, a non-rigid delta or a crash count out of range (RunInputError)."""
    if args.max_rounds is not None and args.max_rounds < 1:
        raise RunInputError(f"--max-rounds must be at least 1, got {args.max_rounds}")
    if header.scheduler != "scripted" and args.schedule is not None:
        raise RunInputError(
            f"--schedule only goes with --scheduler scripted; {path}'s run has "
            f"scheduler={header.scheduler}"
        )
    check_fairness(args.fairness, header.scheduler)
    check_non_rigid(getattr(args, "non_rigid", None))
    check_crash(getattr(args, "crash", None), header.n)


def read_resumable(path: str) -> RunRecord:
    """The run record at `path`, if it holds a run to continue; else RunInputError (one line).

    A torn last line (a crash mid-write, a full disk) is left out: the networked world drops it
    from the file as it opens it, a lock-step run with `drop_torn_end` before it appends.
    """
    if not os.path.exists(path):
        raise RunInputError(
            f"--resume: {path} does not exist; nothing to resume (drop --resume to start a new run)"
        )
    if os.path.isfile(path) and os.path.getsize(path) == 0:
        raise RunInputError(f"--resume: {path} is empty, not a run record; nothing to resume")
    try:
        record = read_record(path, allow_torn_end=True)
    except RecordFormatError as exc:
        raise RunInputError(f"--resume: not a run record: {exc}") from None
    if record.result is not None:
        raise RunInputError(
            f"--resume: {path} already finished ({ended(record.result, record.header.scheduler)})"
            "; nothing to resume"
        )
    return record


def drop_torn_end(path: str, record: RunRecord) -> str | None:
    """Cut the torn last line `record` left out of the file at `path` (never committed: a crash
    or a full disk mid-write), so that the resumed run appends after its last complete line; the
    line saying so, or None if the record had no torn line."""
    # the world's journal (and with it the world core): the CLI imports this module to build
    # its parser
    from fatswarm.world.journal import drop_torn_line

    if record.torn_line is None:
        return None
    dropped = drop_torn_line(path)
    return (
        f"--resume: dropped the torn last line of {path} (line {record.torn_line}, {dropped} "
        "bytes written when the run stopped mid-write)"
    )


def ended(result: Result, scheduler: str = "") -> str:
    """How a finished record ended, in a few words: "formed in 31 rounds" (cycles under an
    async model)."""
    word = unit(scheduler)
    if result.status == Status.FORMED:
        return f"formed in {counted(result.rounds, word)}"
    if result.status == Status.MAX_ROUNDS:
        return f"stopped at the {word} limit of {counted(result.rounds, word)}"
    return f"{result.status} after {counted(result.rounds, word)}"


@dataclass(frozen=True, slots=True)
class Contradiction:
    """A flag given with --resume that says otherwise than the record."""

    flag: str  # `-n`, `--frame-change`
    given: str  # the flag as given: `-n 12`, `--param a=5`
    recorded: str  # what the record says, after "whose run": `has n=8`


def check_against_header(args: argparse.Namespace, recorded: WorldSetup, path: str) -> None:
    """Refuse (RunInputError, one line) the flags given with --resume that contradict the
    record's settings (`WorldSetup.from_header`): every one of them, each with both values."""
    found = contradictions(args, recorded)
    if found:
        said = "; ".join(f"{c.given} contradicts {path}, whose run {c.recorded}" for c in found)
        flags = ", ".join(dict.fromkeys(c.flag for c in found))
        raise RunInputError(f"{said}; drop {flags} to resume it")


def contradictions(args: argparse.Namespace, recorded: WorldSetup) -> list[Contradiction]:
    """Every flag given with --resume that contradicts the record's settings, in one pass over
    them: the algorithm and its parameters, n, a, seed, scheduler, round cap, fairness, start,
    adversary, each axis of the robot model (`AXES`) and --record-views. A flag not given never
    contradicts (its default may be the record's)."""
    h = recorded
    given = given_flags(args)
    found: list[Contradiction] = []
    for name, text in parse_assignments(list(given.get("param") or [])).items():
        value = h.params.get(name)
        if value is None or (str(value) != text and _as_number(text) != value):
            found.append(Contradiction("--param", f"--param {name}={text}", f"has {name}={value}"))
    cap = h.max_rounds if h.max_rounds is not None and h.max_rounds >= 1 else None
    side = _side(h)
    # (flag, dest, the record's value, what it says after "whose run"); `known`: False where
    # the record does not say (an old header without its cap or fairness): no flag contradicts
    rows: list[tuple[str, str, object, str, bool]] = [
        ("--algorithm", "algorithm", h.algorithm, f"has algorithm {h.algorithm}", True),
        ("-n", "n", h.n, f"has n={h.n}", True),
        ("-a", "a", side, f"has a={_number(side)}", True),
        ("--seed", "seed", h.seed, f"has seed={h.seed}", True),
        ("--scheduler", "scheduler", h.scheduler, f"has scheduler={h.scheduler}", True),
        ("--max-rounds", "max_rounds", cap, f"has max_rounds={cap}", cap is not None),
        (
            "--fairness",
            "fairness",
            h.fairness,
            f"has fairness={h.fairness}",
            h.fairness is not None,
        ),
        ("--non-rigid", "non_rigid", h.non_rigid, _says_non_rigid(h.non_rigid), True),
        (
            "--crash",
            "crash",
            h.crash,
            "has no crashes" if h.crash is None else f"has crash={h.crash}",
            True,
        ),
        *(
            (a.flag, a.name, v, f"has {a.name}={a.text(v) or 'none'}", True)
            for a in AXES
            for v in [h.robot_model.value(a.name)]
        ),
        ("--record-views", "record_views", h.record_views, "does not record views", True),
    ]
    for flag, dest, theirs, says, known in rows:
        if dest in given and known and _value(dest, given[dest]) != theirs:
            mine = given[dest]
            shown = "" if mine is True else f" {_number(mine) if isinstance(mine, float) else mine}"
            if dest in AXIS_NAMES:  # as its flag takes it (`--sight unlimited` for None)
                axis = axis_named(dest)
                shown = f" {axis.text(axis.check(mine))}"
            found.append(Contradiction(flag, f"{flag}{shown}", says))
    if "init" in given:
        _check_init(given["init"], h, found)
    elif "start" in given:
        _check_start(given["start"], h, found)
    return found


def _value(dest: str, given: object) -> object:
    """A flag's value as the settings hold it (a robot-model axis's: its member or number)."""
    return axis_named(dest).check(given) if dest in AXIS_NAMES else given


def _says_non_rigid(delta: float | None) -> str:
    return "has rigid moves" if delta is None else f"has non_rigid={delta:g}"


def _check_init(init: str, recorded: WorldSetup, found: list[Contradiction]) -> None:
    """An --init file whose start is not the record's."""
    h = recorded
    positions, _ = load_init(init, points=h.robot_model.bodies is Bodies.POINTS)
    if len(positions) != h.n:
        says = f"has n={h.n} (the file {len(positions)} robots)"
        found.append(Contradiction("--init", f"--init {init}", says))
        return
    points = h.robot_model.bodies is Bodies.POINTS
    where = _first_difference(
        validate_configuration(positions, bodies_are_points=points), h.initial
    )
    if where is not None:
        robot, mine, theirs = where
        says = f"started elsewhere (robot {robot} at {theirs}, not at {mine} as in the file)"
        found.append(Contradiction("--init", f"--init {init}", says))


def _check_start(kind: str, recorded: WorldSetup, found: list[Contradiction]) -> None:
    """A --start kind whose start of the record's seed is not the record's start."""
    h = recorded
    where = _first_difference(random_start(h.n, h.seed, kind, _side(h)), h.initial)
    if where is not None:
        robot, mine, theirs = where
        says = (
            f"did not start from the {kind} start of seed {h.seed} (robot {robot} at "
            f"{theirs}, not at {mine})"
        )
        found.append(Contradiction("--start", f"--start {kind}", says))


def _side(recorded: WorldSetup) -> float:
    """The paper's side `a` of the record's run, as its header gives it (`Header.a`)."""
    value = recorded.params.get("a", DEFAULT_SCALE)
    return float(value) if isinstance(value, (int, float)) else DEFAULT_SCALE


def _as_number(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def _number(value: float) -> str:
    """`value` as short as `:g` puts it, unless that would hide a difference."""
    short = f"{value:g}"
    return short if float(short) == value else repr(value)


def _first_difference(mine: Points, theirs: Points) -> tuple[int, str, str] | None:
    """The first robot placed differently in two (n, 2) starts, with both places; None if equal."""
    for robot, (p, q) in enumerate(zip(mine, theirs, strict=True)):
        if p[0] != q[0] or p[1] != q[1]:
            return robot, f"({p[0]:.9g}, {p[1]:.9g})", f"({q[0]:.9g}, {q[1]:.9g})"
    return None


__all__ = [
    "Contradiction",
    "check_against_header",
    "contradictions",
    "drop_torn_end",
    "ended",
    "read_resumable",
    "resolve_resume",
    "stopped_line",
]
