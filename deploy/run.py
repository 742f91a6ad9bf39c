"""`fatswarm run`: run a swarm, networked (default, deploy.launcher) or in one process (--lockstep).

Exit codes: 0 formed with no collision, 1 not formed (stalled or max_rounds, with or without
collisions), 2 bad input (one line on stderr), 3 formed but with collisions, 130 interrupted.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import secrets
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Final, TextIO

if TYPE_CHECKING:
    from fatswarm.agent.params import Params
    from fatswarm.agent.path import Points
    from fatswarm.coordinator.schedule import Scheduler
    from fatswarm.deploy.lockstep import RoundReport

EXIT_FORMED: Final = 0  # formed, and no robot was ever stopped by contact
EXIT_NOT_FORMED: Final = 1  # stalled or max_rounds, collisions or not
EXIT_BAD_INPUT: Final = 2
EXIT_FORMED_WITH_COLLISIONS: Final = 3  # formed, but not the collision-free formation
EXIT_INTERRUPTED: Final = 130
EXIT_CODES_HELP: Final = (
    f"exit codes: {EXIT_FORMED} formed with no collision; {EXIT_NOT_FORMED} not formed (stalled "
    f"or out of rounds); {EXIT_BAD_INPUT} bad input (one line on stderr says what to fix); "
    f"{EXIT_FORMED_WITH_COLLISIONS} formed, but with collisions (robots stopped at contact: not "
    f"the collision-free formation the paper guarantees); {EXIT_INTERRUPTED} interrupted."
)
DEFAULT_N: Final = 8
DEFAULT_A: Final = 4.0
DEFAULT_SCHEDULER: Final = "ssync"  # the paper's model
DEFAULT_START: Final = "clustered"  # needs SEC expansion, so every phase of the algorithm runs
PROGRESS_SECONDS: Final = 1.0  # at most one progress line per this many seconds


class RunInputError(ValueError):
    """A flag combination `fatswarm run` cannot use."""


def _optional_adder(module_name: str, function: str) -> Callable[[argparse.ArgumentParser], None]:
    """`module.function` if the module exists and defines it, else a no-op (parts land later)."""
    try:
        if importlib.util.find_spec(module_name) is None:
            return lambda p: None
    except ModuleNotFoundError:
        return lambda p: None
    adder = getattr(importlib.import_module(module_name), function, None)
    return adder if callable(adder) else (lambda p: None)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm run` (plus the launcher's and dashboard's, once those modules exist)."""
    from fatswarm.coordinator.schedule import NAMES
    from fatswarm.world.starts import KINDS

    p.epilog = EXIT_CODES_HELP
    p.add_argument(
        "--lockstep",
        action="store_true",
        help="run every robot in this one process, in lock step (no Zenoh)",
    )
    p.add_argument("-n", type=int, default=None, metavar="N",
                   help=f"number of robots (default {DEFAULT_N}; with --init, taken from the file)")
    p.add_argument("-a", type=float, default=None, metavar="A",
                   help=f"least side of the polygon, > 3 (default {DEFAULT_A:g}, or the --init "
                   "file's 'a')")
    p.add_argument("--seed", type=int, default=None, metavar="S",
                   help="seed of the start, frames and scheduler (default: random, printed)")
    p.add_argument("--init", metavar="PATH",
                   help='start from a JSON file {"positions": [[x, y], ...], "a": 4.0}')
    p.add_argument("--start", choices=KINDS, default=DEFAULT_START,
                   help=f"kind of random start without --init (default {DEFAULT_START}: "
                   "needs SEC expansion)")
    p.add_argument("--scheduler", choices=NAMES, default=DEFAULT_SCHEDULER,
                   help=f"who is active each round (default {DEFAULT_SCHEDULER})")
    p.add_argument("--schedule", metavar="PATH",
                   help='scripted scheduler: JSON {"rounds": [[0, 2], [1], ...]} or a run record')
    p.add_argument("--fairness", type=int, default=None, metavar="K",
                   help="ssync/centralized: every robot active at least once in every K rounds "
                   "(default 2n)")
    p.add_argument("--max-rounds", type=int, default=None, metavar="R",
                   help="stop after R rounds (default: 10 (n + 10) for fsync, 40 (n + 10) for "
                   "ssync, 10 n (n + 10) otherwise)")
    p.add_argument("--record", metavar="PATH", help="write the run record (JSON Lines) to PATH")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress lines while running (the summary is still printed)")
    _optional_adder("fatswarm.deploy.launcher", "add_network_arguments")(p)
    # The dashboard's run flags (--no-dashboard, --svg): `add_run_arguments`, because the CLI
    # would hand an `add_dashboard_arguments` to `fatswarm dashboard` itself.
    _optional_adder("fatswarm.deploy.dashboard", "add_run_arguments")(p)


