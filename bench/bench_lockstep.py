"""The lock step's cost per Look and Looks/s (issues 20 and 30): a script that prints figures.

    python bench/bench_lockstep.py                          # this tree
    python bench/bench_lockstep.py --baseline /work/base    # and another checkout, side by side
    python bench/bench_lockstep.py --peer "CMD" --repeats 3 # and a peer's figures, in turn
    python bench/bench_lockstep.py --profile gathering:256  # cProfile one run instead

Every figure is in process through `fatswarm.run` (fsync, spread start), start-up excluded: the
clock runs from the first committed round to the last. `no-compute` is an algorithm that computes
nothing (every robot steps 1e-4 to its right), so its cost per Look is the emulator's alone;
`no-compute-views` is the same through the round hook (`compute_views`: the lock step builds the
round's views as one array and takes every move of the round in one call, as arrays:
`StraightMoves`). `gathering` and `oblot-go-to-cog` (on point robots) have the round hook;
`uniform-circle` plans each round once. `gathering+record` is `gathering` writing its run record
(`--record`, a file in a temporary folder): what the round line and its writer cost.
Each side runs in its own process, with its checkout's python (`--baseline-python`, default
DIR/../basevenv/bin/python if it exists), from its checkout's folder. `--peer CMD` runs a shell
command after each side, in turn, `--repeats` times: it must print one JSON object a line,
`{"n": N, "looks": L, "secs": S}` (Looks of robots that computed, seconds they took, warm), which
the table shows as the peer's Looks/s and whole cost per Look beside fatswarm's, with the ratios.
Asserts nothing.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Mapping, Sequence
from typing import Any, Final

import numpy as np

from fatswarm.domain import path as _path
from fatswarm.domain.path import Line, Path, Points

SIZES: Final = (16, 64, 256)
STEP: Final = 1e-4
ALGORITHMS: Final = (
    "no-compute",
    "no-compute-views",
    "gathering",
    "oblot-go-to-cog",
    "uniform-circle",
    "gathering+record",
)
RECORDED: Final = "+record"  # an algorithm's name and this: the same runs, each writing its record
MODELS: Final[Mapping[str, Mapping[str, Any]]] = {"oblot-go-to-cog": {"bodies": "points"}}
OWN: Final = {"no-compute": "NO_COMPUTE", "no-compute-views": "NO_COMPUTE_VIEWS"}


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


class NoComputeViews(NoCompute):
    """NoCompute with the round hook: every robot of a round steps right in one call, answered
    as arrays (`StraightMoves`: the hook's fast form)."""

    name = "no-compute-views"

    def compute_views(self, views: Points, params: None) -> Any:
        k = len(views)
        straight = getattr(_path, "StraightMoves", None)
        if straight is None:  # a checkout from before the fast form (--baseline): k Paths
            return [_RIGHT] * k
        ends = np.zeros((k, 2), dtype=np.float64)
        ends[:, 0] = STEP
        return straight(ends, np.ones(k, dtype=np.bool_))


_RIGHT: Final = Path((Line((STEP, 0.0)),))
NO_COMPUTE: Final = NoCompute()
NO_COMPUTE_VIEWS: Final = NoComputeViews()


class _Budget(Exception):
    """The time budget of a measurement is spent."""


class _Counter:
    """`on_round` of one run: adds the Looks of every round after the first, and the wall and
    CPU time since the round before, to `totals`; raises _Budget once `budget` seconds of wall
    time are spent."""

    def __init__(self, totals: dict[str, float], budget: float) -> None:
        self.totals, self.budget = totals, budget
        self.last: tuple[float, float] | None = None

    def __call__(self, report: Any) -> None:
        now = (time.perf_counter(), time.process_time())
        if self.last is not None:
            self.totals["looks"] += len(report.entry.active)
            self.totals["secs"] += now[0] - self.last[0]
            self.totals["cpu"] += now[1] - self.last[1]
        self.last = now
        if self.totals["secs"] >= self.budget:
            raise _Budget


def measure(algorithm: str, n: int, budget: float) -> dict[str, float]:
    """Looks, seconds and CPU seconds of lock-step runs of `algorithm` at n robots (seeds 0,
    1, ...), from each run's first committed round to its last, until `budget` seconds pass."""
    import fatswarm  # function-local: a worker imports the fatswarm of its own checkout

    name = algorithm.removesuffix(RECORDED)
    ref = _ref(name)
    totals = {"looks": 0.0, "secs": 0.0, "cpu": 0.0}
    seed = 0
    with tempfile.TemporaryDirectory() as folder:
        while totals["secs"] < budget:
            record = os.path.join(folder, f"{seed}.jsonl") if name != algorithm else None
            with contextlib.suppress(_Budget):
                fatswarm.run(
                    n,
                    algorithm=ref,
                    seed=seed,
                    start="spread",
                    scheduler="fsync",
                    on_round=_Counter(totals, budget),
                    record=record,
                    **MODELS.get(name, {}),
                )
            if record is not None and os.path.exists(record):
                os.unlink(record)
            seed += 1
    return totals


def _ref(algorithm: str) -> str:
    """How `fatswarm.run` loads `algorithm`: this file's own, or by name."""
    own = OWN.get(algorithm)
    return f"{os.path.abspath(__file__)}:{own}" if own else algorithm


def _worker() -> None:
    """Where fatswarm is, as JSON on stdout; then a figure for every line `ALGORITHM N BUDGET`
    on stdin (no Looks where this checkout cannot run it)."""
    import fatswarm  # function-local: the checkout it runs from

    print(json.dumps({"where": fatswarm.__file__}), flush=True)
    for line in sys.stdin:
        algorithm, n, budget = line.split()
        try:
            got = measure(algorithm, int(n), float(budget))
        except Exception as exc:  # an older checkout without this algorithm: a blank cell
            print(f"{algorithm}:{n}: {exc}", file=sys.stderr)
            got = {"looks": 0.0, "secs": 0.0, "cpu": 0.0}
        print(json.dumps(got), flush=True)


Figure = Mapping[str, float]  # looks, secs (wall), cpu (CPU seconds)


class _Process:
    """A measuring process that answers a line of JSON for every line it is sent."""

    def __init__(self, name: str, command: Sequence[str] | str, **kw: Any) -> None:
        self.name = name
        self.proc = subprocess.Popen(
            command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, **kw
        )

    def ask(self, line: str) -> dict[str, Any] | None:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        try:
            self.proc.stdin.write(line + "\n")
            self.proc.stdin.flush()
            answer = self.proc.stdout.readline()
        except OSError:
            answer = ""
        if not answer.strip():
            print(f"{self.name}: no answer to {line!r}", file=sys.stderr)
            return None
        got: dict[str, Any] = json.loads(answer)
        return got

    def close(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        try:
            self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


def side(python: str, checkout: str) -> _Process | None:
    """A worker measuring `checkout`, run by `python` from there; None if it measures another."""
    env = {**os.environ, "PYTHONPATH": checkout}
    worker = _Process(
        checkout, [python, os.path.abspath(__file__), "--worker"], cwd=checkout, env=env
    )
    assert worker.proc.stdout is not None
    first = worker.proc.stdout.readline()
    where = os.path.realpath(json.loads(first)["where"]) if first.strip() else "nowhere"
    if not where.startswith(os.path.realpath(checkout)):
        print(f"{checkout}: measures {where}, not this checkout", file=sys.stderr)
        worker.close()
        return None
    return worker


def _rate(figure: Figure | None, clock: str) -> float | None:
    """Looks per second of wall (`secs`) or CPU (`cpu`) time, or None if not measured."""
    if figure is None or not figure.get("looks") or not figure.get(clock):
        return None
    return figure["looks"] / figure[clock]


def _median(values: Sequence[float | None]) -> float | None:
    known = [v for v in values if v is not None]
    return statistics.median(known) if known else None


def _cell(rate: float | None, per_look: bool) -> str:
    if rate is None:
        return f"{'-':>11}"
    return f"{1e6 / rate:>11,.1f}" if per_look else f"{rate:>11,.0f}"


Results = Mapping[str, Mapping[str, Sequence[Figure | None]]]  # side -> figure key -> repeats


def report(results: Results, sides: Sequence[str], clock: str) -> None:
    """One table (medians of the repeats, on the `clock`): µs per Look of the no-compute
    figures, then Looks/s of every algorithm, by n; with a peer, its Looks/s and whole µs per
    Look, and fatswarm's ratios to it, each from a pair measured one after the other."""
    print(f"{'figure':<30}{'n':>5}" + "".join(f"{name:>11}" for name in sides))
    rows = [(a, True) for a in ALGORITHMS if a.startswith("no-compute")]
    rows += [(a, False) for a in ALGORITHMS]
    peer = "peer" in results
    if peer:
        rows += [("peer", True), ("peer", False)]
    for algorithm, per_look in rows:
        label = f"{algorithm} " + ("µs/Look" if per_look else "Looks/s")
        for n in SIZES:
            key = f"{algorithm}:{n}"
            cells = ""
            for name in sides:
                figures = results.get(name, {}).get(key, ())
                cells += _cell(_median([_rate(f, clock) for f in figures]), per_look)
            print(f"{label:<30}{n:>5}" + cells)
    if not peer:
        return
    print("this tree against the peer, median of the pairs: Looks/s over its; µs over its")
    for algorithm, per_look in rows:
        if algorithm == "peer":
            continue
        label = f"{algorithm} " + ("µs/peer's µs" if per_look else "x peer")
        for n in SIZES:
            ours = results["this tree"].get(f"{algorithm}:{n}", ())
            theirs = results["peer"].get(f"{algorithm}:{n}", ())
            ratios: list[float | None] = []
            for a, b in zip(ours, theirs, strict=False):
                ra, rb = _rate(a, clock), _rate(b, clock)
                ratios.append(None if ra is None or rb is None else ra / rb)
            ratio = _median(ratios)
            if ratio is not None and per_look:
                ratio = 1.0 / ratio
            print(f"{label:<30}{n:>5}" + (f"{ratio:>11.2f}" if ratio else f"{'-':>11}"))


def _spread(results: Results, clock: str) -> None:
    """Each repeat's Looks/s of every figure (the spread behind the medians)."""
    for name, figures in results.items():
        for key, repeats in sorted(figures.items()):
            rates = [_rate(f, clock) for f in repeats]
            print(f"  {name} {key}: " + " ".join(f"{r:,.0f}" if r else "-" for r in rates))


def profile(spec: str, rounds: int) -> None:
    """cProfile `rounds` rounds of one run (ALGORITHM:N), start-up included, top 25 by tottime."""
    import cProfile
    import pstats

    import fatswarm  # function-local: the checkout it runs from

    algorithm, n = spec.split(":")
    name = algorithm.removesuffix(RECORDED)
    prof = cProfile.Profile()
    with tempfile.TemporaryDirectory() as folder:
        prof.enable()
        fatswarm.run(
            int(n),
            algorithm=_ref(name),
            seed=0,
            start="spread",
            scheduler="fsync",
            max_rounds=rounds,
            record=os.path.join(folder, "run.jsonl") if name != algorithm else None,
            **MODELS.get(name, {}),
        )
        prof.disable()
    pstats.Stats(prof).sort_stats("tottime").print_stats(25)


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--baseline", metavar="DIR", help="also measure this checkout (a worktree)")
    p.add_argument("--baseline-python", metavar="PY", help="its python (default: see above)")
    p.add_argument("--budget", type=float, default=3.0, help="seconds per figure (default 3)")
    p.add_argument("--peer", metavar="CMD", help="a shell command measuring a peer (see above)")
    p.add_argument("--repeats", type=int, default=1, help="measure every figure so often")
    p.add_argument("--only", metavar="ALGORITHM", action="append", help="only these figures")
    p.add_argument("--profile", metavar="ALGORITHM:N", help="cProfile one run instead")
    p.add_argument("--rounds", type=int, default=150, help="rounds of the --profile run")
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.worker:
        _worker()
        return 0
    if args.profile:
        profile(args.profile, args.rounds)
        return 0
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    workers = {"this tree": side(sys.executable, here)}
    if args.baseline:
        default = os.path.join(os.path.dirname(os.path.abspath(args.baseline)), "basevenv")
        python = args.baseline_python or os.path.join(default, "bin", "python")
        python = python if os.path.exists(python) else sys.executable
        workers["baseline"] = side(python, args.baseline)
    peer = _Process("peer", args.peer, shell=True) if args.peer else None
    results: dict[str, dict[str, list[Figure | None]]] = {}
    algorithms = [a for a in ALGORITHMS if not args.only or a in args.only]
    try:
        for _ in range(args.repeats):  # each figure on every side in turn: the same load
            for n in SIZES:
                for algorithm in algorithms:
                    key = f"{algorithm}:{n}"
                    for name, worker in workers.items():
                        got = worker.ask(f"{algorithm} {n} {args.budget}") if worker else None
                        results.setdefault(name, {}).setdefault(key, []).append(got)
                    if peer is not None:  # right after: the pair meets the same load
                        got = peer.ask(f"{n} {args.budget}")
                        results.setdefault("peer", {}).setdefault(key, []).append(got)
                        results["peer"].setdefault(f"peer:{n}", []).append(got)
    finally:
        for worker in [*workers.values(), peer]:
            if worker is not None:
                worker.close()
    sides = list(workers) + (["peer"] if peer else [])
    for clock, what in (("secs", "wall clock"), ("cpu", "CPU time of the measuring process")):
        print(
            f"lock step, fsync, spread start, in process, start-up excluded; {what}; "
            f"{args.budget:g} s each, median of {args.repeats} repeat(s), sides in turn"
        )
        report(results, sides, clock)
        if args.repeats > 1:
            _spread(results, clock)
    return 0


if __name__ == "__main__":
    sys.exit(main())
