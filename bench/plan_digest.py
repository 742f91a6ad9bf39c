"""Bit-for-bit equivalence harness of the paper's plan: digests of `plan` and `compute` over many
configurations that real runs reach, to compare one checkout with another (issue 20, item 2).

    python bench/plan_digest.py --save /work/plans/pre.json          # collect, digest, save
    python bench/plan_digest.py --compare /work/plans/pre.json       # 0 differences or exit 1
    python bench/plan_digest.py --quick --save /tmp/q.json           # a smaller collection
    python bench/plan_digest.py --speed                              # us per compute call
    python bench/plan_digest.py --speed --against /work/pre          # the same, paired with pre
    python bench/plan_digest.py --show ID --compare /work/plans/pre.json   # one configuration

Against another checkout, run the script by absolute path from that checkout with it on the path:
`cd /work/pre && PYTHONPATH=/work/pre python /work/main/bench/plan_digest.py --save F`.

Collection runs lock-step runs (`start_lockstep`, shared plans) with `algorithm.plan` wrapped, and
keeps every distinct canonical configuration (canonical points, a) a plan is made on: random starts
of every kind (sizes 2 to 260), the adversarial families (sizes 2 to 256), the named degenerate
starts, under fsync, ssync and centralized, and asynchronous and non-rigid runs (robots Look while
others are part way along a path), with fixed seeds, so that the same list comes out of
every checkout whose plans agree. `--save FILE` writes FILE (JSON: one digest per configuration)
and FILE with suffix .npz (the configurations themselves). `--compare FILE` digests exactly the
saved configurations in this checkout, so that one differing plan cannot change which
configurations are compared, and names the first differences (exit 1 if any). The full collection
is about 70,000 configurations (4,300 runs, 3-5 minutes on 2 cores; a compare takes 1-2 minutes),
--quick about 2,800 (10 s).

A configuration's digest covers `plan(points, Params(n, a))`: phase, kind and every move in order,
each segment's floats as float.hex; and `compute(view, params)` of a few observers (the robots that
move, and two drawn ones), each in a random frame: the others relative to it, X negated or not,
rows shuffled, with a seeded generator per configuration.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import multiprocessing as mp
import os
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path as FsPath
from typing import Any, Final

import numpy as np

from fatswarm.agent import algorithm
from fatswarm.agent.params import Params
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.deploy.engine.lockstep import start_lockstep
from fatswarm.deploy.scenarios.adversarial import (
    FAMILIES,
    SIDES,
    adversarial_cases,
    build_adversarial,
    family_range,
)
from fatswarm.deploy.scenarios.starts import KINDS, degenerate_starts, random_start
from fatswarm.domain.path import Line, Path, Points

SCHEDULERS: Final = ("fsync", "ssync", "centralized")
PER_RUN: Final = 400  # distinct configurations kept from one run (the rest of a long run is cut)
DRAWN_OBSERVERS: Final = 2  # observers drawn per configuration besides the movers
SPEED_SIZES: Final = (16, 64, 256)
DIGEST_CHUNK: Final = 200  # configurations per task of the digest pool


@dataclass(frozen=True, slots=True)
class Run:
    """One lock-step run of the collection: where its start comes from, and how it is run."""

    source: str  # "random", "adversarial", "degenerate"
    family: str
    n: int
    a: float
    seed: int
    scheduler: str
    non_rigid: float | None = None  # the adversary's delta: moves stopped part way
    stride: int = 1  # keep every stride-th new configuration (async runs make thousands)
    max_rounds: int | None = None  # None: the engine's default cap

    @property
    def name(self) -> str:
        cut = "" if self.non_rigid is None else f"/d{self.non_rigid:g}"
        return (
            f"{self.source}:{self.family}:n{self.n}:a{self.a:g}:s{self.seed}:{self.scheduler}{cut}"
        )

    def start(self) -> Points:
        if self.source == "random":
            return random_start(self.n, self.seed, self.family, self.a)
        if self.source == "adversarial":
            return build_adversarial(self.family, self.n, self.seed).positions
        return np.asarray(degenerate_starts()[self.family][0], dtype=np.float64)


def _random_runs(quick: bool) -> list[Run]:
    """Random starts of every kind: many small sizes, a few large, the speed bench's own views."""
    sizes = (2, 3, 5, 8, 13, 24, 64) if quick else (*range(2, 41), 48, 64, 96, 128)
    seeds = 1 if quick else 3
    sides = (4.0, 3.2, 6.0)
    runs: list[Run] = []
    index = 0
    for _ in range(seeds):
        for kind in KINDS:
            for n in sizes:
                a = sides[index % len(sides)]
                runs.extend(Run("random", kind, n, a, 7000 + index, s) for s in SCHEDULERS)
                index += 1
    # bench_core's speed views come from this start (centralized, which at large n spends its
    # time on rounds that plan nothing new: fsync reaches the same configurations).
    big = (16, 64) if quick else (16, 64, 256)
    runs.extend(Run("random", "clustered", n, 4.0, 1, "fsync") for n in big)
    runs.extend(Run("random", "clustered", n, 4.0, 1, "centralized", max_rounds=300) for n in big)
    if not quick:
        for kind in KINDS:
            runs.append(Run("random", kind, 260, 4.0, 9100 + KINDS.index(kind), "fsync"))
            runs.append(Run("random", kind, 200, 3.2, 9200 + KINDS.index(kind), "ssync"))
    return runs


