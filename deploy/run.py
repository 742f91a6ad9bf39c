"""`fatswarm run`: run a swarm, networked (default, deploy.launcher) or in one process (--lockstep).

Exit codes (`ExitCode`): 0 formed with no collision, 1 not formed (stalled or max_rounds, with or
without collisions), 2 bad input (one line on stderr), 3 formed but with collisions, 130
interrupted (SIGINT), 141 standard output closed early (a broken pipe), 143 terminated (SIGTERM).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import math
import os
import secrets
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Final, TextIO

from fatswarm.deploy.config import (
    DEFAULT_A,
    DEFAULT_N,
    DEFAULT_SCHEDULER,
    DEFAULT_START,
    RunConfig,
    RunInputError,
    RunSetup,
    input_errors,
    resolve_start,
)
from fatswarm.deploy.estimate import (
    ESTIMATE_FROM_N,
    ESTIMATE_FROM_S,
    estimate_lockstep,
    estimate_text,
    eta_text,
)
from fatswarm.domain.outcome import ExitCode, Status, exit_code_for

if TYPE_CHECKING:
    from fatswarm.deploy.lockstep import RoundReport


EXIT_FORMED: Final = ExitCode.FORMED
EXIT_NOT_FORMED: Final = ExitCode.NOT_FORMED
EXIT_BAD_INPUT: Final = ExitCode.BAD_INPUT
EXIT_FORMED_WITH_COLLISIONS: Final = ExitCode.FORMED_WITH_COLLISIONS
EXIT_INTERRUPTED: Final = ExitCode.INTERRUPTED
EXIT_BROKEN_PIPE: Final = ExitCode.BROKEN_PIPE
EXIT_TERMINATED: Final = ExitCode.TERMINATED
EXIT_CODES_HELP: Final = (
    f"exit codes: {EXIT_FORMED:d} formed with no collision; {EXIT_NOT_FORMED:d} not formed "
    f"(stalled or out of rounds; networked: or a part's process died, one line says which); "
    f"{EXIT_BAD_INPUT:d} bad input (one line on stderr says what to "
    f"fix); {EXIT_FORMED_WITH_COLLISIONS:d} formed, but with collisions (robots stopped at "
    f"contact: not the collision-free formation the paper guarantees); "
    f"{ExitCode.RECORD_FAILED:d} the run record could not be written (disk full, permissions: "
    f"the run stopped; --resume goes on once fixed); {EXIT_INTERRUPTED:d} "
    f"interrupted (Ctrl-C); {EXIT_BROKEN_PIPE:d} standard output closed early (e.g. | head); "
    f"{EXIT_TERMINATED:d} terminated (SIGTERM)."
)
PROGRESS_SECONDS: Final = 1.0  # at most one progress line per this many seconds


GIVEN: Final = "_given"  # the namespace attribute listing the flags given (`_StoreGiven`)
TRACKED: Final = ("scheduler", "start")  # flags with a default other than None: `_StoreGiven`


class _StoreGiven(argparse.Action):
    """Store the value and note that the flag was given: --resume refuses a given flag that
    contradicts the record, while a default one never does (its default may be the record's)."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        setattr(namespace, self.dest, values)
        setattr(namespace, GIVEN, (*getattr(namespace, GIVEN, ()), self.dest))


def flag_given(args: argparse.Namespace, dest: str) -> bool:
    """Whether the user gave the flag of `dest`: listed by `_StoreGiven` for the TRACKED ones,
    else not None (their default)."""
    if dest in TRACKED:
        return dest in getattr(args, GIVEN, ())
    return getattr(args, dest, None) is not None


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm run`, the launcher's (networked) and the dashboard's among them."""
    from fatswarm.coordinator.schedule import NAMES
    from fatswarm.deploy.dashboard import add_run_arguments
    from fatswarm.deploy.launcher import add_network_arguments
    from fatswarm.world.starts import KINDS

    p.epilog = EXIT_CODES_HELP
    p.add_argument(
        "--lockstep",
        action="store_true",
        help="run every robot in this one process, in lock step (no Zenoh; refuses the "
        "networked-run flags)",
    )
    p.add_argument("-n", type=int, default=None, metavar="N",
                   help=f"number of robots (default {DEFAULT_N}; with --init, taken from the file)")
    p.add_argument("-a", type=float, default=None, metavar="A",
                   help=f"the paper's least side of the polygon, > 3: --param a=A (default "
                   f"{DEFAULT_A:g}, or the --init file's 'a'); random starts are drawn at this "
                   "scale")
    add_algorithm_arguments(p)
    p.add_argument("--seed", type=int, default=None, metavar="S",
                   help="seed of the start, frames and scheduler (default: random, printed)")
    p.add_argument("--init", metavar="PATH",
                   help='start from a JSON file {"positions": [[x, y], ...], "a": 4.0}')
    p.add_argument("--start", choices=KINDS, default=DEFAULT_START, action=_StoreGiven,
                   help=f"kind of random start without --init (default {DEFAULT_START}: "
                   "needs SEC expansion)")
    p.add_argument("--scheduler", choices=NAMES, default=DEFAULT_SCHEDULER, action=_StoreGiven,
                   help=f"who is active each round (default {DEFAULT_SCHEDULER}); async, "
                   "async-slowest: no rounds, robots on their own clocks in virtual time, the "
                   "adversary's delays random or slowest robot last")
    p.add_argument("--schedule", metavar="PATH",
                   help='scripted scheduler: JSON {"rounds": [[0, 2], [1], ...]} or a run record')
    p.add_argument("--fairness", type=int, default=None, metavar="K",
                   help="ssync/centralized: every robot active at least once in every K rounds "
                   "(default 2n)")
    p.add_argument("--max-rounds", type=int, default=None, metavar="R",
                   help="stop after R rounds (default: 10 (n + 10) for fsync, 40 (n + 10) for "
                   "ssync, 40 n (n + 10) ended cycles for the async models, 10 n (n + 10) "
                   "otherwise)")
    p.add_argument("--non-rigid", type=float, default=None, metavar="DELTA",
                   help="non-rigid moves: the adversary may stop a move anywhere after the robot "
                   "has travelled DELTA (> 0, robot radii; e.g. 1) or at its end, drawn from the "
                   "seed (default: rigid moves)")
    p.add_argument("--crash", type=int, default=None, metavar="F",
                   help="F robots (0 < F < n) crash at rounds the adversary draws from the seed "
                   "and stay for good as still obstacles; the goal is then judged on the live "
                   "robots (default: none)")
    p.add_argument("--record", metavar="PATH",
                   help="write the run record (JSON Lines) to PATH (a new file, unless --force)")
    p.add_argument("--force", action="store_true",
                   help="let --record overwrite an existing file")
    p.add_argument("--resume", action="store_true",
                   help="continue the unfinished run of the --record file after its last round, "
                   "appending to it: n, a, seed, scheduler, start and round cap are the record's "
                   "(a flag that contradicts them is refused)")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress lines while running (the summary is still printed)")
    p.add_argument("--json", action="store_true",
                   help="print the summary as one JSON object on stdout (progress stays on "
                   "stderr; no live dashboard)")
    add_network_arguments(p)
    # The dashboard's run flags (--no-dashboard, --svg): `add_run_arguments`, because the CLI
    # would hand an `add_dashboard_arguments` to `fatswarm dashboard` itself.
    add_run_arguments(p)


def add_algorithm_arguments(p: argparse.ArgumentParser, *, params: bool = True) -> None:
    """`--algorithm` (and `--param`): which algorithm the robots run, with what parameters."""
    from fatswarm.domain.registry import DEFAULT

    p.add_argument("--algorithm", default=DEFAULT, metavar="NAME", action=_StoreGiven,
                   help=f"the algorithm every robot runs: a registered name (`fatswarm "
                   f"algorithms` lists them; default {DEFAULT}) or module:attribute or "
                   "path/to/file.py:attribute of your own (docs/algorithms.md)")
    if params:
        p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                       help="set one of the algorithm's parameters (repeat for more; "
                       "`fatswarm algorithms` lists them)")


