"""`fatswarm hunt`: search for counterexamples to an algorithm on every core, shrink each one and
save it as files that `fatswarm run` replays exactly and `fatswarm replay` shows.

`deploy/hunt/search.py` draws, runs and classifies, `deploy/hunt/shrink.py` shrinks;
`deploy/hunt/pool.py` runs that in worker processes and saves the failures; this module reads the
flags and runs the hunt; `deploy/hunt/report.py` shows its progress and summary.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import secrets
import signal
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Final, TypeVar

from fatswarm.coordinator.schedule import NAMES
from fatswarm.deploy.engine.config import check_lights, check_non_rigid, input_errors
from fatswarm.deploy.flags import add_robot_model_arguments
from fatswarm.deploy.hunt.report import make_progress, outside_text, print_summary
from fatswarm.deploy.hunt.search import (
    SEED_BOUND,
    Hunt,
    HuntInputError,
    default_families,
    hunt_models,
    start_families,
)
from fatswarm.deploy.hunt.shrink import DEFAULT_SHRINK_RUNS
from fatswarm.deploy.sweep.batch_flags import (
    add_adversary_arguments,
    add_jobs_argument,
    add_max_rounds_argument,
    add_param_argument,
    add_quiet_argument,
    add_scheduler_argument,
    add_sizes_argument,
    jobs_of,
    stop_on_signals,
)
from fatswarm.deploy.sweep.executor import ClusterError, open_workers
from fatswarm.deploy.sweep.grid import (
    SweepInputError,
    params_text,
    parse_crash,
    parse_ints,
    parse_non_rigid,
    robot_models_of,
    split_values,
)
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.registry import DEFAULT as DEFAULT_ALGORITHM
from fatswarm.domain.registry import load_algorithm
from fatswarm.domain.seam import Configured, assumptions_of
from fatswarm.domain.words import counted, plural

if TYPE_CHECKING:
    from fatswarm.deploy.hunt.pool import Budget, Tally

T = TypeVar("T")

DEFAULT_SIZES: Final = "3..12"
DEFAULT_SECONDS: Final = 60.0  # the budget when neither --budget-runs nor --budget-seconds is given
DEFAULT_FAILURES: Final = 5
DEFAULT_OUT: Final = "hunt"
DESCRIPTION: Final = (
    "Search for counterexamples to an algorithm: lock-step runs from random and adversarial "
    "starts (near-symmetric, touching, lattices...), under the schedulers and robot models "
    "asked for, drawn from a seed, on every core. A failure is a collision, a stall, a run "
    "past its round cap, or a broken invariant (overlap; for uniform-circle, a robot leaving "
    "the smallest enclosing circle in FormUCircle). Each failure is shrunk (fewer robots, a "
    "shorter schedule, simpler coordinates) and saved in a folder of --out: start.json, "
    "schedule.json (round models: the active sets; an async case replays from its --seed, the "
    "adversary's delays being drawn from it), the command that replays it with `fatswarm "
    "run`, its record and summary.json. Docs: docs/hunt.md."
)
EPILOG: Final = (
    "Without a budget the hunt runs for 60 s. Lists: -n, --scheduler and --starts take a comma "
    "list and can be repeated (numbers also LOW..HIGH ranges), as in fatswarm sweep; --non-rigid "
    "and --crash take the sweep's values but one of them (every run of a hunt has it). exit "
    "codes: 0 nothing found (and no --out folder left behind); 1 failures found (each saved in "
    "--out), or a worker process died; 2 bad input, or an --out that cannot be written (one "
    "line on stderr says what to fix); 4 a failure could not be saved (a full disk); 130 "
    "interrupted (Ctrl-C: the failures saved so far stay); 141 standard output closed early; "
    "143 terminated."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm hunt`."""
    p.description = DESCRIPTION
    p.epilog = EPILOG
    p.add_argument(
        "--algorithm",
        default=DEFAULT_ALGORITHM,
        metavar="NAME",
        help=f"the algorithm hunted (default {DEFAULT_ALGORITHM}; a registered name, "
        "module:attribute or path/to/file.py:attribute)",
    )
    add_param_argument(p, "the algorithm")
    _add_search_arguments(p)
    add_robot_model_arguments(p, lists=True)
    _add_budget_arguments(p)
    _add_hunt_run_arguments(p)


