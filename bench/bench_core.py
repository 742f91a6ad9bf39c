"""Evidence and speed of the pure core (issue 2, items 9 and 10): a script that prints figures.

    python bench/bench_core.py            # full matrix (>= 2,000 random starts x 3 schedulers)
    python bench/bench_core.py --quick    # a small subset, for a smoke run
    python bench/bench_core.py --speed-only

Every random run is replayable: `fatswarm run --lockstep -n N -a A --seed S --start KIND
--scheduler X` builds the very same start, frames and schedule. Needs the `bench` extra (scipy)
for the distance lower bound; without it that column is left out.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import multiprocessing as mp
import os
import sys
import time
from collections import Counter, defaultdict
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np

from fatswarm.agent import algorithm, expansion, formation, planning
from fatswarm.agent.params import Params
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.lockstep import RoundReport, run_lockstep, start_lockstep
from fatswarm.deploy.scenarios.starts import KINDS, degenerate_starts, random_start
from fatswarm.domain.path import Path, Points

SCHEDULERS = ("fsync", "ssync", "centralized")
SIZES = tuple(range(2, 41))  # n from 2 to 40
SIDES = (4.0, 4.0, 3.2, 6.0)  # a: mostly the default, some just above 3 (a* = 4), some wide
FULL_SEEDS = 11  # 39 sizes x 5 kinds x 11 seeds = 2,145 random starts
QUICK_SEEDS = 1
DEGENERATE_SEEDS = 10  # each named start under this many seeds: the seed sets the private X flips
QUICK_SIZES = (2, 3, 4, 5, 7, 10, 16, 24)
SPEED_SIZES = (16, 64, 256)
PROGRESS_SECONDS = 2.0
REPEATS = 3  # timing passes over the sampled views; the fastest counts (least disturbed)


@dataclass(frozen=True, slots=True)
class Case:
    """One run of the matrix: a start family, its parameters and the scheduler."""

    family: str  # "clustered", ..., or "degenerate:<name>"
    n: int
    a: float
    seed: int
    scheduler: str
    positions: tuple[tuple[float, float], ...] | None = None  # degenerate starts only

    def start(self) -> Points:
        if self.positions is not None:
            return np.asarray(self.positions, dtype=np.float64)
        return random_start(self.n, self.seed, self.family, self.a)

    def replay(self) -> str:
        if self.positions is not None:
            return f"{self.family} (world.starts.degenerate_starts) --seed {self.seed}"
        return (
            f"fatswarm run --lockstep -n {self.n} -a {self.a:g} --seed {self.seed} "
            f"--start {self.family} --scheduler {self.scheduler}"
        )


@dataclass(frozen=True, slots=True)
class Outcome:
    """What one run gave."""

    case: Case
    status: str
    rounds: int
    epochs: int
    moves: int
    distance: float
    lower_bound: float | None
    collisions: int
    seconds: float
    error: str | None = None


def build_matrix(quick: bool, seeds: int | None = None) -> list[Case]:
    """Random starts (sizes x kinds x seeds) and the named degenerate starts, x schedulers."""
    sizes = QUICK_SIZES if quick else SIZES
    if seeds is None:
        seeds = QUICK_SEEDS if quick else FULL_SEEDS
    cases: list[Case] = []
    index = 0
    for seed_slot in range(seeds):
        for kind in KINDS:
            for n in sizes:
                a = SIDES[index % len(SIDES)]
                seed = 1000 * seed_slot + index
                index += 1
                cases.extend(Case(kind, n, a, seed, s) for s in SCHEDULERS)
    for name, (pts, a) in degenerate_starts().items():
        frozen = tuple((float(x), float(y)) for x, y in pts)
        for seed in range(2 if quick else DEGENERATE_SEEDS):
            cases.extend(
                Case(f"degenerate:{name}", len(pts), a, seed, s, frozen) for s in SCHEDULERS
            )
    return cases


def lower_bound(initial: Points, final: Points) -> float | None:
    """Least total distance of any matching of starts to final positions (scipy), or None."""
    try:
        from scipy.optimize import linear_sum_assignment
    except ImportError:
        return None
    cost = np.hypot(
        initial[:, None, 0] - final[None, :, 0], initial[:, None, 1] - final[None, :, 1]
    )
    rows, cols = linear_sum_assignment(cost)
    return float(cost[rows, cols].sum())


def run_case(case: Case) -> Outcome:
    """Run one case in lockstep (also the worker function of the process pool)."""
    t0 = time.perf_counter()
    try:
        start = case.start()
        result = run_lockstep(
            start,
            Params(case.n, case.a),
            make_scheduler(case.scheduler, case.n, case.seed),
            seed=case.seed,
        )
    except Exception as exc:  # a crash is a finding: report it, keep the matrix going
        return Outcome(
            case,
            "error",
            0,
            0,
            0,
            0.0,
            None,
            0,
            time.perf_counter() - t0,
            f"{type(exc).__name__}: {exc}",
        )
    lb = lower_bound(start, result.positions) if result.status == "formed" else None
    return Outcome(
        case,
        result.status,
        result.rounds,
        result.epochs,
        result.moves,
        result.total_distance,
        lb,
        result.collisions,
        time.perf_counter() - t0,
    )


def run_all(cases: Sequence[Case], jobs: int, quiet: bool) -> list[Outcome]:
    """All cases, over `jobs` spawned processes, with a progress line on stderr."""
    outcomes: list[Outcome] = []
    started = time.monotonic()
    last = started

    def note(done: int) -> None:
        nonlocal last
        now = time.monotonic()
        if quiet or (now - last < PROGRESS_SECONDS and done < len(cases)):
            return
        last = now
        print(f"  runs {done}/{len(cases)}  {now - started:.0f}s", file=sys.stderr, flush=True)

    stream: Iterable[Outcome]
    if jobs <= 1:
        stream = map(run_case, cases)
        try:
            for out in stream:
                outcomes.append(out)
                note(len(outcomes))
        except KeyboardInterrupt:
            print(f"interrupted after {len(outcomes)} of {len(cases)} runs", file=sys.stderr)
        return outcomes
    # Long runs first so the pool does not finish on one straggler.
    order = sorted(cases, key=lambda c: -c.n * (c.n if c.scheduler == "centralized" else 1))
    with mp.get_context("spawn").Pool(jobs) as pool:
        try:
            for out in pool.imap_unordered(run_case, order, chunksize=4):
                outcomes.append(out)
                note(len(outcomes))
        except KeyboardInterrupt:  # Ctrl-C: report what is done
            pool.terminate()
            print(f"interrupted after {len(outcomes)} of {len(cases)} runs", file=sys.stderr)
    return outcomes


def _stats(values: Sequence[float]) -> str:
    if not values:
        return "-"
    arr = np.asarray(values, dtype=np.float64)
    return " / ".join(
        f"{v:.0f}" if v >= 100 else f"{v:.3g}"
        for v in (np.median(arr), np.percentile(arr, 95), arr.max())
    )


def report(outcomes: Sequence[Outcome], out: Any = sys.stdout) -> None:
    """Per scheduler and per family group: success, collisions, stalls, rounds, epochs, cost."""
    print(f"\n== evidence: {len(outcomes)} runs ==", file=out)
    if not outcomes:
        return
    header = (
        f"{'group':<26}{'runs':>6}{'formed':>9}{'coll':>6}{'stall':>6}{'cap':>5}{'err':>5}"
        f"  {'rounds med/p95/max':<22}{'epochs med/p95/max':<20}"
        f"{'moves/robot':<20}{'dist/LB med/p95/max':<20}"
    )
    groups: dict[str, list[Outcome]] = defaultdict(list)
    for o in outcomes:
        family = "degenerate" if o.case.family.startswith("degenerate:") else o.case.family
        groups[f"{o.case.scheduler} all"].append(o)
        groups[f"{o.case.scheduler} {family}"].append(o)
    print(header, file=out)
    for name in sorted(groups, key=lambda g: (SCHEDULERS.index(g.split()[0]), g)):
        rows = groups[name]
        statuses = Counter(o.status for o in rows)
        ratios = [o.distance / lb for o in rows if (lb := o.lower_bound or 0.0) > 1e-9]
        print(
            f"{name:<26}{len(rows):>6}{100 * statuses['formed'] / len(rows):>8.1f}%"
            f"{sum(o.collisions for o in rows):>6}{statuses['stalled']:>6}"
            f"{statuses['max_rounds']:>5}{statuses['error']:>5}"
            f"  {_stats([o.rounds for o in rows]):<22}{_stats([o.epochs for o in rows]):<20}"
            f"{_stats([o.moves / o.case.n for o in rows]):<20}{_stats(ratios):<20}",
            file=out,
        )
    if all(o.lower_bound is None for o in outcomes):
        print("(dist/LB needs scipy: pip install 'fatswarm[bench]')", file=out)
    failures = [o for o in outcomes if o.status != "formed" or o.collisions]
    print(f"\nnot formed or colliding: {len(failures)}", file=out)
    for o in sorted(failures, key=lambda o: (o.case.n, o.case.family))[:40]:
        detail = o.error or f"{o.status}, rounds {o.rounds}, collisions {o.collisions}"
        print(f"  {detail}: {o.case.replay()}", file=out)
    if len(failures) > 40:
        print(f"  ... and {len(failures) - 40} more", file=out)


# ---------------------------------------------------------------------------------------------
# Speed (issue 2, item 10)


class _Budget(Exception):
    """Raised from the round callback when a speed run has used its time."""


def looks_per_second(
    n: int, budget: float, compute: Callable[[Points, Params], Path] | None = None
) -> tuple[int, float]:
    """Looks and seconds of a lockstep fsync run from a clustered start, cut after `budget` s.

    `compute` None: the default (shared plans); `algorithm.compute`: every robot computes alone.
    """
    start = random_start(n, 0, "clustered")
    looks = 0
    t0 = time.perf_counter()

    def count(report: RoundReport) -> None:
        nonlocal looks
        looks += len(report.entry.active)
        if time.perf_counter() - t0 > budget:
            raise _Budget

    with contextlib.suppress(_Budget):
        run_lockstep(
            start, Params(n), make_scheduler("fsync", n, 0), seed=0, on_round=count, compute=compute
        )
    return looks, time.perf_counter() - t0


BASELINE_SNIPPET = """
import importlib, sys, time, contextlib
pkg = sys.argv[3]  # "" for a checkout from before the fatswarm namespace, else "fatswarm."
Params = importlib.import_module(pkg + "agent.params").Params
make_scheduler = importlib.import_module(pkg + "coordinator.schedule").make_scheduler
run_lockstep = importlib.import_module(pkg + "deploy.lockstep").run_lockstep
random_start = importlib.import_module(pkg + "world.starts").random_start
n, budget = int(sys.argv[1]), float(sys.argv[2])
start = random_start(n, 0, "clustered"); looks = 0; t0 = time.perf_counter()
class Stop(Exception): pass
def count(report):
    global looks
    looks += len(report.active)
    if time.perf_counter() - t0 > budget: raise Stop