def _fail(message: str) -> ExitCode:
    print(f"fatswarm run: {message}", file=sys.stderr)
    return EXIT_BAD_INPUT


def main(args: argparse.Namespace) -> int:
    """Run the swarm as asked; returns the exit code."""
    if not args.lockstep:
        return _networked(args)
    return run_lockstep_command(args)


def _networked(args: argparse.Namespace) -> int:
    from fatswarm.deploy.launcher import run_networked

    return run_networked(args)


def networked_flags_given(args: argparse.Namespace) -> list[str]:
    """The networked-only flags (deploy.launcher's) that differ from their defaults in `args`."""
    flags: tuple[tuple[str, str, object], ...] = getattr(args, "_networked_flags", ())
    return [flag for flag, dest, default in flags if getattr(args, dest, default) != default]


def check_lockstep_flags(args: argparse.Namespace) -> None:
    """Refuse networked-only flags in a lockstep run rather than ignore them (RunInputError)."""
    given = networked_flags_given(args)
    if given:
        only = "is" if len(given) == 1 else "are"
        raise RunInputError(f"{', '.join(given)} {only} for networked runs only: drop "
                            f"{'it' if len(given) == 1 else 'them'} or --lockstep")


def check_outputs(args: argparse.Namespace) -> None:
    """Refuse a --record or --svg that cannot be written, before anything runs (RunInputError).

    An existing record is overwritten only with --force (--resume continues it).
    """
    record: str | None = args.record
    resume = bool(getattr(args, "resume", False))
    if resume and not record:
        raise RunInputError("--resume continues a run record: name it with --record PATH")
    if record:
        check_writable("--record", record)
        if resume and args.force:
            raise RunInputError("--resume continues the --record file, --force overwrites it: "
                                "pass one of them")
        if os.path.exists(record) and not os.path.isfile(record):
            raise RunInputError(f"--record {record} exists and is not a regular file (a device, "
                                "a pipe...); name a file")
        if os.path.exists(record) and not (args.force or resume):
            raise RunInputError(f"--record {record} exists; pass --force to overwrite it")
    svg: str | None = getattr(args, "svg", None)  # the dashboard's flag
    if svg:
        check_writable("--svg", svg)


