"""A lock-step round's fixed cost (issue 30): what a round of `no-compute-views` (fsync, spread
start) costs outside the world's commit (`Rounds.commit_open_round`: physics and the books) and
the lock step's round hook (`_Bus._act_at_once`: views, paths, holds), i.e. the coordinator core,
the driver loop, the control requests and replies, the moves notice and the effects.

    python bench/bench_round_overhead.py                        # this tree, n = 16 and 64
    python bench/bench_round_overhead.py --baseline /work/base2 # and another checkout, paired
    python bench/bench_round_overhead.py --callgrind            # instructions (valgrind), not CPU

CPU time: each side runs in its own process from its own checkout, the sides in turn, `--repeats`
times; a round's cost is (CPU of a run of R rounds - CPU of a run of R / 10) / (0.9 R), so start-up
is left out; `outside` subtracts the CPU spent inside the two functions (timed with
`time.process_time` around each call: its own cost, about 1 to 4 µs a round, counts as outside).
`--callgrind` counts instructions instead (repeatable whatever the load): whole runs, and the two
functions alone (called through `itertools.starmap`, valgrind's `--toggle-collect=starmap_next`).
Asserts nothing.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from itertools import starmap
from typing import Any

INSIDE = (("fatswarm.world.rounds", "Rounds", "commit_open_round"),
          ("fatswarm.deploy.engine.lockstep", "_Bus", "_act_at_once"))  # fmt: skip


def _wrap(timed: Callable[[Callable[..., Any]], Callable[..., Any]]) -> list[str]:
    """Wrap each function of INSIDE (where this checkout has it) with `timed`; the ones missing."""
    import importlib

    missing = []
    for module, cls, name in INSIDE:
        owner = getattr(importlib.import_module(module), cls, None)
        if owner is None or not hasattr(owner, name):
            missing.append(f"{module}.{cls}.{name}")
            continue
        setattr(owner, name, timed(getattr(owner, name)))
    return missing


def _run(n: int, rounds: int) -> None:
    import fatswarm  # function-local: the checkout this worker runs from

    sys.path.insert(0, os.path.join(os.getcwd(), "bench"))
    import bench_lockstep

    fatswarm.run(
        n,
        algorithm=bench_lockstep._ref("no-compute-views"),
        seed=0,
        start="spread",
        scheduler="fsync",
        max_rounds=rounds,
    )


def _cpu_worker(n: int, rounds: int) -> None:
    """Print the CPU seconds of a run of `rounds` rounds, whole and inside INSIDE."""
    inside = [0.0]
    clock = time.process_time

    def timed(f: Callable[..., Any]) -> Callable[..., Any]:
        def w(*args: Any) -> Any:
            t = clock()
            try:
                return f(*args)
            finally:
                inside[0] += clock() - t

        return w

    missing = _wrap(timed)
    _run(n, 3)  # warm
    t = clock()
    _run(n, rounds)
    print(json.dumps({"whole": clock() - t, "inside": inside[0], "missing": missing}))


def _cg_worker(n: int, rounds: int) -> None:
    """A run of `rounds` rounds with INSIDE called through `starmap` (valgrind toggles on it)."""

    def through_starmap(f: Callable[..., Any]) -> Callable[..., Any]:
        return lambda *args: next(starmap(f, (args,)))

    _wrap(through_starmap)
    _run(n, rounds)


def _side(checkout: str, python: str, args: Sequence[str], prefix: Sequence[str] = ()) -> str:
    env = {**os.environ, "PYTHONPATH": checkout, "PYTHONHASHSEED": "0"}
    done = subprocess.run(
        [*prefix, python, os.path.abspath(__file__), *args],
        cwd=checkout,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return done.stdout + done.stderr


def _cpu(checkout: str, python: str, n: int, rounds: int) -> tuple[float, float]:
    """µs a round, whole and outside INSIDE, start-up left out."""
    long, short = (
        json.loads(_side(checkout, python, ["--cpu-worker", str(n), str(r)]).splitlines()[0])
        for r in (rounds, rounds // 10)
    )
    if long["missing"]:
        print(f"{checkout}: has no {', '.join(long['missing'])}", file=sys.stderr)
    span = rounds - rounds // 10
    whole = (long["whole"] - short["whole"]) / span * 1e6
    inside = (long["inside"] - short["inside"]) / span * 1e6
    return whole, whole - inside


def _instructions(checkout: str, python: str, n: int, rounds: int, toggle: bool) -> int:
    grind = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null"]
    if toggle:
        grind.append("--toggle-collect=starmap_next")
    out = _side(checkout, python, ["--cg-worker", str(n), str(rounds)], grind)
    line = next(x for x in out.splitlines() if "Collected" in x)
    return int(line.split()[-1])


def _callgrind(checkout: str, python: str, n: int, rounds: int) -> tuple[float, float]:
    """Instructions a round, whole and outside INSIDE, start-up left out."""
    short = rounds // 10
    whole = _instructions(checkout, python, n, rounds, False)
    whole -= _instructions(checkout, python, n, short, False)
    inside = _instructions(checkout, python, n, rounds, True)
    inside -= _instructions(checkout, python, n, short, True)
    span = rounds - short
    return whole / span, (whole - inside) / span


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[16, 64])
    p.add_argument("--rounds", type=int, default=1000, help="rounds a run (default 1000)")
    p.add_argument("--repeats", type=int, default=3, help="CPU runs of each side (default 3)")
    p.add_argument("--baseline", metavar="DIR", help="another checkout, measured in turn")
    p.add_argument("--baseline-python", default=sys.executable, metavar="PYTHON")
    p.add_argument("--callgrind", action="store_true", help="count instructions (valgrind)")
    p.add_argument("--cpu-worker", nargs=2, type=int, help=argparse.SUPPRESS)
    p.add_argument("--cg-worker", nargs=2, type=int, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.cpu_worker:
        _cpu_worker(*args.cpu_worker)
        return
    if args.cg_worker:
        _cg_worker(*args.cg_worker)
        return
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    sides = [("this", here, sys.executable)]
    if args.baseline:
        sides.append(("baseline", os.path.abspath(args.baseline), args.baseline_python))
    unit = "instructions" if args.callgrind else "µs CPU"
    print(f"no-compute-views, fsync, {args.rounds} rounds: {unit} a round, whole | outside")
    for n in args.sizes:
        got: dict[str, list[tuple[float, float]]] = {name: [] for name, _, _ in sides}
        for _ in range(1 if args.callgrind else args.repeats):
            for name, checkout, python in sides:
                measure = _callgrind if args.callgrind else _cpu
                got[name].append(measure(checkout, python, n, args.rounds))
        for name, _, _ in sides:
            whole = statistics.median(w for w, _ in got[name])
            outside = statistics.median(o for _, o in got[name])
            print(f"n = {n:4d}  {name:8s}  {whole:12,.1f} | {outside:10,.1f}")


if __name__ == "__main__":
    main()