def _add_search_arguments(p: argparse.ArgumentParser) -> None:
    """What the candidate runs are drawn from: models, adversary, sizes, start families, cap."""
    add_scheduler_argument(p, "to draw from", ", ".join(hunt_models()))
    add_adversary_arguments(p, lists=False)
    add_sizes_argument(p, "to draw from, e.g. 3..12 or 4,8", DEFAULT_SIZES)
    p.add_argument(
        "--starts",
        "--start",
        action="append",
        default=[],
        metavar="FAMILIES",
        help=f"start families to draw from: {', '.join(start_families())} (default: all but "
        "rows and stacked-rows, so that earlier hunts draw what they drew; --start, sweep's "
        "name, is the same flag)",
    )
    add_max_rounds_argument(p)


def _add_budget_arguments(p: argparse.ArgumentParser) -> None:
    """When the hunt stops drawing, and how much shrinking a failure may take."""
    p.add_argument(
        "--budget-runs",
        type=int,
        default=None,
        metavar="K",
        help="stop drawing after K candidate runs (reproducible from --seed; default none: "
        "the seconds' budget)",
    )
    p.add_argument(
        "--budget-seconds",
        type=float,
        default=None,
        metavar="S",
        help="stop drawing after S seconds (default 60 when no budget is given)",
    )
    p.add_argument(
        "--max-failures",
        type=int,
        default=DEFAULT_FAILURES,
        metavar="K",
        help=f"stop once K failures are found; each is shrunk and saved (default "
        f"{DEFAULT_FAILURES})",
    )
    p.add_argument(
        "--shrink-runs",
        type=int,
        default=DEFAULT_SHRINK_RUNS,
        metavar="K",
        help=f"runs one failure's shrinking may take (default {DEFAULT_SHRINK_RUNS})",
    )


def _add_hunt_run_arguments(p: argparse.ArgumentParser) -> None:
    """How the hunt runs: workers, seed, where failures go, progress."""
    add_jobs_argument(p)
    p.add_argument(
        "--seed",
        type=int,
        default=None,
        metavar="S",
        help="the hunt's seed: the same seed and run budget find the same failures "
        "(default: random, printed)",
    )
    p.add_argument(
        "--out",
        default=DEFAULT_OUT,
        metavar="DIR",
        help=f"where failures are saved, one folder each (default {DEFAULT_OUT}; a "
        "new or empty directory)",
    )
    add_quiet_argument(p)


def build_hunt(args: argparse.Namespace) -> Hunt:
    """The hunt the flags ask for, checked; raises HuntInputError or one of
    `config.input_errors()` with a line saying what to fix."""
    sizes = parse_ints(args.n or [DEFAULT_SIZES], "-n", least=1)
    models = _models(args.scheduler)
    families = _families(args.starts)
    non_rigid = _one("--non-rigid", args.non_rigid, parse_non_rigid(args.non_rigid))
    check_non_rigid(non_rigid)
    crash = _one("--crash", args.crash, parse_crash(args.crash))
    if args.max_rounds is not None and args.max_rounds < 1:
        raise HuntInputError(f"--max-rounds must be at least 1, got {args.max_rounds}")
    robot_models = robot_models_of(args)
    algorithm = load_algorithm(args.algorithm)
    texts = params_text(algorithm, args.param)
    hunt = Hunt(
        args.algorithm,
        texts,
        families,
        sizes,
        models,
        non_rigid,
        crash,
        args.max_rounds,
        robot_models,
        bool(getattr(args, "record_views", False)),
    )
    choices = hunt.choices()
    if not choices:
        least = max(2, (crash or 0) + 1)
        asked = ",".join(args.n) or DEFAULT_SIZES
        raise HuntInputError(
            f"no start family asked for builds an n of -n {asked} that is at "
            f"least {least}; widen -n"
        )
    # an n the algorithm refuses, --lights for an algorithm without lights: now
    settings = [
        Configured.of(algorithm, n, dict(texts))
        for n in sorted({n for _, ns in choices for n in ns})
    ]
    for robot_model in robot_models:
        check_lights(robot_model, settings[0])
    return hunt


