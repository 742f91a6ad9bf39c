"""The lock step's cost per Look and Looks/s (issues 20 and 30): a script that prints figures.

    python bench/bench_lockstep.py                          # this tree
    python bench/bench_lockstep.py --baseline /work/base    # and another checkout, side by side
    python bench/bench_lockstep.py --peer "CMD" --repeats 3 # and a peer's figures, in turn
    python bench/bench_lockstep.py --profile gathering:256  # cProfile one run instead

Every figure is in process through `fatswarm.run` (fsync, spread start), start-up excluded: the
clock runs from the first committed round to the last. `no-compute` is an algorithm that computes
nothing (every robot steps 1e-4 to its right), so its cost per Look is the emulator's alone;
`no-compute-views` is the same through the round hook (`compute_views`: the lock step builds the
round's views as one array and takes every path of the round in one call). `gathering` and
`oblot-go-to-cog` (on point robots) have the round hook; `uniform-circle` plans each round once.
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
import time
from collections.abc import Mapping, Sequence
from typing import Any, Final

from fatswarm.domain.path import Line, Path, Points

SIZES: Final = (16, 64, 256)
STEP: Final = 1e-4
ALGORITHMS: Final = (
    "no-compute",
    "no-compute-views",
    "gathering",
    "oblot-go-to-cog",
    "uniform-circle",
)
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
    """NoCompute with the round hook: every robot of a round steps right in one call."""

    name = "no-compute-views"

    def compute_views(self, views: Points, params: None) -> list[Path]:
        return [_RIGHT] * len(views)


_RIGHT: Final = Path((Line((STEP, 0.0)),))
NO_COMPUTE: Final = NoCompute()
NO_COMPUTE_VIEWS: Final = NoComputeViews()


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

    ref = _ref(algorithm)
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
                **MODELS.get(algorithm, {}),
            )
        seed += 1
    return totals


def _ref(algorithm: str) -> str:
    """How `fatswarm.run` loads `algorithm`: this file's own, or by name."""
    own = OWN.get(algorithm)
    return f"{os.path.abspath(__file__)}:{own}" if own else algorithm


def _worker(budget: float) -> None:
    """Every figure of this checkout as JSON on stdout."""
    out: dict[str, dict[str, float]] = {}
    for algorithm in ALGORITHMS:
        for n in SIZES:
            try:
                out[f"{algorithm}:{n}"] = measure(algorithm, n, budget)
            except Exception as exc:  # an older checkout without this algorithm: a blank cell
                print(f"{algorithm}:{n}: {exc}", file=sys.stderr)
                out[f"{algorithm}:{n}"] = {"looks": 0.0, "secs": 0.0}
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


Figures = Mapping[str, Mapping[str, float]]