def check_writable(flag: str, path: str) -> None:
    """Refuse `path` for `flag` if it is a directory or its directory is missing or read-only."""
    if os.path.isdir(path):
        raise RunInputError(f"{flag} {path} is a directory; name a file")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise RunInputError(f"{flag} {path}: the directory {folder} does not exist; create it "
                            "first")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise RunInputError(f"{flag} {path}: cannot write in {folder}")


def check_seconds(flag: str, value: float, *, zero_ok: bool) -> None:
    """Refuse a duration flag that is not finite, or not > 0 (>= 0 if `zero_ok`)."""
    if not math.isfinite(value) or value < 0 or (value == 0 and not zero_ok):
        bound = ">= 0" if zero_ok else "> 0"
        raise RunInputError(f"{flag} must be a finite number of seconds {bound}, got {value:g}")


def resolve_run(args: argparse.Namespace, seed: int) -> RunSetup:
    """Build the run the flags describe (shared by lockstep and networked runs, so both refuse
    the same input with the same message); raises one of `input_errors()`."""
    check_outputs(args)
    if getattr(args, "resume", False):
        from fatswarm.deploy.resume import resolve_resume

        return resolve_resume(args)
    return RunConfig.from_args(args, seed).resolve()


def run_lockstep_command(args: argparse.Namespace, out: TextIO | None = None) -> int:
    """`fatswarm run --lockstep`: build the run from the flags, run it, print the summary."""
    from fatswarm.deploy.lockstep import HistoryMismatchError, run_lockstep
    from fatswarm.domain.adversary import ASYNC_NAMES
    from fatswarm.domain.seam import AlgorithmFailure
    from fatswarm.world.physics import InvalidConfigurationError
    from fatswarm.world.record import RecordFormatError, RecordWriteError, RecordWriter

    out = sys.stdout if out is None else out
    seed_given = args.seed is not None
    seed: int = args.seed if seed_given else secrets.randbelow(2**31)
    bad_input: tuple[type[Exception], ...] = (*input_errors(), RecordFormatError)
    try:
        check_lockstep_flags(args)
        setup = resolve_run(args, seed)
        resumed = setup.resumed
        if resumed is not None and setup.scheduler.name in ASYNC_NAMES:
            raise RunInputError(f"--resume: a {setup.scheduler.name} run cannot be resumed yet; "
                                "run it again with its --seed: a lock-step run repeats exactly")
        # --resume appends after the committed rounds: nothing there is ever cut or rewritten
        record = RecordWriter(args.record, append=resumed is not None) if args.record else None
    except bad_input as exc:
        return _fail(str(exc))
    params, initial, scheduler, max_rounds, seed = (
        setup.params, setup.initial, setup.scheduler, setup.max_rounds, setup.seed
    )

    forecast = estimate_lockstep(params.n, scheduler.name, max_rounds)
    if not args.quiet:
        if not seed_given and resumed is None:
            print(f"seed {seed} (pass --seed {seed} to repeat this run)", file=sys.stderr)
        if params.n >= ESTIMATE_FROM_N or forecast.seconds >= ESTIMATE_FROM_S:
            print(estimate_text(forecast, params.n, record=bool(args.record)), file=sys.stderr,
                  flush=True)
    on_round = None if args.quiet else _progress_printer(max_rounds, forecast.rounds)
    try:
        result = run_lockstep(
            initial,
            params,
            scheduler,
            seed=seed,
            max_rounds=max_rounds,
            record=record,
            on_round=on_round,
            history=None if resumed is None else resumed.rounds,
            algorithm_ref=setup.algorithm_ref,
            header_extra=({} if setup.config is None
                          else setup.config.header_extra(networked=False,
                                                       n=setup.params.n)),
            non_rigid=setup.non_rigid,
            crash=setup.crash,
        )
    except InvalidConfigurationError as exc:
        return _fail(f"invalid start: {exc}")
    except AlgorithmFailure as exc:  # the record holds every round before it
        print(f"fatswarm run: {exc}", file=sys.stderr)
        return ExitCode.NOT_FORMED
    except RecordWriteError as exc:  # the rounds written stay; --resume goes on from them
        print(f"fatswarm run: {exc}; the run stopped (resume it with --resume once fixed)",
              file=sys.stderr)
        return ExitCode.RECORD_FAILED
    except HistoryMismatchError as exc:  # refused before anything was appended
        return _fail(f"--resume: {args.record} cannot be continued exactly in lock step: {exc} "
                     "(resume it with the run's own --fairness or --schedule, or networked if "
                     "it ran so)")
    finally:
        if record is not None:
            with contextlib.suppress(RecordWriteError):  # said above, if it matters
                record.close()

    outcome = Outcome(
        status=result.status,
        rounds=result.rounds,
        collisions=result.collisions,
        n=params.n,
        a=side_of(params.values),
        seed=seed,
        scheduler=scheduler.name,
        epochs=result.epochs,
        moves=result.moves,
        total_distance=result.total_distance,
        algorithm=params.name,
        params=dict(params.values),
        time=result.time,
    )
    code = exit_code(outcome)
    svg: str | None = getattr(args, "svg", None)  # the dashboard's flag, when it is there
    if svg:
        from fatswarm.deploy.dashboard import Frame, save_svg

        final = Frame(
            round=result.rounds,
            n=params.n,
            algorithm=params.name,
            params=dict(params.values),
            figures=params.figures(result.positions),
            scheduler=scheduler.name,
            positions=result.positions,
            collisions_total=result.collisions,
            status=result.status,
            seed=seed,
            max_rounds=max_rounds,
            source="lockstep",
        )
        try:
            save_svg(final, svg)
        except OSError as exc:
            code = _fail(f"cannot write {svg}: {exc.strerror}")
            svg = None
    print_outcome(outcome, code, out, as_json=args.json, record=args.record, svg=svg)
    return code


