"""`fatswarm run`: run a swarm, networked (default, deploy.net.launcher) or in one process
(--lockstep).

Exit codes (`ExitCode`): 0 formed with no collision, 1 not formed (stalled or max_rounds, with or
without collisions), 2 bad input (one line on stderr), 3 formed but with collisions, 4 the record
could not be written, 130 interrupted (SIGINT), 141 standard output closed early (a broken pipe),
143 terminated (SIGTERM).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import secrets
import sys
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Final, TextIO

from fatswarm.coordinator.schedule import NAMES
from fatswarm.deploy.commands.resume import drop_torn_end, resolve_resume, stopped_line
from fatswarm.deploy.engine.config import (
    DEFAULT_A,
    DEFAULT_N,
    DEFAULT_SCHEDULER,
    DEFAULT_START,
    RunConfig,
    RunInputError,
    RunSetup,
    input_errors,
)
from fatswarm.deploy.engine.estimate import (
    ESTIMATE_FROM_N,
    ESTIMATE_FROM_S,
    estimate_lockstep,
    estimate_text,
    eta_text,
)
from fatswarm.deploy.flags import (
    StoreGiven,
    Terminated,
    add_algorithm_arguments,
    add_robot_model_arguments,
    check_start_flags,
    check_writable,
)
from fatswarm.deploy.net.run_flags import add_network_arguments
from fatswarm.deploy.scenarios.starts import KINDS
from fatswarm.deploy.view import dashboard
from fatswarm.deploy.view.dashboard import Frame, save_svg
from fatswarm.deploy.view.summary import (
    Outcome,
    crashes_in,
    exit_code,
    print_outcome,
    side_of,
    unit,
)
from fatswarm.domain.adversary import ASYNC_NAMES
from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.seam import AlgorithmFailure
from fatswarm.world.physics import InvalidConfigurationError
from fatswarm.world.record import (
    Header,
    RecordFormatError,
    RecordWriteError,
    RecordWriter,
    Result,
    RoundEntry,
)

if TYPE_CHECKING:
    from fatswarm.deploy.engine.estimate import Estimate
    from fatswarm.deploy.engine.lockstep import RoundReport, RunResult


EXIT_CODES_HELP: Final = (
    f"exit codes: {ExitCode.FORMED:d} formed with no collision; {ExitCode.NOT_FORMED:d} not formed "
    f"(stalled or out of rounds; networked: or a part's process died, one line says which); "
    f"{ExitCode.BAD_INPUT:d} bad input (one line on stderr says what to "
    f"fix); {ExitCode.FORMED_WITH_COLLISIONS:d} formed, but with collisions (robots stopped at "
    f"contact: not the collision-free formation the paper guarantees); "
    f"{ExitCode.RECORD_FAILED:d} the run record could not be written (disk full, permissions: "
    f"the run stopped; --resume goes on once fixed); {ExitCode.INTERRUPTED:d} "
    f"interrupted (Ctrl-C); {ExitCode.BROKEN_PIPE:d} standard output closed early (e.g. | head); "
    f"{ExitCode.TERMINATED:d} terminated (SIGTERM). A run stopped by a signal or a record it "
    "cannot write says in one line after which round, and how to go on (--resume)."
)
PROGRESS_SECONDS: Final = 1.0  # at most one progress line per this many seconds


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm run`, the launcher's (networked) and the dashboard's among them."""
    p.epilog = EXIT_CODES_HELP
    _add_start_arguments(p)
    _add_model_arguments(p)
    add_robot_model_arguments(p)
    _add_output_arguments(p)
    add_network_arguments(p)
    # The dashboard's run flags (--no-dashboard, --svg): `add_run_arguments`, because the CLI
    # would hand an `add_dashboard_arguments` to `fatswarm dashboard` itself. Called through its
    # module: the CLI would take an `add_run_arguments` of this module for all of run's flags.
    dashboard.add_run_arguments(p)


def _add_start_arguments(p: argparse.ArgumentParser) -> None:
    """How the run is made (in lock step or not), its robots, algorithm, seed and start."""
    p.add_argument(
        "--lockstep",
        action="store_true",
        help="run every robot in this one process, in lock step (no Zenoh; refuses the "
        "networked-run flags)",
    )
    p.add_argument(
        "-n",
        type=int,
        default=None,
        metavar="N",
        help=f"number of robots (default {DEFAULT_N}; with --init, taken from the file)",
    )
    p.add_argument(
        "-a",
        type=float,
        default=None,
        metavar="A",
        help=f"the paper's least side of the polygon, > 3: --param a=A (default "
        f"{DEFAULT_A:g}, or the --init file's 'a'); random starts are drawn at this "
        "scale",
    )
    add_algorithm_arguments(p)
    p.add_argument(
        "--seed",
        type=int,
        default=None,
        metavar="S",
        help="seed of the start, frames and scheduler (default: random, printed)",
    )
    p.add_argument(
        "--init",
        metavar="PATH",
        help='start from a JSON file {"positions": [[x, y], ...], "a": 4.0}',
    )
    p.add_argument(
        "--start",
        choices=KINDS,
        default=DEFAULT_START,
        action=StoreGiven,
        help=f"kind of random start without --init (default {DEFAULT_START}: needs SEC expansion)",
    )