with contextlib.suppress(Stop):
    run_lockstep(start, Params(n), make_scheduler("fsync", n, 0), seed=0, on_round=count)
print(looks, time.perf_counter() - t0, importlib.import_module(pkg + "deploy.lockstep").__file__)
"""


def baseline_looks_per_second(checkout: str, n: int, budget: float) -> float | None:
    """Looks/s of another checkout's lockstep (e.g. a git worktree of an older commit), same run."""
    import subprocess

    env = {**os.environ, "PYTHONPATH": checkout}
    pkg = "fatswarm." if os.path.isdir(os.path.join(checkout, "fatswarm")) else ""
    done = subprocess.run(
        [sys.executable, "-c", BASELINE_SNIPPET, str(n), str(budget), pkg],
        cwd=checkout,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0:
        print(
            f"baseline at {checkout} failed: {done.stderr.strip().splitlines()[-1:]}",
            file=sys.stderr,
        )
        return None
    looks, secs, where = done.stdout.split()
    if not os.path.realpath(where).startswith(os.path.realpath(checkout)):
        print(f"baseline: {where} is not from {checkout}", file=sys.stderr)
        return None
    return int(looks) / float(secs)


# PHASE HOOK: until agent/algorithm.py exposes its phases, compute's time is split by wrapping the
# helpers it calls (SEC; path checks). Replace `_PHASE_WRAPS` with the lead's phase functions
# when they land. Wrapping adds a little overhead to every call: the split is approximate.
_PLANNING_MODULES: tuple[ModuleType, ...] = (algorithm, planning, expansion, formation)
_PHASE_WRAPS: dict[str, tuple[str, ...]] = {
    "sec": ("sec",),
    "path checks": ("is_free", "segment_distances"),
}


def _sample_views(n: int, count: int) -> list[Points]:
    """Views robots actually see during a run (clustered start, centralized), one per sampled
    Look: the run's first `count` (fewer if it ends first). The run is advanced a step at a time
    and left once they are in, so no compute is made to fail to stop it (the engine would count
    and log that as the algorithm's failure)."""
    views: list[Points] = []

    def keep(view: Points, params: Params) -> Path:
        if len(views) < count:
            views.append(view.copy())
        return algorithm.compute(view, params)

    # Centralized: one Look a round, so the sample spans the phases of the run, not one round.
    start = random_start(n, 1, "clustered")
    run = start_lockstep(
        start, Params(n), make_scheduler("centralized", n, 1), seed=1, compute=keep
    )
    while len(views) < count and run.advance():
        pass
    return views


def compute_split(n: int, count: int) -> dict[str, float]:
    """Mean microseconds per compute call, overall and per wrapped phase, over sampled views."""
    views = _sample_views(n, count)
    params = Params(n)
    spent: dict[str, float] = dict.fromkeys(_PHASE_WRAPS, 0.0)
    originals: dict[tuple[ModuleType, str], Callable[..., Any]] = {}

    def wrap(phase: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def timed(*args: Any, **kwargs: Any) -> Any:
            t = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                spent[phase] += time.perf_counter() - t

        return timed

    def timed_pass() -> float:
        t0 = time.perf_counter()
        for view in views:
            algorithm.compute(view, params)
        return time.perf_counter() - t0

    timed_pass()  # warm-up
    plain = min(timed_pass() for _ in range(REPEATS))
    try:
        for phase, names in _PHASE_WRAPS.items():
            for module in _PLANNING_MODULES:  # wherever the algorithm's phases call them from
                for name in names:
                    if hasattr(module, name):
                        originals[module, name] = getattr(module, name)
                        setattr(module, name, wrap(phase, originals[module, name]))
        wrapped = math.inf
        for _ in range(REPEATS):  # keep the phase times of the fastest pass
            spent.update(dict.fromkeys(spent, 0.0))
            this = timed_pass()
            if this < wrapped:
                wrapped, best = this, dict(spent)
        spent = best
    finally:
        for (module, name), fn in originals.items():
            setattr(module, name, fn)
    calls = max(1, len(views))
    split = {"compute (unwrapped)": 1e6 * plain / calls}
    for phase, secs in spent.items():
        split[phase] = 1e6 * secs / calls
    split["planning (rest)"] = 1e6 * (wrapped - sum(spent.values())) / calls
    return split


def speed(quick: bool, baseline: str | None = None, out: Any = sys.stdout) -> None:
    """Looks/s of the lockstep runner at n = 16, 64, 256 (fsync), time per compute call by phase.

    Three ways side by side: shared plans (the default: one canonical form and one plan a round),
    every robot computing alone (what a networked agent does), and `baseline`, another checkout.
    """
    budget = 3.0 if quick else 15.0
    print("\n== speed (lockstep, fsync, clustered start, one process) ==", file=out)
    head = f"{'n':<5} {'shared plans':>14} {'every robot':>12}"
    print(head + (f" {'baseline':>10}" if baseline else "") + "   Looks/s", file=out)
    for n in SPEED_SIZES:
        looks, secs = looks_per_second(n, budget)
        alone, alone_secs = looks_per_second(n, budget, algorithm.compute)
        row = f"{n:<5} {looks / secs:>14,.0f} {alone / alone_secs:>12,.0f}"
        if baseline:
            base = baseline_looks_per_second(baseline, n, budget)
            row += f" {base:>10,.0f}" if base is not None else f" {'failed':>10}"
        print(row, file=out)
    print(
        "\ncompute per call, microseconds (mean over sampled views; split approximate):", file=out
    )
    for n in SPEED_SIZES:
        split = compute_split(n, 60 if quick else 300)
        parts = "  ".join(f"{k} {v:,.0f}" for k, v in split.items())
        print(f"n={n:<4} {parts}", file=out)


def _iter_args(argv: Sequence[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--quick", action="store_true", help="a small subset of the matrix")
    p.add_argument("--jobs", type=int, default=2, help="worker processes (spawn; default 2)")
    p.add_argument(
        "--seeds",
        type=int,
        default=None,
        metavar="K",
        help=f"seeds per (kind, n) (default {FULL_SEEDS}; --quick {QUICK_SEEDS})",
    )
    p.add_argument("--speed-only", action="store_true", help="skip the evidence matrix")
    p.add_argument("--evidence-only", action="store_true", help="skip the speed part")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    p.add_argument(
        "--baseline",
        metavar="DIR",
        help="also time the lockstep of another checkout (e.g. `git worktree add DIR "
        "REV`), in the same run",
    )
    return p.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    args = _iter_args(argv)
    if not args.speed_only:
        cases = build_matrix(args.quick, args.seeds)
        random_starts = len({(c.family, c.n, c.seed) for c in cases if c.positions is None})
        print(
            f"matrix: {random_starts} random starts + {len(degenerate_starts())} degenerate "
            f"(several seeds each), "
            f"x {len(SCHEDULERS)} schedulers = {len(cases)} runs, {args.jobs} process(es)",
            file=sys.stderr,
        )
        t0 = time.monotonic()
        outcomes = run_all(cases, args.jobs, args.quiet)
        report(outcomes)
        print(f"\nmatrix wall time {time.monotonic() - t0:.0f}s", file=sys.stdout)
    if not args.evidence_only:
        speed(args.quick, args.baseline)
    return 0


if __name__ == "__main__":
    sys.exit(main())
