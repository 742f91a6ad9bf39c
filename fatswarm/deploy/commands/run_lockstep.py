"""`fatswarm run --lockstep`: the run the flags ask for, in this one process: its progress lines,
its record (new or resumed), the line a stopped run says, the summary and the exit code."""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import secrets
import sys
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Final, TextIO

from fatswarm.deploy.commands.resume import drop_torn_end, stopped_line
from fatswarm.deploy.commands.run_input import check_lockstep_flags, resolve_run
from fatswarm.deploy.engine.config import RunSetup, input_errors
from fatswarm.deploy.engine.estimate import (
    ESTIMATE_FROM_N,
    ESTIMATE_FROM_S,
    estimate_lockstep,
    estimate_text,
    eta_text,
)
from fatswarm.deploy.flags import Terminated
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

PROGRESS_SECONDS: Final = 1.0  # at most one progress line per this many seconds
TAIL_BYTES: Final = 1 << 16  # `last_round` reads a record's end by this much, then 4x as much


def _fail(message: str) -> ExitCode:
    print(f"fatswarm run: {message}", file=sys.stderr)
    return ExitCode.BAD_INPUT


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
    if resumed is not None:
        note = drop_torn_end(args.record, resumed)
        if note is not None:
            print(f"fatswarm run: {note}", file=sys.stderr)
    # --resume appends after the committed rounds: nothing there is ever cut or rewritten
    record = RecordWriter(args.record, append=resumed is not None) if args.record else None
    return setup, record


def model_fields(setup: RunSetup) -> dict[str, Any]:
    """The header fields a run's summary names: its model (if not the paper's) and the line saying
    that it is outside the algorithm's assumptions (if it is)."""
    model = setup.robot_model
    return {
        "model": None if model.is_paper else model.to_header(),
        "assumption": setup.outside or None,
    }


def _announce(
    args: argparse.Namespace, setup: RunSetup, forecast: Estimate, *, seed_given: bool
) -> None:
    """That the run is outside its algorithm's assumptions (if it is), the drawn seed (of a new
    run), where a resumed run goes on from, and, for a large or long run, the estimate (of what is
    left), on stderr."""
    n = setup.params.n
    if setup.outside:  # the run goes ahead: that is the experiment
        print(f"fatswarm run: {setup.outside}", file=sys.stderr)
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
    """`stopped_line` for this lock-step run: after the round its record ends with, if it has
    one (a signal may land between a line's write and the watch's count of it)."""
    return stopped_line(
        word,
        watch.done if not args.record else last_round(args.record, watch.done),
        record=args.record,
        scheduler=setup.scheduler.name,
        lockstep=True,
        seed=setup.seed,
        fix=fix,
    )


def last_round(path: str, otherwise: int) -> int:
    """The round of the last complete line of the record at `path` if that is a round line (a
    torn end after it is not a line: `--resume` drops it), else `otherwise` (a header alone, a
    file that cannot be read)."""
    try:
        with open(path, "rb") as f:
            size = f.seek(0, os.SEEK_END)
            chunk = TAIL_BYTES
            while True:  # read back until the last complete line is whole
                start = max(0, size - chunk)
                f.seek(start)
                tail = f.read(size - start)
                end = tail.rfind(b"\n")
                begin = tail.rfind(b"\n", 0, max(end, 0)) + 1
                if start == 0 or (end >= 0 and begin > 0):
                    break
                chunk *= 4
        line = json.loads(tail[begin:end]) if end >= 0 else None
    except (OSError, ValueError):
        return otherwise
    if isinstance(line, dict) and line.get("type") == "round" and type(line.get("round")) is int:
        return int(line["round"])
    return otherwise


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
            settings=setup.settings,
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
        model=setup.settings.robot_model.short,
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


__all__ = ["PROGRESS_SECONDS", "model_fields", "run_lockstep_command"]
