"""Evidence matrix over adversarial starts (deploy/scenarios/adversarial.py) under fsync, ssync,
centralized.

    python bench/bench_adversarial.py                    # 2,000 starts x 3 schedulers = 6,000 runs
    python bench/bench_adversarial.py --quick --jobs 2   # 60 cases (n <= 16) x 3 = 180 runs
    python bench/bench_adversarial.py --families rim,lattice --csv runs.csv
    python bench/bench_adversarial.py --emit-start lattice 12 345 4.0 > start.json

Every run is replayable: `--emit-start FAMILY N SEED A` writes the start as an --init file, and
`fatswarm run --lockstep --init start.json --seed SEED --scheduler X` runs the very same start,
frames and schedule (the failure lines below print both commands). A crash of one run is a finding:
it is counted as an error with its message, and the matrix goes on. Ctrl-C reports what was done.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import multiprocessing as mp
import os
import signal
import sys
import time
import traceback
from collections import Counter, defaultdict
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from types import FrameType
from typing import Any, Final, TextIO

import numpy as np
from bench_core import PROGRESS_SECONDS, SCHEDULERS, _stats

from fatswarm.agent.params import Params
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.lockstep import run_lockstep
from fatswarm.deploy.scenarios.adversarial import (
    DESCRIPTIONS,
    FAMILIES,
    Case,
    adversarial_cases,
    build_adversarial,
)

DEFAULT_COUNT: Final = 2000  # adversarial starts, x 3 schedulers = 6,000 runs
DEFAULT_N_MAX: Final = 40
QUICK_COUNT: Final = 60  # cases, x 3 schedulers = 180 runs
QUICK_N_MAX: Final = 16
DEFAULT_TIMEOUT: Final = 600.0  # seconds per run before it counts as an error (0: no limit)
SHOWN: Final = 12  # errors and failures listed in full
REPO: Final = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MOVE_BUDGET: Final = 2  # the algorithm needs about n + 2 moves (one mover or mirror pair a step)
CSV_FIELDS: Final = (
    "family",
    "variant",
    "n",
    "a",
    "seed",
    "scheduler",
    "status",
    "rounds",
    "epochs",
    "moves",
    "moves_per_n",
    "max_robot_moves",
    "within_n_plus_2",
    "collisions",
    "distance",
    "seconds",
    "error",
)


class RunTimeout(BaseException):
    """A run used more than its time limit (an algorithm loop that never ends is a finding).
    Not an Exception: raised inside a compute, the engine would count it as the algorithm's
    failure, the robot would stay and the run go on with no limit left."""


@dataclass(frozen=True, slots=True)
class Outcome:
    """What one run of the matrix gave (status 'error' when it raised; `error` says what)."""

    case: Case
    scheduler: str
    variant: str
    status: str
    rounds: int = 0
    epochs: int = 0
    moves: int = 0
    max_robot_moves: int = 0
    collisions: int = 0
    distance: float = 0.0
    seconds: float = 0.0
    error: str | None = None

    @property
    def moves_per_n(self) -> float:
        return self.moves / self.case.n

    @property
    def within_budget(self) -> bool:
        return self.moves <= self.case.n + MOVE_BUDGET

    def problems(self) -> list[str]:
        """Why this run is not the paper's promise: formed, no collision, about n + 2 moves."""
        found = []
        if self.error is not None:
            found.append(f"error {self.error}")
        elif self.status != "formed":
            found.append(self.status)
        if self.collisions:
            found.append(f"{self.collisions} collision(s)")
        if self.error is None and not self.within_budget:
            found.append(f"{self.moves} moves > n + {MOVE_BUDGET}")
        if self.case.family == "formed" and self.moves:
            found.append("already formed, yet robots moved")
        return found

    def row(self) -> dict[str, Any]:
        """One CSV row."""
        return {
            **{k: v for k, v in asdict(self.case).items()},
            "variant": self.variant,
            "scheduler": self.scheduler,
            "status": self.status,
            "rounds": self.rounds,
            "epochs": self.epochs,
            "moves": self.moves,
            "moves_per_n": f"{self.moves_per_n:.4g}",
            "max_robot_moves": self.max_robot_moves,
            "within_n_plus_2": int(self.within_budget),
            "collisions": self.collisions,
            "distance": f"{self.distance:.6g}",
            "seconds": f"{self.seconds:.3f}",
            "error": self.error or "",
        }