def _one(flag: str, given: Sequence[str], values: tuple[T, ...]) -> T:
    """The one value of a flag that takes the sweep's lists but one value in a hunt (every run
    has it); HuntInputError for more."""
    if len(values) > 1:
        raise HuntInputError(
            f"{flag} takes one value in a hunt (every run has it), got {','.join(given)}: "
            "hunt once per value (a sweep takes the list)"
        )
    return values[0]


def _models(given: Sequence[str]) -> tuple[str, ...]:
    """The --scheduler models asked for (default: every one a hunt takes); HuntInputError."""
    usable = hunt_models()
    models = split_values(given) or usable
    for name in models:
        if name not in usable:
            why = "needs a schedule file" if name in NAMES else "is not a scheduler"
            raise HuntInputError(f"--scheduler {name} {why}; a hunt takes {', '.join(usable)}")
    return models


def _families(given: Sequence[str]) -> tuple[str, ...]:
    """The --starts families asked for (default: `default_families`); HuntInputError."""
    known = start_families()
    families = split_values(given) or default_families()
    for family in families:
        if family not in known:
            raise HuntInputError(
                f"--starts {family}: not a start family; choose from {', '.join(known)}"
            )
    return families


def build_budget(args: argparse.Namespace) -> Budget:
    """The budget the flags ask for; raises HuntInputError."""
    # the pool brings the whole lock-step engine and multiprocessing: the CLI imports this
    # module to build its parser
    from fatswarm.deploy.hunt.pool import Budget

    if args.budget_runs is not None and args.budget_runs < 1:
        raise HuntInputError(f"--budget-runs must be at least 1, got {args.budget_runs}")
    seconds = args.budget_seconds
    if seconds is not None and not (seconds > 0 and seconds < float("inf")):
        raise HuntInputError(f"--budget-seconds must be a finite number > 0, got {seconds:g}")
    if args.budget_runs is None and seconds is None:
        seconds = DEFAULT_SECONDS
    if args.max_failures < 1:
        raise HuntInputError(f"--max-failures must be at least 1, got {args.max_failures}")
    if args.shrink_runs < 1:
        raise HuntInputError(f"--shrink-runs must be at least 1, got {args.shrink_runs}")
    return Budget(args.budget_runs, seconds, args.max_failures, args.shrink_runs)


def main(args: argparse.Namespace) -> int:
    """`fatswarm hunt`: hunt, save the failures, print the summary; the exit code. An --out the
    hunt created and left empty (nothing found) is removed."""
    # the pools bring the whole lock-step engine and multiprocessing: the CLI imports this
    # module to build its parser
    from fatswarm.deploy.hunt.pool import check_out

    refused: tuple[type[Exception], ...] = (SweepInputError, *input_errors())
    try:
        hunt = build_hunt(args)
        budget = build_budget(args)
        jobs = jobs_of(args.jobs)
        if args.seed is not None and not 0 <= args.seed < 2**63:
            raise HuntInputError(f"--seed must be a whole number >= 0, got {args.seed}")
        check_out(args.out)
        created = make_out(args.out)
    except refused as exc:
        return _fail(str(exc))
    try:
        return _hunt(args, hunt, budget, jobs)
    finally:
        if created:
            drop_if_empty(args.out)


def make_out(out: str) -> bool:
    """Make the --out directory if it is missing (True: made here); HuntInputError, one line,
    if it cannot be made or written in."""
    made = not os.path.isdir(out)
    try:
        os.makedirs(out, exist_ok=True)
    except OSError as exc:
        where = os.path.dirname(os.path.abspath(out))
        raise HuntInputError(
            f"--out {out}: cannot make it in {where}: {exc.strerror or exc}; name a directory "
            "you can write in"
        ) from None
    if not os.access(out, os.W_OK | os.X_OK):
        raise HuntInputError(f"--out {out}: cannot write in it; name a directory you can write in")
    return made


def drop_if_empty(out: str) -> None:
    """Remove the --out directory if nothing was saved in it."""
    with contextlib.suppress(OSError):  # not empty (or gone): it stays as it is
        os.rmdir(out)