def print_outcome(
    outcome: Outcome | None,
    code: int,
    out: TextIO,
    *,
    as_json: bool,
    record: str | None,
    svg: str | None,
) -> None:
    """Print the end of a run to `out`: the text summary and the files written, or (`as_json`)
    one JSON object. `outcome` None: the run ended without a result in its record."""
    if as_json:
        print(summary_json(outcome, code, record=record, svg=svg), file=out)
        return
    if outcome is not None:
        print(summary(outcome), file=out)
    if record:
        print(f"record: {record}", file=out)
    if svg:
        print(f"svg: {svg}", file=out)


@dataclass(frozen=True, slots=True)
class Outcome:
    """How a finished run ended (lockstep result or networked record): what the summary says."""

    status: str  # a world.outcome.Status that ended the run
    rounds: int
    collisions: int  # robots stopped at contact, over the whole run
    n: int
    a: float | None  # the paper's side, None for an algorithm without one
    seed: int | None
    scheduler: str
    epochs: int | None  # None when the record does not say
    moves: int
    total_distance: float
    algorithm: str = "uniform-circle"
    params: dict[str, Any] = dataclasses.field(default_factory=dict)
    time: float | None = None  # async models: the virtual time the run ended at


def side_of(values: Any) -> float | None:
    """The parameter `a` (the paper's side), None for an algorithm without one."""
    a = values.get("a")
    return float(a) if isinstance(a, (int, float)) and not isinstance(a, bool) else None