def _add_model_arguments(p: argparse.ArgumentParser) -> None:
    """The scheduler and the adversary: who is active, fairness, round cap, non-rigid, crashes."""
    p.add_argument(
        "--scheduler",
        choices=NAMES,
        default=DEFAULT_SCHEDULER,
        action=StoreGiven,
        help=f"who is active each round (default {DEFAULT_SCHEDULER}); async, "
        "async-slowest: no rounds, robots on their own clocks in virtual time, the "
        "adversary's delays random or slowest robot last",
    )
    p.add_argument(
        "--schedule",
        metavar="PATH",
        help='scripted scheduler: JSON {"rounds": [[0, 2], [1], ...]} or a run record',
    )
    p.add_argument(
        "--fairness",
        type=int,
        default=None,
        metavar="K",
        help="ssync/centralized: every robot active at least once in every K rounds (default 2n)",
    )
    p.add_argument(
        "--max-rounds",
        type=int,
        default=None,
        metavar="R",
        help="stop after R rounds (default: 10 (n + 10) for fsync, 40 (n + 10) for "
        "ssync, 10 n (n + 10) otherwise; for the async models 40 n (n + 10) ended cycles, "
        "times ceil(reach / 40) when the radius of the start's or target circle, the reach, "
        "exceeds 40)",
    )
    p.add_argument(
        "--non-rigid",
        type=float,
        default=None,
        metavar="DELTA",
        help="non-rigid moves: the adversary may stop a move anywhere after the robot "
        "has travelled DELTA (> 0, robot radii; e.g. 1) or at its end, drawn from the "
        "seed (default: rigid moves)",
    )
    p.add_argument(
        "--crash",
        type=int,
        default=None,
        metavar="F",
        help="F robots (0 < F < n) crash at rounds the adversary draws from the seed "
        "and stay for good as still obstacles; the goal is then judged on the live "
        "robots (default: none)",
    )


def _add_output_arguments(p: argparse.ArgumentParser) -> None:
    """The run record (new, overwritten or resumed) and what is printed."""
    p.add_argument(
        "--record",
        metavar="PATH",
        help="write the run record (JSON Lines) to PATH (a new file, unless --force)",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="let --record overwrite an existing file; networked: also start a run larger "
        "than this machine seems to hold (see the estimate it prints)",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue the unfinished run of the --record file after its last round, "
        "appending to it: n, a, seed, scheduler, start and round cap are the record's "
        "(a flag that contradicts them is refused)",
    )
    p.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="no progress lines while running (the summary is still printed)",
    )
    p.add_argument(
        "--json",
        action="store_true",
        help="print the summary as one JSON object on stdout (progress stays on "
        "stderr; no live dashboard)",
    )


def _fail(message: str) -> ExitCode:
    print(f"fatswarm run: {message}", file=sys.stderr)
    return ExitCode.BAD_INPUT


def main(args: argparse.Namespace) -> int:
    """Run the swarm as asked; returns the exit code."""
    if not args.lockstep:
        return _networked(args)
    return run_lockstep_command(args)


def _networked(args: argparse.Namespace) -> int:
    # the launcher (subprocess, the parts' supervision) loads only for a networked run: the CLI
    # imports this module to build its parser
    from fatswarm.deploy.net.launcher import run_networked

    return run_networked(args, resolve_run)


def networked_flags_given(args: argparse.Namespace) -> list[str]:
    """The networked-only flags (the launcher's) that differ from their defaults in `args`."""
    flags: tuple[tuple[str, str, object], ...] = getattr(args, "_networked_flags", ())
    return [flag for flag, dest, default in flags if getattr(args, dest, default) != default]


def check_lockstep_flags(args: argparse.Namespace) -> None:
    """Refuse networked-only flags in a lockstep run rather than ignore them (RunInputError)."""
    given = networked_flags_given(args)
    if given:
        only = "is" if len(given) == 1 else "are"
        raise RunInputError(
            f"{', '.join(given)} {only} for networked runs only: drop "
            f"{'it' if len(given) == 1 else 'them'} or --lockstep"
        )


