"""The lock-step engine's own cost per Look (issue 20, item 1): a script that prints figures.

    python bench/bench_lockstep.py                          # this tree
    python bench/bench_lockstep.py --baseline /work/base    # and another checkout, side by side
    python bench/bench_lockstep.py --profile gathering:256  # cProfile one run instead

Every figure is in process through `fatswarm.run` (fsync, spread start), start-up excluded: the
clock runs from the first committed round to the last. `no-compute` is an algorithm that computes
nothing (every robot steps 1e-4 to its right), so its cost per Look is the emulator's alone.
Each side runs in its own process, with its checkout's python (`--baseline-python`, default
DIR/../basevenv/bin/python if it exists), from its checkout's folder. Asserts nothing.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import subprocess
import sys
import time
from collections.abc import Mapping, Sequence
from typing import Any, Final

from fatswarm.domain.path import Line, Path, Points

SIZES: Final = (16, 64, 256)
STEP: Final = 1e-4
ALGORITHMS: Final = ("no-compute", "gathering", "uniform-circle")


class NoCompute:
    """Every robot steps STEP to the right of its own frame, whatever it sees."""

    name = "no-compute"
    summary = "a benchmark: every robot steps 1e-4 to its right, computing nothing"
    parameters: tuple[Any, ...] = ()

    def make_params(self, n: int, values: Mapping[str, Any]) -> None:
        return None

    def compute(self, view: Points, params: None) -> Path:
        return _RIGHT

    def goal(self, positions: Points, params: None) -> bool:
        return False


_RIGHT: Final = Path((Line((STEP, 0.0)),))
NO_COMPUTE: Final = NoCompute()


class _Budget(Exception):
    """The time budget of a measurement is spent."""


class _Counter:
    """`on_round` of one run: adds the Looks of every round after the first and the time since
    the round before to `totals`; raises _Budget once `budget` seconds are spent."""

    def __init__(self, totals: dict[str, float], budget: float) -> None:
        self.totals, self.budget = totals, budget
        self.last: float | None = None

    def __call__(self, report: Any) -> None:
        now = time.perf_counter()
        if self.last is not None:
            self.totals["looks"] += len(report.entry.active)
            self.totals["secs"] += now - self.last
        self.last = now
        if self.totals["secs"] >= self.budget:
            raise _Budget


def measure(algorithm: str, n: int, budget: float) -> dict[str, float]:
    """Looks and seconds of lock-step runs of `algorithm` at n robots (seeds 0, 1, ...), from
    each run's first committed round to its last, until `budget` seconds are spent."""
    import fatswarm  # function-local: a worker imports the fatswarm of its own checkout

    ref = f"{os.path.abspath(__file__)}:NO_COMPUTE" if algorithm == "no-compute" else algorithm
    totals = {"looks": 0.0, "secs": 0.0}
    seed = 0
    while totals["secs"] < budget:
        with contextlib.suppress(_Budget):
            fatswarm.run(
                n,
                algorithm=ref,
                seed=seed,
                start="spread",
                scheduler="fsync",
                on_round=_Counter(totals, budget),
            )
        seed += 1
    return totals


def _worker(budget: float) -> None:
    """Every figure of this checkout as JSON on stdout."""
    out: dict[str, dict[str, float]] = {}
    for algorithm in ALGORITHMS:
        for n in SIZES:
            out[f"{algorithm}:{n}"] = measure(algorithm, n, budget)
    import fatswarm  # function-local: the checkout it ran from

    print(json.dumps({"figures": out, "where": fatswarm.__file__}))


def side(python: str, checkout: str, budget: float) -> dict[str, dict[str, float]] | None:
    """The figures of `checkout`, measured in a process of `python` run from there."""
    env = {**os.environ, "PYTHONPATH": checkout}
    done = subprocess.run(
        [python, os.path.abspath(__file__), "--worker", "--budget", str(budget)],
        cwd=checkout,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0:
        print(f"{checkout}: failed: {done.stderr.strip()[-800:]}", file=sys.stderr)
        return None
    got = json.loads(done.stdout.strip().splitlines()[-1])
    where = os.path.realpath(got["where"])
    if not where.startswith(os.path.realpath(checkout)):
        print(f"{checkout}: measured {where}, not this checkout", file=sys.stderr)
        return None
    figures: dict[str, dict[str, float]] = got["figures"]
    return figures


def _cell(figures: Mapping[str, dict[str, float]] | None, key: str, per_look: bool) -> str:
    if figures is None or figures[key]["looks"] == 0:
        return f"{'-':>10}"
    looks, secs = figures[key]["looks"], figures[key]["secs"]
    return f"{1e6 * secs / looks:>10,.1f}" if per_look else f"{looks / secs:>10,.0f}"


def report(now: Mapping[str, Any] | None, base: Mapping[str, Any] | None, baseline: bool) -> None:
    """The table: no-compute µs per Look, then Looks/s of every algorithm, by n."""
    head = f"{'figure':<28}{'n':>5}{'this tree':>10}" + (f"{'baseline':>10}" if baseline else "")
    print(head)
    for algorithm in ALGORITHMS:
        for per_look in (True, False) if algorithm == "no-compute" else (False,):
            label = f"{algorithm} " + ("µs/Look" if per_look else "Looks/s")
            for n in SIZES:
                row = f"{label:<28}{n:>5}" + _cell(now, f"{algorithm}:{n}", per_look)
                print(row + (_cell(base, f"{algorithm}:{n}", per_look) if baseline else ""))


def profile(spec: str, rounds: int) -> None:
    """cProfile `rounds` rounds of one run (ALGORITHM:N), start-up included, top 25 by tottime."""
    import cProfile
    import pstats

    import fatswarm  # function-local: the checkout it runs from

    algorithm, n = spec.split(":")
    ref = f"{os.path.abspath(__file__)}:NO_COMPUTE" if algorithm == "no-compute" else algorithm
    prof = cProfile.Profile()
    prof.enable()
    fatswarm.run(
        int(n), algorithm=ref, seed=0, start="spread", scheduler="fsync", max_rounds=rounds
    )
    prof.disable()
    pstats.Stats(prof).sort_stats("tottime").print_stats(25)


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--baseline", metavar="DIR", help="also measure this checkout (a worktree)")
    p.add_argument("--baseline-python", metavar="PY", help="its python (default: see above)")
    p.add_argument("--budget", type=float, default=3.0, help="seconds per figure (default 3)")
    p.add_argument("--profile", metavar="ALGORITHM:N", help="cProfile one run instead")
    p.add_argument("--rounds", type=int, default=150, help="rounds of the --profile run")
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.worker:
        _worker(args.budget)
        return 0
    if args.profile:
        profile(args.profile, args.rounds)
        return 0
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    now = side(sys.executable, here, args.budget)
    base = None
    if args.baseline:
        default = os.path.join(os.path.dirname(os.path.abspath(args.baseline)), "basevenv")
        python = args.baseline_python or os.path.join(default, "bin", "python")
        base = side(
            python if os.path.exists(python) else sys.executable, args.baseline, args.budget
        )
    print(f"lock step, fsync, spread start, in process, start-up excluded; {args.budget:g} s each")
    report(now, base, bool(args.baseline))
    return 0


if __name__ == "__main__":
    sys.exit(main())