def _hunt(args: argparse.Namespace, hunt: Hunt, budget: Budget, jobs: int) -> int:
    """Run the hunt the flags asked for, into the --out directory; the exit code."""
    from fatswarm.deploy.hunt.pool import run_hunt
    from fatswarm.deploy.sweep.pool import WorkerDiedError

    seed = args.seed if args.seed is not None else secrets.randbelow(SEED_BOUND)
    progress = make_progress(budget, quiet=args.quiet)
    try:
        with open_workers(jobs, args.cluster) as workers:
            if not args.quiet:
                _say(_plan_text(hunt, budget, seed, workers.where, args.out))
                if _outside(hunt):  # the hunt goes ahead: that is the experiment
                    _say(_outside(hunt))
            with stop_on_signals() as stopped, progress:
                tally, complete = run_hunt(
                    hunt, seed, budget, workers, args.out, progress.show, lambda: bool(stopped[0])
                )
    except ClusterError as exc:
        return _fail(str(exc))
    except WorkerDiedError as exc:
        _say(f"fatswarm hunt: {exc}; the failures saved so far stay in {args.out}")
        return ExitCode.NOT_FORMED
    except OSError as exc:  # a full disk, a permission, while saving a failure
        _say(f"fatswarm hunt: cannot save a failure in {args.out}: {exc.strerror or exc}")
        return ExitCode.RECORD_FAILED
    if not complete:
        word = "interrupted" if stopped[0] == signal.SIGINT else "terminated"
        _say(
            f"{word}: {counted(tally.runs, 'run')}, {counted(len(tally.saved), 'failure')} "
            f"saved in {args.out}; "
            f"rerun with --seed {seed} to hunt again"
        )
        return ExitCode.INTERRUPTED if stopped[0] == signal.SIGINT else ExitCode.TERMINATED
    print_summary(tally, sys.stdout, _outside(hunt))
    _say(_end_text(tally, seed, args.out))
    return ExitCode.NOT_FORMED if tally.saved else ExitCode.OK


def _outside(hunt: Hunt) -> str:
    """Which of the hunt's draws are outside its algorithm's assumptions ('' if none)."""
    algorithm = load_algorithm(hunt.algorithm)  # loaded and checked before the hunt began
    return outside_text(
        algorithm.name, assumptions_of(algorithm), hunt.models, hunt.robot_models, hunt.non_rigid
    )


def _plan_text(hunt: Hunt, budget: Budget, seed: int, where: str, out: str) -> str:
    limits = []
    if budget.runs is not None:
        limits.append(counted(budget.runs, "run"))
    if budget.seconds is not None:
        limits.append(f"{budget.seconds:g} s")
    extra = "".join(
        [
            f", non-rigid {hunt.non_rigid:g}" if hunt.non_rigid is not None else "",
            f", crash {hunt.crash}" if hunt.crash is not None else "",
            _robot_models_text(hunt),
        ]
    )
    families = counted(len(hunt.families), "start family", "start families")
    return (
        f"hunt: seed {seed}, {hunt.algorithm}, n {_sizes(hunt.sizes)}, "
        f"{', '.join(hunt.models)}{extra}; {families}; budget "
        f"{' or '.join(limits)}, at most {counted(budget.failures, 'failure')} into {out}/; "
        f"on {where}"
    )


def _robot_models_text(hunt: Hunt) -> str:
    """The robot models of the plan line (`RobotModel.short`), "" for the paper's alone."""
    if all(m.is_paper for m in hunt.robot_models):
        return ""
    words = [m.short for m in hunt.robot_models]
    return f"; {plural('robot model', len(words))} {', '.join(words)}"


def _sizes(sizes: Sequence[int]) -> str:
    if len(sizes) > 2 and list(sizes) == list(range(sizes[0], sizes[-1] + 1)):
        return f"{sizes[0]}..{sizes[-1]}"
    return ",".join(map(str, sizes))


def _end_text(tally: Tally, seed: int, out: str) -> str:
    if not tally.saved:
        return (
            f"nothing found in {counted(tally.runs, 'run')} "
            f"({counted(tally.refused, 'start')} refused as unsupported); hunt seed {seed}"
        )
    first = tally.saved[0]
    return (
        f"{counted(len(tally.saved), 'failure')} saved in {out}/ (hunt seed {seed}); "
        "replay one with\n"
        f"  cd {first.folder} && {first.summary['command']}\n"
        f"  fatswarm replay {os.path.join(first.folder, 'record.jsonl')}"
    )


def _say(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _fail(message: str) -> int:
    _say(f"fatswarm hunt: {message}")
    return ExitCode.BAD_INPUT


__all__ = ["add_arguments", "build_budget", "build_hunt", "main"]