def _cut_runs(quick: bool) -> list[Run]:
    """Asynchronous and non-rigid runs: robots Look while others are part way along a path."""
    sizes = (3, 6, 12) if quick else (3, 4, 6, 9, 12, 16, 20, 24, 32, 40)
    runs: list[Run] = []
    for index, n in enumerate(sizes):
        for j, kind in enumerate(KINDS[: 2 if quick else 5]):
            seed = 8000 + 10 * index + j
            a = (4.0, 3.2, 6.0)[(index + j) % 3]
            stride = max(1, n // 6)
            runs.append(Run("random", kind, n, a, seed, "async", stride=stride))
            runs.append(Run("random", kind, n, a, seed, "async-slowest", stride=stride))
            runs.append(Run("random", kind, n, a, seed, "ssync", non_rigid=0.5))
            runs.append(Run("random", kind, n, a, seed, "fsync", non_rigid=1.5))
    return runs


def _adversarial_runs(quick: bool) -> list[Run]:
    """The default families (as the hunts draw them), the row families, and large sizes."""
    runs: list[Run] = []
    count = 40 if quick else 600
    for case in adversarial_cases(count, 20, n_max=16 if quick else 48):
        runs.extend(
            Run("adversarial", case.family, case.n, case.a, case.seed, s) for s in SCHEDULERS
        )
    extra_sizes = (4, 9) if quick else (3, 6, 10, 17, 30, 64, 128, 256)
    for family in FAMILIES:
        lo, hi = family_range(family)
        for j, n in enumerate(s for s in extra_sizes if lo <= s <= hi):
            a = 4.0 if family == "formed" else SIDES[j % len(SIDES)]
            seed = 500 + 31 * j + FAMILIES.index(family)
            scheds = SCHEDULERS if n <= 64 else ("fsync", "ssync")
            runs.extend(Run("adversarial", family, n, a, seed, s) for s in scheds)
    return runs


def _degenerate_runs(quick: bool) -> list[Run]:
    runs: list[Run] = []
    for name, (pts, a) in degenerate_starts().items():
        for seed in range(1 if quick else 3):
            runs.extend(Run("degenerate", name, len(pts), a, seed, s) for s in SCHEDULERS)
    return runs


def all_runs(quick: bool) -> list[Run]:
    """The runs of the collection, in a fixed order."""
    return [
        *_random_runs(quick),
        *_adversarial_runs(quick),
        *_degenerate_runs(quick),
        *_cut_runs(quick),
    ]


def collect_run(run: Run) -> tuple[str, list[np.ndarray], str]:
    """The distinct canonical configurations the run plans on, in order, and how it ended ("cut"
    once a plan is asked on a new one after PER_RUN were kept). The run is advanced a step at a
    time and left there, so no plan is made to fail to stop it (where a robot's own compute
    calls it, the engine would count and log that as the algorithm's failure)."""
    seen: set[bytes] = set()
    found: list[np.ndarray] = []
    enough = False
    original = algorithm.plan

    def recording(points: Points, params: Params) -> algorithm.Plan:
        nonlocal enough
        key = points.tobytes()
        if key not in seen:
            if len(found) >= PER_RUN:
                enough = True
            else:
                if len(seen) % run.stride == 0:
                    found.append(np.array(points, dtype=np.float64))
                seen.add(key)
        return original(points, params)

    algorithm.plan = recording
    try:
        lockstep = start_lockstep(
            run.start(),
            Params(run.n, run.a),
            make_scheduler(run.scheduler, run.n, run.seed),
            seed=run.seed,
            non_rigid=run.non_rigid,
            max_rounds=run.max_rounds,
        )
        while not enough and lockstep.advance():
            pass
        status = "cut" if enough else str(lockstep.finish().status)
    except Exception as exc:  # a failing run still gave its configurations
        status = f"error {type(exc).__name__}"
    finally:
        algorithm.plan = original
    return run.name, found, status


# --- digests ---------------------------------------------------------------------------------


def path_text(path: Path) -> str:
    """Every float of the path, exactly."""
    parts: list[str] = []
    for seg in path.segments:
        if isinstance(seg, Line):
            parts.append(f"L{float(seg.end[0]).hex()},{float(seg.end[1]).hex()}")
        else:
            c = seg.center
            parts.append(f"A{float(c[0]).hex()},{float(c[1]).hex()},{float(seg.sweep).hex()}")
    return ";".join(parts)


def plan_text(made: algorithm.Plan) -> str:
    moves = " ".join(f"{i}={path_text(p)}" for i, p in made.moves.items())
    return f"{made.phase} {made.kind} {moves}"


def _h(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def compute_texts(points: Points, a: float, made: algorithm.Plan, index: int) -> list[str]:
    """compute() of the movers and DRAWN_OBSERVERS drawn robots, each in a random frame."""
    n = len(points)
    params = Params(n, a)
    rng = np.random.default_rng([2024, index])
    drawn = rng.integers(0, n, size=DRAWN_OBSERVERS)
    observers = sorted({*made.moves, *(int(i) for i in drawn)})
    out: list[str] = []
    for obs in observers:
        flip = bool(rng.integers(2))
        order = rng.permutation(n - 1)
        others = np.concatenate((points[:obs], points[obs + 1 :])) - points[obs]
        view = others[order]
        if flip:
            view[:, 0] *= -1.0
        view += 0.0
        out.append(f"{obs}{'f' if flip else ''}:{path_text(algorithm.compute(view, params))}")
    return out


def digest_one(points: Points, a: float, index: int) -> dict[str, str]:
    """The plan's and the computes' digests of one configuration."""
    made = algorithm.plan(points, Params(len(points), a))
    computes = compute_texts(points, a, made, index)
    return {"plan": _h(plan_text(made)), "compute": _h("|".join(computes))}


def _digest_chunk(args: tuple[int, list[np.ndarray], list[float]]) -> list[dict[str, str]]:
    start, configs, sides = args
    return [
        digest_one(p, a, start + k) for k, (p, a) in enumerate(zip(configs, sides, strict=True))
    ]


# --- collection, save, compare ---------------------------------------------------------------


@dataclass
class Configs:
    """The configurations: ids, canonical points and sides, in collection order."""

    ids: list[str]
    points: list[np.ndarray]
    sides: list[float]

    def save(self, file: FsPath) -> None:
        flat = np.concatenate(self.points) if self.points else np.zeros((0, 2))
        sizes = np.array([len(p) for p in self.points], dtype=np.int64)
        np.savez_compressed(
            file, ids=np.array(self.ids), flat=flat, sizes=sizes, sides=np.array(self.sides)
        )

    @classmethod
    def load(cls, file: FsPath) -> Configs:
        data = np.load(file)
        bounds = np.concatenate(([0], np.cumsum(data["sizes"])))
        flat = data["flat"]
        points = [flat[bounds[k] : bounds[k + 1]].copy() for k in range(len(data["sizes"]))]
        return cls([str(s) for s in data["ids"]], points, [float(a) for a in data["sides"]])


def _pool_map(
    fn: Callable[[Any], Any], tasks: Sequence[Any], jobs: int, what: str
) -> Iterator[Any]:
    """fn over tasks, in order, over `jobs` spawned processes, with progress on stderr."""
    started = last = time.monotonic()

    def note(done: int) -> None:
        nonlocal last
        now = time.monotonic()
        if now - last >= 5.0 or done == len(tasks):
            last = now
            print(f"  {what} {done}/{len(tasks)}  {now - started:.0f}s", file=sys.stderr)

    if jobs <= 1:
        for k, task in enumerate(tasks):
            yield fn(task)
            note(k + 1)
        return
    with mp.get_context("spawn").Pool(jobs) as pool:
        for k, out in enumerate(pool.imap(fn, tasks, chunksize=1)):
            yield out
            note(k + 1)


def collect(quick: bool, jobs: int) -> Configs:
    """Every distinct (canonical points, a) the runs plan on, first occurrence first."""
    runs = all_runs(quick)
    # Longest runs first would balance the pool better, but then the order would depend on it.
    configs = Configs([], [], [])
    seen: set[bytes] = set()
    statuses: Counter[str] = Counter()
    for (name, found, status), run in zip(
        _pool_map(collect_run, runs, jobs, "runs"), runs, strict=True
    ):
        statuses[status.split()[0]] += 1
        for k, pts in enumerate(found):
            key = pts.tobytes() + np.float64(run.a).tobytes()
            if key in seen:
                continue
            seen.add(key)
            configs.ids.append(f"{name}#{k}")
            configs.points.append(pts)
            configs.sides.append(run.a)
    print(f"{len(runs)} runs: " + ", ".join(f"{k} {v}" for k, v in sorted(statuses.items())))
    return configs


def digests(configs: Configs, jobs: int) -> list[dict[str, str]]:
    tasks = [
        (s, configs.points[s : s + DIGEST_CHUNK], configs.sides[s : s + DIGEST_CHUNK])
        for s in range(0, len(configs.ids), DIGEST_CHUNK)
    ]
    out: list[dict[str, str]] = []
    for chunk in _pool_map(_digest_chunk, tasks, jobs, "digest chunks"):
        out.extend(chunk)
    return out


def summary(configs: Configs) -> str:
    sizes = [len(p) for p in configs.points]
    by_source = Counter(i.split(":")[0] for i in configs.ids)
    by_sched = Counter(i.split("#")[0].rsplit(":", 1)[1] for i in configs.ids)
    bands = Counter(
        "2-16" if s <= 16 else "17-63" if s < 64 else "64-127" if s < 128 else "128+" for s in sizes
    )
    return (
        f"{len(configs.ids)} configurations, n {min(sizes)}..{max(sizes)}; "
        f"sources {dict(by_source)}; schedulers {dict(by_sched)}; sizes {dict(bands)}"
    )


def save(file: FsPath, configs: Configs, digs: list[dict[str, str]]) -> None:
    rows = [
        {"id": i, "n": len(p), "a": a.hex(), **d}
        for i, p, a, d in zip(configs.ids, configs.points, configs.sides, digs, strict=True)
    ]
    whole = _h("".join(d["plan"] + d["compute"] for d in digs))
    file.write_text(json.dumps({"digest": whole, "configurations": rows}, indent=0) + "\n")
    configs.save(file.with_suffix(".npz"))
    print(f"saved {file} and {file.with_suffix('.npz')}; overall digest {whole}")


def compare(file: FsPath, jobs: int, shown: int = 12) -> int:
    base = json.loads(file.read_text())["configurations"]
    configs = Configs.load(file.with_suffix(".npz"))
    print(summary(configs))
    digs = digests(configs, jobs)
    bad = [
        (row["id"], [k for k in ("plan", "compute") if row[k] != d[k]])
        for row, d in zip(base, digs, strict=True)
        if row["plan"] != d["plan"] or row["compute"] != d["compute"]
    ]
    for name, what in bad[:shown]:
        print(f"DIFFERENT {' and '.join(what)}: {name}")
    print(f"{len(bad)} of {len(base)} configurations differ")
    return 1 if bad else 0


def show(file: FsPath, name: str) -> None:
    """The configuration `name` of a saved collection and its plan in this checkout."""
    configs = Configs.load(file.with_suffix(".npz"))
    if name not in configs.ids:
        raise SystemExit(f"{file.with_suffix('.npz')} holds no configuration {name!r}")
    k = configs.ids.index(name)
    pts, a = configs.points[k], configs.sides[k]
    np.set_printoptions(precision=17, threshold=sys.maxsize)
    print(f"{name}: n={len(pts)} a={a!r}\n{pts!r}")
    made = algorithm.plan(pts, Params(len(pts), a))
    print(plan_text(made))
    print("\n".join(compute_texts(pts, a, made, k)))


def speed_figures(repeats: int = 7) -> dict[int, tuple[float, float, int]]:
    """Mean us per compute call at n = 16, 64, 256 on bench_core's views: the best of `repeats`
    passes, in CPU time (steadier on a shared machine) and in wall time, and the views' count."""
    sys.path.insert(0, str(FsPath(__file__).resolve().parent))
    from bench_core import _sample_views

    out: dict[int, tuple[float, float, int]] = {}
    for n in SPEED_SIZES:
        views = _sample_views(n, 300)
        params = Params(n)
        cpu = wall = float("inf")
        for _ in range(repeats + 1):
            t0, c0 = time.perf_counter(), time.process_time()
            for view in views:
                algorithm.compute(view, params)
            cpu = min(cpu, time.process_time() - c0)
            wall = min(wall, time.perf_counter() - t0)
        per = 1e6 / len(views)
        out[n] = (per * cpu, per * wall, len(views))
    return out


def speed() -> None:
    for n, (cpu, wall, count) in speed_figures().items():
        print(f"n={n:<4} {cpu:7.1f} us CPU  {wall:7.1f} us wall  ({count} views)")


def _speed_of(tree: FsPath) -> dict[int, tuple[float, float, int]]:
    """`speed_figures` of the checkout `tree`, in a fresh process with it first on the path."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    done = subprocess.run(
        [sys.executable, str(FsPath(__file__).resolve()), "--speed-json"],
        env=env,
        cwd=tree,
        capture_output=True,
        text=True,
        check=True,
    )
    return {int(n): (c, w, k) for n, (c, w, k) in json.loads(done.stdout).items()}


def speed_against(other: FsPath, rounds: int) -> None:
    """us per compute call here and in checkout `other`, measured alternately `rounds` times in
    fresh processes (pairs on a loaded machine): the best of each, and the ratio here / there."""
    here = FsPath(__file__).resolve().parent.parent
    best: dict[str, dict[int, float]] = {"there": {}, "here": {}}
    for k in range(rounds):
        for side, tree in (("there", other), ("here", here)):
            figures = _speed_of(tree)
            row = "  ".join(f"n={n} {c:6.1f}" for n, (c, _, _) in figures.items())
            print(f"round {k + 1} {side:5} us CPU a call: {row}", file=sys.stderr)
            for n, (c, _, _) in figures.items():
                best[side][n] = min(best[side].get(n, float("inf")), c)
    print(f"us CPU per compute call, best of {rounds} alternated runs each")
    print(f"{'n':>5} {str(other)[-28:]:>28} {'this checkout':>14} {'ratio':>6}")
    for n in SPEED_SIZES:
        there, now = best["there"][n], best["here"][n]
        print(f"{n:>5} {there:>28.1f} {now:>14.1f} {now / there:>6.2f}")


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--save", type=FsPath, help="collect, digest and write FILE and FILE.npz")
    p.add_argument(
        "--compare", type=FsPath, help="digest FILE's configurations here; exit 1 on a difference"
    )
    p.add_argument("--show", metavar="ID", help="print one configuration of --compare FILE")
    p.add_argument("--quick", action="store_true", help="about 2,000 configurations")
    p.add_argument("--speed", action="store_true", help="us per compute call at n = 16, 64, 256")
    p.add_argument(
        "--against",
        type=FsPath,
        metavar="TREE",
        help="with --speed: the same here and in checkout TREE, alternately, with the ratio",
    )
    p.add_argument("--rounds", type=int, default=3, help="alternations of --against (default 3)")
    p.add_argument("--speed-json", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--jobs", type=int, default=2, help="worker processes (spawn; default 2)")
    args = p.parse_args(argv)
    if args.speed_json:  # --against's child: the figures of the checkout on the path
        print(json.dumps(speed_figures()))
        return 0
    if args.speed and args.against is not None:
        speed_against(args.against.resolve(), args.rounds)
        return 0
    if args.speed:
        speed()
        return 0
    if args.show:
        if args.compare is None:
            p.error("--show needs --compare FILE")
        show(args.compare, args.show)
        return 0
    if args.compare is not None:
        return compare(args.compare, args.jobs)
    if args.save is None:
        p.error("give --save FILE, --compare FILE or --speed")
    t0 = time.perf_counter()
    configs = collect(args.quick, args.jobs)
    print(summary(configs))
    save(args.save, configs, digests(configs, args.jobs))
    print(f"{time.perf_counter() - t0:.0f}s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