def check_outputs(args: argparse.Namespace) -> None:
    """Refuse a --record or --svg that cannot be written, before anything runs (RunInputError).

    An existing record is overwritten only with --force (--resume continues it).
    """
    record: str | None = args.record
    resume = bool(getattr(args, "resume", False))
    if resume and not record:
        raise RunInputError("--resume continues a run record: name it with --record PATH")
    if getattr(args, "force", False) and not record and getattr(args, "lockstep", True):
        raise RunInputError("--force lets --record overwrite its file: name it with --record PATH")
    if record:
        check_writable("--record", record)
        if resume and args.force:
            raise RunInputError(
                "--resume continues the --record file, --force overwrites it: pass one of them"
            )
        if os.path.exists(record) and not os.path.isfile(record):
            raise RunInputError(
                f"--record {record} exists and is not a regular file (a device, "
                "a pipe...); name a file"
            )
        if os.path.exists(record) and not (args.force or resume):
            raise RunInputError(f"--record {record} exists; pass --force to overwrite it")
    svg: str | None = getattr(args, "svg", None)  # the dashboard's flag
    if svg:
        check_svg(svg)


def check_svg(svg: str) -> None:
    """Refuse an --svg that cannot be written or does not end in .svg: the final frame is SVG,
    and SVG in a .png file opens nowhere (`fatswarm plot RECORD OUT.png` draws a PNG)."""
    check_writable("--svg", svg)
    if os.path.splitext(svg)[1].lower() != ".svg":
        raise RunInputError(
            f"--svg writes the final frame as SVG: name a .svg file, got {svg!r} (for a PNG: "
            "--record R, then fatswarm plot R OUT.png)"
        )


def resolve_run(args: argparse.Namespace, seed: int) -> RunSetup:
    """Build the run the flags describe (shared by lockstep and networked runs, so both refuse
    the same input with the same message); raises one of `input_errors()`."""
    check_outputs(args)
    check_start_flags(args)
    if getattr(args, "resume", False):
        return resolve_resume(args)
    return RunConfig.from_args(args, seed).resolve()


def run_lockstep_command(args: argparse.Namespace, out: TextIO | None = None) -> int:
    """`fatswarm run --lockstep`: build the run from the flags, run it, print the summary."""
    out = sys.stdout if out is None else out
    seed_given = args.seed is not None
    seed: int = args.seed if seed_given else secrets.randbelow(2**31)
    bad_input: tuple[type[Exception], ...] = (*input_errors(), RecordFormatError)
    try:
        setup, record = _lockstep_setup(args, seed)
    except bad_input as exc:
        return _fail(str(exc))
    done = 0 if setup.resumed is None else len(setup.resumed.rounds)
    forecast = estimate_lockstep(
        setup.params.n, setup.scheduler.name, setup.max_rounds, done, _reach(setup)
    )
    if not args.quiet:
        _announce(args, setup, forecast, seed_given=seed_given)
    printer = None if args.quiet else _progress_printer(setup, done + forecast.rounds, done)
    before = () if setup.resumed is None else crashes_in(setup.resumed.rounds)
    watch = _Watch(done, printer, before)
    result = _run_setup(args, setup, record, watch)
    if isinstance(result, ExitCode):
        return result
    outcome = _outcome(setup, result, watch)
    code = exit_code(outcome)
    svg: str | None = getattr(args, "svg", None)  # the dashboard's flag, when it is there
    if svg and not _save_final_frame(result, setup, svg):
        code, svg = ExitCode.BAD_INPUT, None
    print_outcome(outcome, code, out, as_json=args.json, record=args.record, svg=svg)
    return code


def _reach(setup: RunSetup) -> float:
    """The run's reach (`lockstep.run_reach`) under an async model, whose cycles grow with it;
    0 otherwise."""
    if setup.scheduler.name not in ASYNC_NAMES:
        return 0.0
    # the whole lock-step engine: the CLI imports this module to build its parser
    from fatswarm.deploy.engine.lockstep import run_reach

    return run_reach(setup.params, setup.initial)


def _outcome(setup: RunSetup, result: RunResult, watch: _Watch) -> Outcome:
    """What the summary says of a lock-step run that ended."""
    params = setup.params
    return Outcome(
        status=result.status,
        rounds=result.rounds,
        collisions=result.collisions,
        n=params.n,
        a=side_of(params.values),
        seed=setup.seed,
        scheduler=setup.scheduler.name,
        epochs=result.epochs,
        moves=result.moves,
        total_distance=result.total_distance,
        algorithm=params.name,
        params=dict(params.values),
        time=result.time,
        crashes=tuple(watch.crashes),
        derived=result.derived,
    ).noted(model_fields(setup))