def _fail(message: str) -> int:
    print(f"fatswarm run: {message}", file=sys.stderr)
    return EXIT_BAD_INPUT


def main(args: argparse.Namespace) -> int:
    """Run the swarm as asked; returns the exit code."""
    if not args.lockstep:
        return _networked(args)
    return run_lockstep_command(args)


def _networked(args: argparse.Namespace) -> int:
    try:
        launcher = importlib.import_module("fatswarm.deploy.launcher")
    except ModuleNotFoundError as exc:
        if exc.name != "fatswarm.deploy.launcher":
            raise
        launcher = None
    run_networked: Any = getattr(launcher, "run_networked", None)
    if run_networked is None:
        return _fail("the networked emulator is not available in this build; use --lockstep")
    code: int = run_networked(args)
    return code


@dataclass(frozen=True, slots=True)
class RunSetup:
    """What the flags of `fatswarm run` ask for, checked: the start, parameters and scheduler."""

    seed: int
    params: Params
    initial: Points
    scheduler: Scheduler
    max_rounds: int


def input_errors() -> tuple[type[Exception], ...]:
    """The exceptions `resolve_run` raises for bad input (each message says what to fix)."""
    from fatswarm.agent.params import ParamsError
    from fatswarm.agent.tolerance import UnsupportedInputError
    from fatswarm.coordinator.schedule import ScheduleError
    from fatswarm.world.physics import InvalidConfigurationError
    from fatswarm.world.starts import InitFileError

    return (ParamsError, InitFileError, ScheduleError, InvalidConfigurationError,
            UnsupportedInputError, RunInputError)


def resolve_start(
    init: str | None, n: int | None, a: float | None, seed: int, kind: str
) -> tuple[Params, Points]:
    """The parameters and (n, 2) start that `--init` or `-n`/`-a`/`--seed`/`--start` ask for,
    valid and inside the supported range (agent/tolerance.py); raises one of `input_errors()`.

    Shared by `fatswarm run` and `fatswarm world`, so both refuse the same start the same way.
    """
    import numpy as np

    from fatswarm.agent.params import Params
    from fatswarm.agent.tolerance import check_supported
    from fatswarm.world.physics import validate_configuration
    from fatswarm.world.starts import load_init, random_start

    if init is not None:
        initial, file_a = load_init(init)  # finite numbers, as check_supported needs
        if n is not None and n != len(initial):
            raise RunInputError(
                f"-n {n} disagrees with the {len(initial)} robots of {init}; drop -n"
            )
        side = a if a is not None else (file_a if file_a is not None else DEFAULT_A)
        params = Params(len(initial), side)
    else:
        params = Params(DEFAULT_N if n is None else n, DEFAULT_A if a is None else a)
        # the side first: a random start is drawn at its scale (a = 1e308 would overflow it)
        check_supported(np.zeros((params.n, 2)), params.a)
        initial = random_start(params.n, seed, kind, params.a)
    check_supported(initial, params.a)
    return params, validate_configuration(initial)


def resolve_run(args: argparse.Namespace, seed: int) -> RunSetup:
    """Build the run the flags describe (shared by lockstep and networked runs, so both refuse
    the same input with the same message); raises one of `input_errors()`."""
    from fatswarm.coordinator.schedule import make_scheduler
    from fatswarm.deploy.lockstep import default_max_rounds

    params, initial = resolve_start(args.init, args.n, args.a, seed, args.start)
    if args.scheduler != "scripted" and args.schedule is not None:
        raise RunInputError("--schedule only goes with --scheduler scripted")
    if args.max_rounds is not None and args.max_rounds < 1:
        raise RunInputError(f"--max-rounds must be at least 1, got {args.max_rounds}")
    scheduler = make_scheduler(args.scheduler, params.n, seed, args.schedule, args.fairness)
    max_rounds = args.max_rounds or default_max_rounds(params.n, args.scheduler)
    return RunSetup(seed, params, initial, scheduler, max_rounds)


