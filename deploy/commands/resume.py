"""`fatswarm run --resume`: the run a record continues, taken from its header, and the refusal of
a flag that contradicts it or of a record that cannot be continued (one line each)."""

from __future__ import annotations

import argparse
import os
import shlex
from typing import TYPE_CHECKING, Any

from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.config import (
    MODEL_FLAGS,
    RunInputError,
    RunSetup,
    check_crash,
    check_fairness,
    check_non_rigid,
)
from fatswarm.deploy.flags import flag_given
from fatswarm.deploy.scenarios.starts import load_init, random_start
from fatswarm.deploy.view.summary import counted, unit
from fatswarm.domain.adversary import ASYNC_NAMES
from fatswarm.domain.outcome import Status
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.robot_model import RobotModel
from fatswarm.domain.seam import Configured, parse_assignments
from fatswarm.world.physics import validate_configuration
from fatswarm.world.record import RecordFormatError
from fatswarm.world.record_read import read_record
from fatswarm.world.setup import header_crash, header_non_rigid

if TYPE_CHECKING:
    from fatswarm.domain.path import Points
    from fatswarm.world.record import Header, Result, RunRecord


def resolve_resume(args: argparse.Namespace) -> RunSetup:
    """The run `--resume` continues: the --record file's header (n, a, seed, scheduler, start,
    round cap) and committed rounds; raises one of `input_errors()` for a record that cannot be
    continued or a flag given that contradicts it (flags that agree with it are fine)."""
    # the whole lock-step engine: the CLI imports this module (through deploy.commands.run) to
    # build its parser
    from fatswarm.deploy.engine.lockstep import default_max_rounds

    path: str = args.record
    record = read_resumable(path)
    h = record.header
    if h.seed is None:
        raise RunInputError(f"--resume: {path} does not say its seed; its run cannot be continued")
    cap = _recorded_cap(h)
    if args.max_rounds is not None and args.max_rounds < 1:
        raise RunInputError(f"--max-rounds must be at least 1, got {args.max_rounds}")
    check_against_header(args, h, cap, path)
    if h.scheduler != "scripted" and args.schedule is not None:
        raise RunInputError(
            f"--schedule only goes with --scheduler scripted; {path}'s run has "
            f"scheduler={h.scheduler}"
        )
    params = Configured.of(load_algorithm(h.algorithm_ref), h.n, h.params)
    params.check_start(h.initial)
    initial = validate_configuration(h.initial)
    fairness = recorded_fairness(args, h, path)
    schedule = args.schedule
    if schedule is None and isinstance(h.extra.get("schedule"), str):
        schedule = h.extra["schedule"]  # the script the run was made with, where it was
    scheduler = make_scheduler(h.scheduler, h.n, h.seed, schedule, fairness)
    if cap is None:  # a header without its cap: as the run would have had it
        cap = args.max_rounds or default_max_rounds(h.n, h.scheduler)
    return RunSetup(
        h.seed,
        params,
        initial,
        scheduler,
        cap,
        record,
        h.algorithm_ref,
        non_rigid=recorded_non_rigid(args, h, path),
        crash=recorded_crash(args, h, path),
        robot_model=recorded_model(args, h, path),
        record_views=h.extra.get("record_views") is True,
    )


def recorded_model(args: argparse.Namespace, header: Header, path: str) -> RobotModel:
    """The header's robot model (none: the paper's); RunInputError for a model flag that says
    otherwise than the record (or a --record-views the record was not made with)."""
    recorded = RobotModel.from_header(header.extra.get("model"))
    says = recorded.to_header()
    for key in MODEL_FLAGS:
        given = getattr(args, key, None)
        if given is not None and given != says[key]:
            flag = "--" + key.replace("_", "-")
            raise RunInputError(
                f"{flag} {given} contradicts {path}, whose run has {key}={says[key]}; "
                f"drop {flag} to resume it"
            )
    if getattr(args, "record_views", False) and header.extra.get("record_views") is not True:
        raise RunInputError(
            f"--record-views contradicts {path}, whose run does not record views; drop it"
        )
    return recorded


def _recorded_cap(header: Header) -> int | None:
    """The header's round cap, if it says one (a whole number >= 1)."""
    saved = header.extra.get("max_rounds")
    return saved if isinstance(saved, int) and not isinstance(saved, bool) and saved >= 1 else None


def recorded_fairness(args: argparse.Namespace, header: Header, path: str) -> int | None:
    """The fairness bound of the resumed run: --fairness, else the header's (None: neither says
    one); RunInputError for a --fairness that says otherwise than the record."""
    check_fairness(args.fairness, header.scheduler)
    recorded_k = header.extra.get("fairness")
    if isinstance(recorded_k, int) and args.fairness is not None and args.fairness != recorded_k:
        raise RunInputError(
            f"--fairness {args.fairness} contradicts {path}, whose run has "
            f"fairness={recorded_k}; drop --fairness to resume it"
        )
    return (
        args.fairness
        if args.fairness is not None
        else (recorded_k if isinstance(recorded_k, int) else None)
    )


def recorded_non_rigid(args: argparse.Namespace, header: Header, path: str) -> float | None:
    """The header's non-rigid delta (None: rigid moves); RunInputError for a --non-rigid that is
    not a finite number > 0 or that says otherwise than the record."""
    delta = header_non_rigid(header)
    given: float | None = getattr(args, "non_rigid", None)
    check_non_rigid(given)
    if given is not None and given != delta:
        says = "rigid moves" if delta is None else f"non_rigid={delta:g}"
        raise RunInputError(
            f"--non-rigid {given:g} contradicts {path}, whose run has {says}; "
            "drop --non-rigid to resume it"
        )
    return delta