def exit_code(outcome: Outcome) -> ExitCode:
    """The exit code of `fatswarm run` for this outcome (see EXIT_CODES_HELP)."""
    return exit_code_for(outcome.status, outcome.collisions)


def verdict(outcome: Outcome) -> str:
    """One line: formed or not, in how many rounds, and whether robots collided on the way."""
    k, rounds = outcome.collisions, outcome.rounds
    collisions = f"{k} collision{'' if k == 1 else 's'}"
    if outcome.status == Status.FORMED:
        if k == 0:
            return f"formed in {rounds} rounds, collision-free"
        return (f"formed in {rounds} rounds, but with {collisions}: not the collision-free "
                "formation the paper guarantees")
    if outcome.status == Status.STALLED:
        head = f"not formed: stalled after {rounds} rounds"
    elif outcome.status == Status.MAX_ROUNDS:
        head = f"not formed: stopped at the round limit ({rounds} rounds)"
    else:
        head = f"not formed: {outcome.status} after {rounds} rounds"
    return head if k == 0 else f"{head}, with {collisions}"


def summary(outcome: Outcome) -> str:
    """The summary both kinds of run print at the end: the verdict, the run, its figures."""
    o = outcome
    epochs = "?" if o.epochs is None else str(o.epochs)
    values = o.params or ({"a": o.a} if o.algorithm == "uniform-circle" else {})
    shown = "".join(f" {k}={v:g}" if isinstance(v, float) else f" {k}={v}"
                    for k, v in values.items())
    named = "" if o.algorithm == "uniform-circle" else f" algorithm={o.algorithm}"
    return (
        f"{verdict(o)}\n"
        f"n={o.n}{named}{shown} seed={'?' if o.seed is None else o.seed} "
        f"scheduler={o.scheduler}\n"
        f"rounds {o.rounds}  epochs {epochs}  moves {o.moves} ({o.moves / o.n:.2f} per robot)  "
        f"total distance {o.total_distance:.3f}  collisions {o.collisions}"
        + ("" if o.time is None else f"  virtual time {o.time:.3f}")
    )


def summary_json(
    outcome: Outcome | None, code: int, *, record: str | None = None, svg: str | None = None
) -> str:
    """The summary as one JSON object (`--json`): the outcome's figures, verdict, exit code and
    the files written; status "unfinished" (and no figures) when the run ended without a result."""
    fields: dict[str, Any] = {"status": "unfinished"}
    if outcome is not None:
        fields = {**dataclasses.asdict(outcome), "verdict": verdict(outcome)}
    fields.update(exit_code=int(code), record=record or None, svg=svg or None)
    return json.dumps(fields, allow_nan=False)


def _progress_printer(max_rounds: int, expected_rounds: int) -> Callable[[RoundReport], None]:
    """A round callback printing a progress line (with an ETA) to stderr at most once per
    PROGRESS_SECONDS."""
    start = time.monotonic()
    last = [start]

    def show(report: RoundReport) -> None:
        now = time.monotonic()
        if now - last[0] < PROGRESS_SECONDS:
            return
        last[0] = now
        p = report.progress
        rate = report.round / (now - start) if now > start else 0.0
        print(
            f"round {report.round}/{max_rounds}  epochs {p.epochs}  moves {p.moves}  "
            f"distance {p.total_distance:.1f}  collisions {p.collisions}  "
            f"{eta_text(report.round, rate, expected_rounds, max_rounds)}",
            file=sys.stderr,
            flush=True,
        )

    return show


__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_BROKEN_PIPE",
    "EXIT_FORMED",
    "EXIT_FORMED_WITH_COLLISIONS",
    "EXIT_INTERRUPTED",
    "EXIT_NOT_FORMED",
    "EXIT_TERMINATED",
    "ExitCode",
    "Outcome",
    "add_arguments",
    "check_outputs",
    "check_seconds",
    "check_writable",
    "exit_code",
    "exit_code_for",
    "main",
    "print_outcome",
    "resolve_start",
    "run_lockstep_command",
    "side_of",
    "summary",
    "summary_json",
    "verdict",
]