class _Watch:
    """The lock step's round callback: keeps the last committed round and when the crash
    adversary crashed whom (from the figures: an async record's lines do not say it), and hands
    each round on to the progress printer, if there is one."""

    def __init__(
        self,
        done: int,
        printer: Callable[[RoundReport], None] | None,
        crashes: Sequence[tuple[int, int]] = (),
    ) -> None:
        self.done = done  # the last round (ended cycle) committed
        self.printer = printer
        self.crashes = list(crashes)  # (robot, round): those of the rounds resumed from first
        self.seen = {robot for robot, _ in crashes}

    def __call__(self, report: RoundReport) -> None:
        self.done = report.entry.round
        for robot in report.progress.crashed:
            if robot not in self.seen:
                self.seen.add(robot)
                self.crashes.append((robot, report.entry.round))
        if self.printer is not None:
            self.printer(report)


class _Counted:
    """The run record, telling the watch of each round line it holds: a run stopped between a
    line and its callback still says after which round its record ends."""

    def __init__(self, writer: RecordWriter, watch: _Watch) -> None:
        self.writer, self.watch = writer, watch
        self.path = writer.path

    def append(self, line: Header | RoundEntry | Result) -> None:
        self.writer.append(line)
        if isinstance(line, RoundEntry):
            self.watch.done = line.round

    def close(self) -> None:
        self.writer.close()


def _lockstep_setup(args: argparse.Namespace, seed: int) -> tuple[RunSetup, RecordWriter | None]:
    """The run the flags ask for in lock step and the writer of its record (None: no --record);
    raises one of `input_errors()` or RecordFormatError. A resumed record's torn last line (a
    run stopped mid-write) is cut first, and said on stderr."""
    check_lockstep_flags(args)
    setup = resolve_run(args, seed)
    resumed = setup.resumed
    if resumed is not None and setup.scheduler.name in ASYNC_NAMES:
        raise RunInputError(
            f"--resume: a {setup.scheduler.name} run cannot be resumed yet; "
            "run it again with its --seed: a lock-step run repeats exactly"
        )
    if resumed is not None:
        note = drop_torn_end(args.record, resumed)
        if note is not None:
            print(f"fatswarm run: {note}", file=sys.stderr)
    # --resume appends after the committed rounds: nothing there is ever cut or rewritten
    record = RecordWriter(args.record, append=resumed is not None) if args.record else None
    return setup, record


def model_fields(setup: RunSetup) -> dict[str, Any]:
    """The header fields a run's summary names: its model (if not the paper's) and the line saying
    that its frames are outside the algorithm's assumption (if they are)."""
    # here, not at the top: the CLI imports this module to build its parser
    from fatswarm.world.core import outside_assumption

    model = setup.robot_model
    return {
        "model": None if model.is_paper else model.to_header(),
        "assumption": outside_assumption(setup.params, model) or None,
    }


def _announce(
    args: argparse.Namespace, setup: RunSetup, forecast: Estimate, *, seed_given: bool
) -> None:
    """The drawn seed (of a new run), where a resumed run goes on from, and, for a large or long
    run, the estimate (of what is left), on stderr."""
    n = setup.params.n
    if not seed_given and setup.resumed is None:
        print(f"seed {setup.seed} (pass --seed {setup.seed} to repeat this run)", file=sys.stderr)
    if setup.resumed is not None:
        word = unit(setup.scheduler.name)
        print(
            f"resuming {args.record} after {word} {forecast.done} (its {word} cap: "
            f"{setup.max_rounds})",
            file=sys.stderr,
        )
    if n >= ESTIMATE_FROM_N or forecast.seconds >= ESTIMATE_FROM_S:
        print(estimate_text(forecast, n, record=bool(args.record)), file=sys.stderr, flush=True)


def _run_setup(
    args: argparse.Namespace, setup: RunSetup, record: RecordWriter | None, watch: _Watch
) -> RunResult | ExitCode:
    """Run `setup` in lock step, writing `record` (closed at the end); the result, or the exit
    code of a run that could not go on (said on stderr: a signal or a failed write says after
    which round, and how to go on)."""
    try:
        return _run_lockstep(args, setup, record, watch)
    except (KeyboardInterrupt, Terminated) as exc:
        word = "terminated" if isinstance(exc, Terminated) else "interrupted"
        print(_stopped(word, args, setup, watch), file=sys.stderr)
        return ExitCode.TERMINATED if isinstance(exc, Terminated) else ExitCode.INTERRUPTED
    except RecordWriteError as exc:  # the rounds written stay; --resume goes on from them
        said = _stopped("stopped", args, setup, watch, fix=True)
        print(f"fatswarm run: {exc}; the run {said}", file=sys.stderr)
        return ExitCode.RECORD_FAILED
    finally:
        if record is not None:
            with contextlib.suppress(RecordWriteError):  # said above, if it matters
                record.close()