def replay(case: Case, scheduler: str) -> str:
    """Shell commands that rerun this very run with the fatswarm command."""
    return (
        f"python bench/bench_adversarial.py --emit-start {case.family} {case.n} {case.seed} "
        f"{case.a:g} > start.json && fatswarm run --lockstep --init start.json "
        f"--seed {case.seed} --scheduler {scheduler}"
    )


def _describe(exc: BaseException) -> str:
    """The exception's type and message, and the deepest line of this repository it came
    through (file:line, function): where a fix would go, not numpy's internals."""
    frames = list(traceback.extract_tb(exc.__traceback__))
    if isinstance(exc, RunTimeout):
        frames = frames[:-1]  # where the run was when time ran out, not the alarm handler
    ours = [f for f in frames if os.path.abspath(f.filename).startswith(REPO + os.sep)]
    where = ""
    if ours or frames:
        last = (ours or frames)[-1]
        where = f" [at {os.path.relpath(last.filename, REPO)}:{last.lineno} in {last.name}]"
    message = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {message}{where}"


@contextmanager
def _time_limit(seconds: float) -> Iterator[None]:
    """Raise RunTimeout inside the block after `seconds` (no limit if 0 or without SIGALRM)."""
    if seconds <= 0 or not hasattr(signal, "SIGALRM"):
        yield
        return

    def on_alarm(signum: int, frame: FrameType | None) -> None:
        del signum, frame
        raise RunTimeout(f"the run took longer than {seconds:g} s (--run-timeout)")

    previous = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def run_one(job: tuple[Case, str, float]) -> Outcome:
    """Run one (case, scheduler) in lockstep; any exception becomes an 'error' outcome."""
    case, scheduler, timeout = job
    t0 = time.perf_counter()
    variant = "?"
    try:
        built = build_adversarial(case.family, case.n, case.seed)
        variant = built.variant
        with _time_limit(timeout):
            result = run_lockstep(
                built.positions,
                Params(case.n, case.a),
                make_scheduler(scheduler, case.n, case.seed),
                seed=case.seed,
            )
    except (Exception, RunTimeout) as exc:  # a crash is a finding: record it, keep going
        return Outcome(
            case,
            scheduler,
            variant,
            "error",
            seconds=time.perf_counter() - t0,
            error=_describe(exc),
        )
    return Outcome(
        case,
        scheduler,
        variant,
        result.status,
        rounds=result.rounds,
        epochs=result.epochs,
        moves=result.moves,
        max_robot_moves=max(result.moves_by_robot, default=0),
        collisions=result.collisions,
        distance=result.total_distance,
        seconds=time.perf_counter() - t0,
    )