def peer(command: str) -> dict[str, dict[str, float]] | None:
    """The peer's figures by n ("peer:N"), from the JSON lines `command` prints."""
    done = subprocess.run(command, shell=True, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        print(f"peer: failed: {done.stderr.strip()[-800:]}", file=sys.stderr)
        return None
    out: dict[str, dict[str, float]] = {}
    for line in done.stdout.splitlines():
        if line.strip().startswith("{"):
            got = json.loads(line)
            out[f"peer:{int(got['n'])}"] = {
                "looks": float(got["looks"]),
                "secs": float(got["secs"]),
            }
    return out


def _rate(figures: Figures | None, key: str) -> float | None:
    """Looks per second of `key`, or None if not measured."""
    if figures is None or key not in figures or figures[key]["looks"] == 0:
        return None
    return figures[key]["looks"] / figures[key]["secs"]


def _median(repeats: Sequence[Figures | None], key: str) -> float | None:
    rates = [r for r in (_rate(f, key) for f in repeats) if r is not None]
    return statistics.median(rates) if rates else None


def _cell(rate: float | None, per_look: bool) -> str:
    if rate is None:
        return f"{'-':>11}"
    return f"{1e6 / rate:>11,.1f}" if per_look else f"{rate:>11,.0f}"


def report(
    now: Sequence[Figures | None], base: Sequence[Figures | None], peers: Sequence[Figures | None]
) -> None:
    """The table (medians of the repeats): µs per Look of no-compute, then Looks/s of every
    algorithm, by n; with a peer, its Looks/s and whole µs per Look, and fatswarm's ratios."""
    columns = [("this tree", now)] + ([("baseline", base)] if base else [])
    print(f"{'figure':<30}{'n':>5}" + "".join(f"{name:>11}" for name, _ in columns))
    rows = [(a, True) for a in ALGORITHMS if a.startswith("no-compute")]
    rows += [(a, False) for a in ALGORITHMS]
    if peers:
        rows += [("peer", True), ("peer", False)]
    for algorithm, per_look in rows:
        label = f"{algorithm} " + ("µs/Look" if per_look else "Looks/s")
        for n in SIZES:
            cells = "".join(_cell(_median(f, f"{algorithm}:{n}"), per_look) for _, f in columns)
            print(f"{label:<30}{n:>5}" + cells)
    if not peers:
        return
    print("ratios, this tree against the peer (medians): Looks/s over the peer's; µs over its")
    for algorithm, per_look in rows:
        if algorithm == "peer":
            continue
        label = f"{algorithm} " + ("µs/peer's µs" if per_look else "x peer")
        for n in SIZES:
            ours, theirs = _median(now, f"{algorithm}:{n}"), _median(peers, f"peer:{n}")
            ratio = None if ours is None or theirs is None else ours / theirs
            if ratio is not None and per_look:
                ratio = 1.0 / ratio
            print(f"{label:<30}{n:>5}" + (f"{ratio:>11.2f}" if ratio else f"{'-':>11}"))


def _repeat(figures: Sequence[Figures | None], name: str) -> None:
    """Each repeat's Looks/s of every figure, on one line each (the spread behind the medians)."""
    for key in sorted({k for f in figures if f for k in f}):
        rates = [_rate(f, key) for f in figures]
        shown = " ".join(f"{r:,.0f}" if r else "-" for r in rates)
        print(f"  {name} {key}: {shown}")


def profile(spec: str, rounds: int) -> None:
    """cProfile `rounds` rounds of one run (ALGORITHM:N), start-up included, top 25 by tottime."""
    import cProfile
    import pstats

    import fatswarm  # function-local: the checkout it runs from

    algorithm, n = spec.split(":")
    prof = cProfile.Profile()
    prof.enable()
    fatswarm.run(
        int(n),
        algorithm=_ref(algorithm),
        seed=0,
        start="spread",
        scheduler="fsync",
        max_rounds=rounds,
        **MODELS.get(algorithm, {}),
    )
    prof.disable()
    pstats.Stats(prof).sort_stats("tottime").print_stats(25)


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--baseline", metavar="DIR", help="also measure this checkout (a worktree)")
    p.add_argument("--baseline-python", metavar="PY", help="its python (default: see above)")
    p.add_argument("--budget", type=float, default=3.0, help="seconds per figure (default 3)")
    p.add_argument("--peer", metavar="CMD", help="a shell command printing a peer's figures")
    p.add_argument("--repeats", type=int, default=1, help="measure every side so often")
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
    now: list[Figures | None] = []
    base: list[Figures | None] = []
    peers: list[Figures | None] = []
    for _ in range(args.repeats):  # in turn, so that each side meets the same load
        now.append(side(sys.executable, here, args.budget))
        if args.baseline:
            default = os.path.join(os.path.dirname(os.path.abspath(args.baseline)), "basevenv")
            python = args.baseline_python or os.path.join(default, "bin", "python")
            python = python if os.path.exists(python) else sys.executable
            base.append(side(python, args.baseline, args.budget))
        if args.peer:
            peers.append(peer(args.peer))
    print(
        f"lock step, fsync, spread start, in process, start-up excluded; {args.budget:g} s "
        f"each, median of {args.repeats} repeat(s), sides in turn"
    )
    report(now, base, peers)
    if args.repeats > 1:
        _repeat(now, "this tree")
        _repeat(base, "baseline")
        _repeat(peers, "peer")
    return 0


if __name__ == "__main__":
    sys.exit(main())