def _stopped(
    word: str, args: argparse.Namespace, setup: RunSetup, watch: _Watch, *, fix: bool = False
) -> str:
    """`stopped_line` for this lock-step run."""
    return stopped_line(
        word,
        watch.done,
        record=args.record,
        scheduler=setup.scheduler.name,
        lockstep=True,
        seed=setup.seed,
        fix=fix,
    )


def _run_lockstep(
    args: argparse.Namespace, setup: RunSetup, record: RecordWriter | None, watch: _Watch
) -> RunResult | ExitCode:
    """`run_lockstep` on `setup`; the exit code (said on stderr) of a start, an algorithm or a
    history that fails."""
    # the whole lock-step engine: the CLI imports this module to build its parser
    from fatswarm.deploy.engine.lockstep import HistoryMismatchError, run_lockstep

    try:
        return run_lockstep(
            setup.initial,
            setup.params,
            setup.scheduler,
            seed=setup.seed,
            max_rounds=setup.max_rounds,
            record=None if record is None else _Counted(record, watch),
            on_round=watch,
            history=None if setup.resumed is None else setup.resumed.rounds,
            algorithm_ref=setup.algorithm_ref,
            header_extra=(
                {}
                if setup.config is None
                else setup.config.header_extra(networked=False, n=setup.params.n)
            ),
            non_rigid=setup.non_rigid,
            crash=setup.crash,
            robot_model=setup.robot_model,
            record_views=setup.record_views,
        )
    except InvalidConfigurationError as exc:
        return _fail(f"invalid start: {exc}")
    except AlgorithmFailure as exc:  # the record holds every round before it
        print(f"fatswarm run: {exc}", file=sys.stderr)
        return ExitCode.NOT_FORMED
    except HistoryMismatchError as exc:  # refused before anything was appended
        return _fail(
            f"--resume: {args.record} cannot be continued exactly in lock step: {exc} "
            "(resume it with the run's own --fairness or --schedule, or networked if "
            "it ran so)"
        )


def _save_final_frame(result: RunResult, setup: RunSetup, svg: str) -> bool:
    """Save the run's final dashboard frame as SVG at `svg`; False (said on stderr) if it cannot
    be written."""
    params = setup.params
    final = Frame(
        round=result.rounds,
        n=params.n,
        algorithm=params.name,
        params=dict(params.values),
        figures=params.figures(result.positions),
        scheduler=setup.scheduler.name,
        positions=result.positions,
        collisions_total=result.collisions,
        status=result.status,
        seed=setup.seed,
        max_rounds=setup.max_rounds,
        source="lockstep",
        lights=result.lights,
        palette=tuple(sorted(params.colours)),  # names sorted, as replay and plot colour them
    )
    try:
        save_svg(final, svg)
    except OSError as exc:
        _fail(f"cannot write {svg}: {exc.strerror}")
        return False
    return True


def _progress_printer(
    setup: RunSetup, expected_rounds: int, done: int
) -> Callable[[RoundReport], None]:
    """A round callback printing a progress line (with an ETA) to stderr at most once per
    PROGRESS_SECONDS; `done`: the rounds committed before this process started (a resume).
    Under an async model it counts ended cycles and shows the virtual time."""
    start = time.monotonic()
    last = [start]
    max_rounds, word = setup.max_rounds, unit(setup.scheduler.name)

    def show(report: RoundReport) -> None:
        now = time.monotonic()
        if now - last[0] < PROGRESS_SECONDS:
            return
        last[0] = now
        p, k = report.progress, report.entry.round
        rate = (k - done) / (now - start) if now > start else 0.0
        end = report.entry.extra.get("end")
        clock = f"  time {end:.1f}" if isinstance(end, (int, float)) else ""
        print(
            f"{word} {k}/{max_rounds}{clock}  epochs {p.epochs}  moves {p.moves}  "
            f"distance {p.total_distance:.1f}  collisions {p.collisions}  "
            f"{eta_text(k, rate, expected_rounds, max_rounds, word)}",
            file=sys.stderr,
            flush=True,
        )

    return show


__all__ = [
    "add_arguments",
    "check_outputs",
    "check_svg",
    "main",
    "resolve_run",
    "run_lockstep_command",
]