def recorded_crash(args: argparse.Namespace, header: Header, path: str) -> int | None:
    """The header's crash count f (None: no crashes); RunInputError for a --crash that is not
    0 < f < n or that says otherwise than the record."""
    f = header_crash(header)
    given: int | None = getattr(args, "crash", None)
    check_crash(given, header.n)
    if given is not None and given != f:
        says = "no crashes" if f is None else f"crash={f}"
        raise RunInputError(
            f"--crash {given} contradicts {path}, whose run has {says}; drop --crash to resume it"
        )
    return f


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


def stopped_line(
    word: str,
    done: int,
    *,
    record: str | None,
    scheduler: str,
    lockstep: bool,
    seed: int | None = None,
    fix: bool = False,
) -> str:
    """The line a run stopped by a signal (`word`: "interrupted", "terminated") or a failed write
    prints: after which round, and how to go on (`fatswarm run --record R --resume`), or why it
    cannot be. `done`: the rounds (ended cycles, under an async model) its record holds.
    `fix`: something must be fixed first (a full disk). Shared by the lock step and the
    networked launcher, so that both say it alike."""
    after = f"{word} after {unit(scheduler)} {done}"
    if scheduler in ASYNC_NAMES:
        again = "" if seed is None else f" with --seed {seed}"
        return f"{after}; an async run cannot be resumed: run it again{again}"
    if not record:
        return f"{after} (no --record: nothing to resume)"
    mode = " --lockstep" if lockstep else ""
    then = "once that is fixed, go on" if fix else "go on"
    return f"{after}; {then} with `fatswarm run{mode} --record {shlex.quote(record)} --resume`"


def check_against_header(
    args: argparse.Namespace, header: Header, cap: int | None, path: str
) -> None:
    """Refuse (RunInputError, one line) a flag given with --resume that contradicts the record's
    header, naming the flag and both values; `cap`: the header's round cap, if it says one."""
    h = header
    checks: list[tuple[str, str, Any, Any, str]] = [
        ("-n", "n", args.n, h.n, f"n={h.n}"),
        ("-a", "a", args.a, h.a, f"a={_number(h.a)}"),
        ("--seed", "seed", args.seed, h.seed, f"seed={h.seed}"),
        ("--scheduler", "scheduler", args.scheduler, h.scheduler, f"scheduler={h.scheduler}"),
        ("--max-rounds", "max_rounds", args.max_rounds, cap, f"max_rounds={cap}"),
    ]
    if flag_given(args, "algorithm") and args.algorithm != header.algorithm_ref:
        raise RunInputError(
            f"--algorithm {args.algorithm} contradicts {path}, whose run has "
            f"algorithm {header.algorithm_ref}; drop --algorithm to resume it"
        )
    _check_params(args, header, path)
    for flag, dest, value, recorded, says in checks:
        if flag_given(args, dest) and recorded is not None and value != recorded:
            shown = _number(value) if isinstance(value, float) else value
            raise RunInputError(
                f"{flag} {shown} contradicts {path}, whose run has {says}; drop {flag} to resume it"
            )
    if args.init is not None:
        _check_init(args.init, h, path)
    elif flag_given(args, "start") and h.seed is not None:
        _check_start(args.start, h, path)


def _check_params(args: argparse.Namespace, header: Header, path: str) -> None:
    """Refuse a --param whose value is not the record's."""
    for name, text in parse_assignments(list(getattr(args, "param", []) or [])).items():
        recorded = header.params.get(name)
        if recorded is None or (str(recorded) != text and _as_number(text) != recorded):
            raise RunInputError(
                f"--param {name}={text} contradicts {path}, whose run has "
                f"{name}={recorded}; drop --param to resume it"
            )


def _check_init(init: str, header: Header, path: str) -> None:
    """Refuse an --init file whose start is not the record's."""
    h = header
    positions, _ = load_init(init)
    if len(positions) != h.n:
        raise RunInputError(
            f"--init {init} contradicts {path}, whose run has n={h.n} "
            f"(the file {len(positions)} robots); drop --init to resume it"
        )
    where = _first_difference(validate_configuration(positions), h.initial)
    if where is not None:
        robot, mine, theirs = where
        raise RunInputError(
            f"--init {init} contradicts {path}, whose run started "
            f"elsewhere (robot {robot} at {theirs}, not at {mine} as in the "
            "file); drop --init to resume it"
        )


def _check_start(kind: str, header: Header, path: str) -> None:
    """Refuse a --start kind whose start of the record's seed is not the record's start."""
    h = header
    assert h.seed is not None
    where = _first_difference(random_start(h.n, h.seed, kind, h.a), h.initial)
    if where is not None:
        robot, mine, theirs = where
        raise RunInputError(
            f"--start {kind} contradicts {path}, whose run did not start "
            f"from the {kind} start of seed {h.seed} (robot {robot} at "
            f"{theirs}, not at {mine}); drop --start to resume it"
        )


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
    "check_against_header",
    "drop_torn_end",
    "ended",
    "read_resumable",
    "recorded_crash",
    "recorded_fairness",
    "recorded_model",
    "recorded_non_rigid",
    "resolve_resume",
    "stopped_line",
]