def _ignore_sigint() -> None:
    """Pool workers leave Ctrl-C to the parent, which stops them and reports what is done."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def run_all(
    jobs: Sequence[tuple[Case, str, float]], workers: int, quiet: bool
) -> tuple[list[Outcome], bool]:
    """All runs over `workers` spawned processes, progress on stderr; (outcomes, interrupted)."""
    outcomes: list[Outcome] = []
    started = time.monotonic()
    last = started

    def note() -> None:
        nonlocal last
        now = time.monotonic()
        done = len(outcomes)
        if quiet or (now - last < PROGRESS_SECONDS and done < len(jobs)):
            return
        last = now
        tally = Counter(o.status for o in outcomes)
        collided = sum(1 for o in outcomes if o.collisions)
        print(
            f"  runs {done}/{len(jobs)}  {now - started:.0f}s  formed {tally['formed']}  "
            f"stalled {tally['stalled']}  max_rounds {tally['max_rounds']}  "
            f"collisions {collided}  errors {tally['error']}",
            file=sys.stderr,
            flush=True,
        )

    # Long runs first (centralized costs about n rounds a step) so no straggler ends the pool.
    order = sorted(jobs, key=lambda j: -j[0].n * (j[0].n if j[1] == "centralized" else 1))
    try:
        if workers <= 1:
            for job in order:
                outcomes.append(run_one(job))
                note()
        else:
            ctx = mp.get_context("spawn")
            with ctx.Pool(workers, initializer=_ignore_sigint) as pool:
                try:
                    for out in pool.imap_unordered(run_one, order, chunksize=1):
                        outcomes.append(out)
                        note()
                except KeyboardInterrupt:
                    pool.terminate()
                    raise
    except KeyboardInterrupt:
        print(
            f"\ninterrupted after {len(outcomes)} of {len(jobs)} runs; reporting those",
            file=sys.stderr,
            flush=True,
        )
        return outcomes, True
    return outcomes, False


def _med_max(values: Sequence[float]) -> str:
    if not values:
        return "-"
    arr = np.asarray(values, dtype=np.float64)
    return f"{np.median(arr):.3g} / {arr.max():.3g}"


def report(outcomes: Sequence[Outcome], out: TextIO = sys.stdout) -> None:
    """Per family x scheduler: runs, formed, collisions, stalls, caps, errors, moves, rounds."""
    print(f"\n== adversarial evidence: {len(outcomes)} runs ==", file=out)
    if not outcomes:
        return
    groups: dict[tuple[str, str], list[Outcome]] = defaultdict(list)
    for o in outcomes:
        groups[(o.case.family, o.scheduler)].append(o)
        groups[("all", o.scheduler)].append(o)
    header = (
        f"{'family':<16}{'scheduler':<12}{'runs':>5}{'formed':>7}{'coll':>5}{'stall':>6}"
        f"{'maxr':>5}{'err':>5}  {'moves/n med/max':<16}{'>n+2':>5}  {'rounds med/p95/max':<20}"
    )
    print(header, file=out)
    print("-" * len(header), file=out)
    family_order = {name: i for i, name in enumerate((*FAMILIES, "all"))}
    scheduler_order = {name: i for i, name in enumerate(SCHEDULERS)}
    for family, scheduler in sorted(
        groups, key=lambda g: (family_order.get(g[0], -1), scheduler_order.get(g[1], -1))
    ):
        rows = groups[(family, scheduler)]
        ran = [o for o in rows if o.error is None]
        tally = Counter(o.status for o in rows)
        print(
            f"{family:<16}{scheduler:<12}{len(rows):>5}{tally['formed']:>7}"
            f"{sum(1 for o in rows if o.collisions):>5}{tally['stalled']:>6}"
            f"{tally['max_rounds']:>5}{tally['error']:>5}  "
            f"{_med_max([o.moves_per_n for o in ran]):<16}"
            f"{sum(1 for o in ran if not o.within_budget):>5}  "
            f"{_stats([o.rounds for o in ran]):<20}",
            file=out,
        )
    errors = [o for o in outcomes if o.error is not None]
    by_message = Counter((o.error or "").split(" [at ")[0] for o in errors)
    print(f"\nerrors: {len(errors)} runs, {len(by_message)} distinct messages", file=out)
    for o in sorted(errors, key=lambda o: (o.case.n, o.case.family, o.scheduler))[:SHOWN]:
        print(f"  {o.case} {o.scheduler} ({o.variant}): {o.error}", file=out)
        print(f"    {replay(o.case, o.scheduler)}", file=out)
    failures = [o for o in outcomes if o.error is None and o.problems()]
    print(
        f"\nnot formed, colliding, over n + {MOVE_BUDGET} moves or moving when formed: "
        f"{len(failures)} runs",
        file=out,
    )
    for o in sorted(failures, key=lambda o: (o.case.n, o.case.family, o.scheduler))[:SHOWN]:
        print(
            f"  {', '.join(o.problems())}; rounds {o.rounds}: {o.case} {o.scheduler} ({o.variant})",
            file=out,
        )
        print(f"    {replay(o.case, o.scheduler)}", file=out)
    hidden = max(0, len(failures) - SHOWN) + max(0, len(errors) - SHOWN)
    if hidden:
        print(f"  ... and {hidden} more (see --csv)", file=out)


def write_csv(path: str, outcomes: Iterable[Outcome]) -> None:
    """One row per run, in matrix order (family, n, seed, scheduler)."""
    rows = sorted(
        outcomes,
        key=lambda o: (
            FAMILIES.index(o.case.family),
            o.case.n,
            o.case.seed,
            SCHEDULERS.index(o.scheduler),
        ),
    )
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=CSV_FIELDS)
        writer.writeheader()
        for o in rows:
            writer.writerow(o.row())


def select_cases(count: int, seed: int, n_max: int, families: Sequence[str]) -> list[Case]:
    """The first `count` cases of the given families; each is the very case the full matrix of
    the same seed runs (adversarial_cases(k) is a prefix of adversarial_cases(k + 1))."""
    wanted = set(families)
    total = count
    while True:
        chosen = [c for c in adversarial_cases(total, seed, n_max) if c.family in wanted]
        if len(chosen) >= count or total > 64 * max(count, 1):
            return chosen[:count]
        total *= 2


def _families(text: str) -> list[str]:
    names = [name.strip() for name in text.split(",") if name.strip()]
    unknown = [name for name in names if name not in FAMILIES]
    if unknown or not names:
        raise argparse.ArgumentTypeError(
            f"unknown famil{'y' if len(unknown) == 1 else 'ies'} {', '.join(unknown) or '(none)'}"
            f"; choose from {', '.join(FAMILIES)}"
        )
    return names


def _parse(argv: Sequence[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument(
        "--count",
        type=int,
        default=None,
        metavar="K",
        help=f"cases (each under {len(SCHEDULERS)} schedulers; default "
        f"{DEFAULT_COUNT}, --quick {QUICK_COUNT})",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the case list (default 0)")
    p.add_argument(
        "--n-max",
        type=int,
        default=None,
        metavar="N",
        help=f"largest n (default {DEFAULT_N_MAX}, --quick {QUICK_N_MAX})",
    )
    p.add_argument(
        "--families",
        type=_families,
        default=list(FAMILIES),
        metavar="A,B",
        help=f"only these families (default all: {', '.join(FAMILIES)})",
    )
    p.add_argument(
        "--jobs",
        type=int,
        default=os.cpu_count() or 1,
        help="worker processes (spawn; default: all cores)",
    )
    p.add_argument(
        "--quick", action="store_true", help=f"smoke run: {QUICK_COUNT} cases, n <= {QUICK_N_MAX}"
    )
    p.add_argument("--csv", metavar="PATH", help="write one row per run to PATH")
    p.add_argument(
        "--run-timeout",
        type=float,
        default=DEFAULT_TIMEOUT,
        metavar="SECONDS",
        help=f"a run longer than this counts as an error (default {DEFAULT_TIMEOUT:g};"
        " 0: no limit)",
    )
    p.add_argument("--list", action="store_true", help="describe the families and exit")
    p.add_argument(
        "--emit-start",
        nargs=4,
        metavar=("FAMILY", "N", "SEED", "A"),
        help="print one case's start as a `fatswarm run --init` file and exit",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    args = p.parse_args(argv)
    if args.count is not None and args.count < 0:
        p.error(f"--count must be >= 0, got {args.count}")
    if args.jobs < 1:
        p.error(f"--jobs must be >= 1, got {args.jobs}")
    return args


def emit_start(family: str, n: str, seed: str, a: str, out: TextIO = sys.stdout) -> int:
    """Write {"positions": [...], "a": A} (exact floats) for `fatswarm run --init`."""
    try:
        built = build_adversarial(family, int(n), int(seed))
        side = float(a)
    except ValueError as exc:
        print(f"bench_adversarial: {exc}", file=sys.stderr)
        return 2
    positions = [[float(x), float(y)] for x, y in built.positions]
    json.dump({"positions": positions, "a": side, "variant": built.variant}, out)
    out.write("\n")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    args = _parse(argv)
    if args.list:
        for name in FAMILIES:
            print(f"{name:<16}{DESCRIPTIONS[name]}")
        return 0
    if args.emit_start:
        return emit_start(*args.emit_start)
    count = args.count if args.count is not None else (QUICK_COUNT if args.quick else DEFAULT_COUNT)
    n_max = args.n_max if args.n_max is not None else (QUICK_N_MAX if args.quick else DEFAULT_N_MAX)
    try:
        cases = select_cases(count, args.seed, n_max, args.families)
    except ValueError as exc:
        print(f"bench_adversarial: {exc}", file=sys.stderr)
        return 2
    jobs = [(case, s, float(args.run_timeout)) for case in cases for s in SCHEDULERS]
    print(
        f"matrix: {len(cases)} adversarial cases ({', '.join(sorted(set(args.families)))}; "
        f"n <= {n_max}, seed {args.seed}) x {len(SCHEDULERS)} schedulers = {len(jobs)} runs, "
        f"{args.jobs} process(es)",
        file=sys.stderr,
        flush=True,
    )
    t0 = time.monotonic()
    outcomes, interrupted = run_all(jobs, args.jobs, args.quiet)
    report(outcomes)
    wall = time.monotonic() - t0
    busy = math.fsum(o.seconds for o in outcomes)
    print(
        f"\nwall time {wall:.0f}s, {busy:.0f}s of runs"
        f"{' (interrupted: partial matrix)' if interrupted else ''}"
    )
    if args.csv:
        write_csv(args.csv, outcomes)
        print(f"csv: {args.csv} ({len(outcomes)} rows)")
    return 130 if interrupted else 0


if __name__ == "__main__":
    sys.exit(main())