def run_lockstep_command(args: argparse.Namespace, out: TextIO | None = None) -> int:
    """`fatswarm run --lockstep`: build the run from the flags, run it, print the summary."""
    from fatswarm.deploy.lockstep import run_lockstep
    from fatswarm.world.physics import InvalidConfigurationError
    from fatswarm.world.record import RecordFormatError, RecordWriter

    out = sys.stdout if out is None else out
    seed_given = args.seed is not None
    seed: int = args.seed if seed_given else secrets.randbelow(2**31)
    bad_input: tuple[type[Exception], ...] = (*input_errors(), RecordFormatError)
    try:
        setup = resolve_run(args, seed)
        record = RecordWriter(args.record) if args.record else None
    except bad_input as exc:
        return _fail(str(exc))
    params, initial, scheduler, max_rounds = (
        setup.params, setup.initial, setup.scheduler, setup.max_rounds
    )

    if not seed_given and not args.quiet:
        print(f"seed {seed} (pass --seed {seed} to repeat this run)", file=sys.stderr)
    on_round = None if args.quiet else _progress_printer(max_rounds)
    try:
        result = run_lockstep(
            initial,
            params,
            scheduler,
            seed=seed,
            max_rounds=max_rounds,
            record=record,
            on_round=on_round,
        )
    except InvalidConfigurationError as exc:
        return _fail(f"invalid start: {exc}")
    finally:
        if record is not None:
            record.close()

    outcome = Outcome(
        status=result.status,
        rounds=result.rounds,
        collisions=result.collisions,
        n=params.n,
        a=params.a,
        seed=seed,
        scheduler=scheduler.name,
        epochs=result.epochs,
        moves=result.moves,
        total_distance=result.total_distance,
    )
    print(summary(outcome), file=out)
    if args.record:
        print(f"record: {args.record}", file=out)
    svg = getattr(args, "svg", None)  # the dashboard's flag, when deploy.dashboard is there
    if svg:
        from fatswarm.deploy.dashboard import Frame, save_svg

        final = Frame(
            round=result.rounds,
            n=params.n,
            a=params.a,
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
            return _fail(f"cannot write {svg}: {exc.strerror}")
        print(f"svg: {svg}", file=out)
    return exit_code(outcome)


@dataclass(frozen=True, slots=True)
class Outcome:
    """How a finished run ended (lockstep result or networked record): what the summary says."""

    status: str  # "formed" | "stalled" | "max_rounds"
    rounds: int
    collisions: int  # robots stopped at contact, over the whole run
    n: int
    a: float
    seed: int | None
    scheduler: str
    epochs: int | None  # None when the record does not say
    moves: int
    total_distance: float


def exit_code_for(status: str, collisions: int) -> int:
    """0 only for a collision-free formation; formed through collisions is 3, not formed is 1."""
    if status != "formed":
        return EXIT_NOT_FORMED
    return EXIT_FORMED if collisions == 0 else EXIT_FORMED_WITH_COLLISIONS


def exit_code(outcome: Outcome) -> int:
    """The exit code of `fatswarm run` for this outcome (see EXIT_CODES_HELP)."""
    return exit_code_for(outcome.status, outcome.collisions)


def verdict(outcome: Outcome) -> str:
    """One line: formed or not, in how many rounds, and whether robots collided on the way."""
    k, rounds = outcome.collisions, outcome.rounds
    collisions = f"{k} collision{'' if k == 1 else 's'}"
    if outcome.status == "formed":
        if k == 0:
            return f"formed in {rounds} rounds, collision-free"
        return (f"formed in {rounds} rounds, but with {collisions}: not the collision-free "
                "formation the paper guarantees")
    if outcome.status == "stalled":
        head = f"not formed: stalled after {rounds} rounds"
    elif outcome.status == "max_rounds":
        head = f"not formed: stopped at the round limit ({rounds} rounds)"
    else:
        head = f"not formed: {outcome.status} after {rounds} rounds"
    return head if k == 0 else f"{head}, with {collisions}"


def summary(outcome: Outcome) -> str:
    """The summary both kinds of run print at the end: the verdict, the run, its figures."""
    o = outcome
    epochs = "?" if o.epochs is None else str(o.epochs)
    return (
        f"{verdict(o)}\n"
        f"n={o.n} a={o.a:g} seed={'?' if o.seed is None else o.seed} scheduler={o.scheduler}\n"
        f"rounds {o.rounds}  epochs {epochs}  moves {o.moves} ({o.moves / o.n:.2f} per robot)  "
        f"total distance {o.total_distance:.3f}  collisions {o.collisions}"
    )


def _progress_printer(max_rounds: int) -> Callable[[RoundReport], None]:
    """A round callback printing a progress line to stderr at most once per PROGRESS_SECONDS."""
    last = [time.monotonic()]

    def show(report: RoundReport) -> None:
        now = time.monotonic()
        if now - last[0] < PROGRESS_SECONDS:
            return
        last[0] = now
        p = report.progress
        print(
            f"round {report.round}/{max_rounds}  epochs {p.epochs}  moves {p.moves}  "
            f"distance {p.total_distance:.1f}  collisions {p.collisions}",
            file=sys.stderr,
            flush=True,
        )

    return show


__all__ = [
    "Outcome",
    "add_arguments",
    "exit_code",
    "exit_code_for",
    "main",
    "resolve_start",
    "run_lockstep_command",
    "summary",
    "verdict",
]
