"""Bit-for-bit referee of one round of physics (`world.physics.apply_round`): digests of its every
output over a fixed, seeded collection of rounds, to compare one checkout with another (issue 30).

    python bench/physics_digest.py --save /tmp/phys.json      # collect, digest, save
    python bench/physics_digest.py --compare /tmp/phys.json   # 0 differences or exit 1
    python bench/physics_digest.py --speed                    # us CPU per apply_round call
    python bench/physics_digest.py --speed --against /work/base2   # the same, paired

Against another checkout, run the script by absolute path from that checkout with it on the path:
`cd /work/base2 && PYTHONPATH=/work/base2 python /work/wt/physics/bench/physics_digest.py --save F`.

The collection: rounds where every path is a single Line (spread starts where no pair can meet,
every robot stepping 1e-4; clustered, dense and clumped starts with moves of every length, toward
their centre, head-on and chasing pairs, chains of touching discs that stop one another, pairs
within 1e-9 of contact, tied distances of symmetric rings, offsets near 3e5, point robots), rounds
with arcs and several segments, rounds that must raise, and the rounds real runs make: every
apply_round call of lock-step runs of `gathering` and `oblot-go-to-cog` (fsync and ssync), n from 2
to 256. `--save FILE` writes FILE (JSON: one digest per round) and FILE with suffix .pkl (the
rounds themselves); `--compare FILE` digests exactly the saved rounds in this checkout and names
the first differences. A round's digest covers the positions (dtype, shape, every bit), traveled,
lengths (keys in order, types, float.hex), the collisions in order, and any exception's type and
text; and that the positions given were left as they were.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import pickle
import subprocess
import sys
import time
import zlib
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path as FsPath
from typing import Any, Final

import numpy as np

from fatswarm.domain.path import Arc, Line, Path, Points, transform
from fatswarm.domain.tolerance import GRID, snap

SPEED_SIZES: Final = (16, 64, 256)
Round = tuple[str, Points, Mapping[Any, Any], bool]  # name, positions, paths (world), points


# --------------------------------------------------------------------------------------------------
# The collection


def _start(n: int, seed: int, kind: str) -> Points:
    from fatswarm.deploy.scenarios.starts import random_start  # only where starts are drawn

    return random_start(n, seed, kind)


def _seed(text: str) -> int:
    """A seed from a name, the same in every process (str hashes are salted)."""
    return zlib.crc32(text.encode())


def _lines(start: Points, movers: Sequence[int], steps: Any) -> dict[Any, Path]:
    """Each mover a Line by `steps[k]` from where it is, as rounds.py makes world paths."""
    at = start.tolist()
    return {
        int(r): transform(Path((Line((float(s[0]), float(s[1]))),)), (at[r][0], at[r][1]), False)
        for r, s in zip(movers, steps, strict=True)
    }


def _directions(rng: np.random.Generator, m: int, lengths: np.ndarray) -> Points:
    ang = rng.uniform(0.0, 2.0 * math.pi, m)
    return np.column_stack([np.cos(ang) * lengths, np.sin(ang) * lengths])


def spread_rounds() -> list[Round]:
    """The bench's rounds: spread starts, every robot steps 1e-4 (no pair can meet)."""
    out: list[Round] = []
    for n in (2, 3, 16, 31, 64, 100, 256):
        for seed in range(3):
            start = _start(n, seed, "spread")
            rng = np.random.default_rng(1000 + n * 10 + seed)
            steps = _directions(rng, n, np.full(n, 1e-4))
            out.append((f"spread-n{n}-s{seed}", start, _lines(start, range(n), steps), False))
            right = np.tile([1e-4, 0.0], (n, 1))
            out.append((f"spread-right-n{n}-s{seed}", start, _lines(start, range(n), right), False))
            out.append((f"spread-pts-n{n}-s{seed}", start, _lines(start, range(n), steps), True))
            some = sorted(rng.choice(n, size=max(1, n // 3), replace=False).tolist())
            out.append(
                (f"spread-some-n{n}-s{seed}", start, _lines(start, some, steps[: len(some)]), False)
            )
    return out


def order_rounds() -> list[Round]:
    """Rounds whose paths come in another order than the robots' (the order of the movers decides
    the frame, ties and the snap's order), and ends on half-grid points (ties of the snap)."""
    out: list[Round] = []
    for n in (3, 16, 64, 100):
        for kind in ("spread", "clustered"):
            start = _start(n, 11, kind)
            rng = np.random.default_rng(_seed(f"order-{kind}-{n}"))
            steps = _directions(rng, n, rng.choice((1e-4, 0.5, 3.0), size=n))
            paths = _lines(start, range(n), steps)
            backwards = dict(reversed(paths.items()))
            shuffled = {r: paths[r] for r in rng.permutation(n).tolist()}
            out.append((f"order-back-{kind}-n{n}", start, backwards, False))
            out.append((f"order-shuffled-{kind}-n{n}", start, shuffled, False))
            out.append((f"order-shuffled-{kind}-n{n}-pts", start, shuffled, True))
            half = snap(start + steps) + GRID / 2.0 * rng.integers(0, 2, size=(n, 2))
            ties = {
                r: Path((Line((float(x), float(y))),)) for r, (x, y) in enumerate(half.tolist())
            }
            out.append((f"half-grid-{kind}-n{n}", start, ties, False))
            out.append((f"half-grid-{kind}-n{n}-pts", start, ties, True))
    return out


def random_rounds() -> list[Round]:
    """Random starts of every kind, random movers with moves of every length and direction, and
    moves toward the centre (where pairs meet and stop one another); fat and point robots."""
    out: list[Round] = []
    scales = (1e-9, 1e-4, 0.01, 0.3, 1.0, 2.5, 8.0)
    for kind in ("clustered", "dense", "clumped", "loose", "spread"):
        for n in (2, 3, 5, 8, 16, 33, 64, 128, 256):
            for seed in range(2 if n > 64 else 3):
                start = _start(n, 7 + seed, kind)
                rng = np.random.default_rng(_seed(f"{kind}-{n}-{seed}"))
                m = int(rng.integers(1, n + 1))
                movers = sorted(rng.choice(n, size=m, replace=False).tolist())
                lengths = rng.choice(scales, size=m) * rng.uniform(0.5, 1.5, m)
                steps = _directions(rng, m, lengths)
                name = f"random-{kind}-n{n}-s{seed}"
                paths = _lines(start, movers, steps)
                out.append((name, start, paths, False))
                out.append((name + "-pts", start, paths, True))
                centre = start.mean(axis=0)
                to_centre = (centre - start) * rng.uniform(0.2, 1.2)
                every = list(range(n))
                out.append((name + "-centre", start, _lines(start, every, to_centre), False))
                out.append((name + "-centre-pts", start, _lines(start, every, to_centre), True))
    return out


def _grid(points: Any) -> Points:
    return snap(np.array(points, dtype=np.float64))


def contact_rounds() -> list[Round]:
    """Head-on and chasing pairs, chains of touching discs, near contact, ties, far offsets."""
    out: list[Round] = []
    g = GRID
    for gap in (0.0, g, 2 * g, 3 * g, 1e-9, 1e-6, 0.5):
        d = 2.0 + gap
        pair = _grid([[0.0, 0.0], [d, 0.0]])
        out.append((f"headon-{gap!r}", pair, _lines(pair, [0, 1], [[1.0, 0], [-1.0, 0]]), False))
        out.append((f"chase-{gap!r}", pair, _lines(pair, [0, 1], [[1.5, 0], [0.5, 0]]), False))
        out.append((f"pushstill-{gap!r}", pair, _lines(pair, [0], [[0.7, 0.0]]), False))
        out.append((f"slide-{gap!r}", pair, _lines(pair, [0, 1], [[0, 3.0], [0, 3.0]]), False))
        out.append((f"tangent-{gap!r}", pair, _lines(pair, [0], [[0.0, 1.0]]), False))
        out.append((f"away-{gap!r}", pair, _lines(pair, [0, 1], [[-1.0, 0], [1.0, 0]]), False))
        out.append((f"headon-pts-{gap!r}", pair, _lines(pair, [0, 1], [[3, 0], [-3, 0]]), True))
        for k in (3, 6, 12):
            chain = _grid([[i * d, 0.0] for i in range(k)])
            pushes = np.array([[1.0 - 0.05 * i, 0.01 * i] for i in range(k)])
            out.append((f"chain{k}-{gap!r}", chain, _lines(chain, range(k), pushes), False))
            back = -pushes[::-1]
            out.append((f"chainback{k}-{gap!r}", chain, _lines(chain, range(k), back), False))
    for n in (4, 5, 8, 16, 64):  # rings toward their centre: equal distances, tied contacts
        ang = 2.0 * math.pi * np.arange(n) / n
        radius = 2.0 / (2.0 * math.sin(math.pi / n)) + 3.0
        ring = _grid(np.column_stack([radius * np.cos(ang), radius * np.sin(ang)]))
        steps = -ring * 0.9
        out.append((f"ring{n}", ring, _lines(ring, range(n), steps), False))
        out.append((f"ring{n}-pts", ring, _lines(ring, range(n), steps), True))
        square = _grid([[x, y] for x in range(int(math.sqrt(n)) + 1) for y in range(2)]) * 2.0
        sq = _grid(square * 1.0)
        out.append((f"lattice{n}", sq, _lines(sq, range(len(sq)), -sq * 0.5 + 0.3), False))
    far: list[Round] = []
    for name, start, paths, points in out + random_rounds()[::7]:
        off = np.array([3e5 - 17.25, -3e5 + 3.5])
        moved = start + off
        far_paths = {r: transform(p, (off[0], off[1]), False) for r, p in paths.items()}
        far.append((f"far-{name}", moved, far_paths, points))
    return out + far


def _arc_path(rng: np.random.Generator, x: float, y: float, k: int) -> Path:
    """A path of k segments from (x, y): lines and arcs of random sizes (world frame)."""
    segs: list[Line | Arc] = []
    here = (x, y)
    for _ in range(k):
        if rng.random() < 0.5:
            end = (here[0] + float(rng.normal(0.0, 1.0)), here[1] + float(rng.normal(0.0, 1.0)))
            segs.append(Line(end))
            here = end
        else:
            c = (here[0] + float(rng.normal(0.0, 1.5)), here[1] + float(rng.normal(0.0, 1.5)))
            sweep = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.01, 2.5 * math.pi))
            segs.append(Arc(c, sweep))
            r = math.hypot(here[0] - c[0], here[1] - c[1])
            a0 = math.atan2(here[1] - c[1], here[0] - c[0]) + sweep
            here = (c[0] + r * math.cos(a0), c[1] + r * math.sin(a0))
    return Path(tuple(segs))


def arc_rounds() -> list[Round]:
    """Arcs and several segments, empty paths and zero-length lines mixed with single lines."""
    out: list[Round] = []
    for kind in ("clustered", "dense", "loose"):
        for n in (2, 4, 9, 24, 64):
            for seed in range(3):
                start = _start(n, 50 + seed, kind)
                rng = np.random.default_rng(_seed(f"arc-{kind}-{n}-{seed}"))
                at = start.tolist()
                paths: dict[int, Path] = {}
                for r in range(n):
                    u = rng.random()
                    x, y = at[r]
                    if u < 0.1:
                        paths[r] = Path()
                    elif u < 0.2:
                        paths[r] = Path((Line((x, y)),))
                    elif u < 0.5:
                        paths[r] = transform(Path((Line((0.3, -0.2)),)), (x, y), False)
                    else:
                        paths[r] = _arc_path(rng, x, y, int(rng.integers(1, 5)))
                name = f"arcs-{kind}-n{n}-s{seed}"
                out.append((name, start, paths, False))
                out.append((name + "-pts", start, paths, True))
    two = _grid([[0.0, 0.0], [4.0, 0.0]])
    orbit = {0: Path((Arc((2.0, 0.0), 2 * math.pi),)), 1: Path((Arc((2.0, 0.0), 2 * math.pi),))}
    out.append(("orbit-same-circle", two, orbit, False))
    still = {0: Path((Arc((2.0, 0.0), math.pi),))}
    out.append(("arc-into-still", two, still, False))
    return out


def error_rounds() -> list[Round]:
    """Rounds apply_round must refuse, and odd but valid inputs (numpy keys, int coordinates)."""
    start = _grid([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    step = Path((Line((0.5, 0.5)),))
    nan, inf = float("nan"), float("inf")
    cases: list[tuple[str, Any, Mapping[Any, Any]]] = [
        ("unknown-robot", start, {3: step}),
        ("negative-robot", start, {-1: step}),
        ("str-robot", start, {"a": step}),
        ("bool-robot", start, {True: step}),
        ("float-robot", start, {1.0: step}),
        ("np-int-robot", start, {np.int64(1): step}),
        ("not-a-path", start, {0: [(1.0, 1.0)]}),
        ("nan-end", start, {0: Path((Line((nan, 0.0)),))}),
        ("inf-end", start, {1: step, 0: Path((Line((inf, 0.0)),))}),
        ("int-end", start, {0: Path((Line((1, 0)),))}),
        ("np-float-end", start, {0: Path((Line((np.float64(0.5), np.float64(0.25))),))}),
        ("list-end", start, {0: Path((Line([0.5, 0.25]),))}),  # type: ignore[arg-type]
        ("three-end", start, {0: Path((Line((0.5, 0.25, 1.0)),))}),  # type: ignore[arg-type]
        ("bool-end", start, {0: Path((Line((True, 0.25)),))}),
        ("nan-arc", start, {0: Path((Arc((1.0, 0.0), nan),))}),
        ("not-a-segment", start, {0: Path(((1.0, 2.0),))}),  # type: ignore[arg-type]
        ("too-many", start, {0: Path(tuple(Line((0.01 * k, 0.0)) for k in range(65)))}),
        ("too-long", start, {0: Path((Line((1e308, 0.0)), Line((-1e308, 0.0))))}),
        ("too-long-line", start, {0: Path((Line((1.7e308, 1.7e308)),))}),
        ("too-long-mixed", start, {0: Path((Line((1.7e308, 1.7e308)),)), 1: step}),
        ("overlap-start", _grid([[0.0, 0.0], [1.0, 0.0]]), {0: step}),
        ("overlap-still", _grid([[0.0, 0.0], [1.0, 0.0], [5.0, 5.0]]), {2: step}),
        ("overlap-pts", _grid([[0.0, 0.0], [0.0, 0.0]]), {0: step}),
        ("empty-positions", np.zeros((0, 2)), {}),
        ("bad-shape", np.zeros((3, 3)), {0: step}),
        ("nan-position", np.array([[0.0, nan], [4.0, 0.0]]), {1: step}),
        ("list-positions", [[0.0, 0.0], [4.0, 0.0]], {0: step}),
        ("no-moves", start, {}),
        ("all-empty", start, {0: Path(), 2: Path()}),
        ("zero-length", start, {0: Path((Line((0.0, 0.0)),))}),
        ("unsorted-keys", start, {2: step, 0: Path((Line((0.5, 0.0)),)), 1: step}),
        ("off-grid", np.array([[0.1, 0.2], [3.3, 0.7]]), {0: Path((Line((0.7, 0.8)),))}),
    ]
    out: list[Round] = []
    for name, pos, paths in cases:
        out.append((f"err-{name}", pos, paths, False))
        out.append((f"err-{name}-pts", pos, paths, True))
    return out


@contextmanager
def _recording(out: list[Round], label: list[str]) -> Iterator[None]:
    """Every apply_round call of the lock step (rounds and asynchronous windows) joins `out`,
    named `label[0]` and its index, while the block runs."""
    from fatswarm.world import asynchrony, physics, rounds  # only where runs are recorded

    def recording(positions: Points, paths: Mapping[int, Path], *, points: bool = False) -> Any:
        out.append((f"{label[0]}-{len(out)}", np.array(positions), dict(paths), points))
        return physics.apply_round(positions, paths, points=points)

    for module in (rounds, asynchrony):
        setattr(module, "apply_round", recording)  # noqa: B010 - mypy: not an exported name
    try:
        yield
    finally:
        for module in (rounds, asynchrony):
            setattr(module, "apply_round", physics.apply_round)  # noqa: B010


def recorded_rounds(quick: bool = False) -> list[Round]:
    """Every apply_round call of a few lock-step runs of gathering and oblot-go-to-cog."""
    import fatswarm  # only where runs are recorded

    out: list[Round] = []
    label = [""]
    runs: list[tuple[str, int, str, str, int, dict[str, Any]]] = [
        ("gathering", 16, "clustered", "fsync", 120, {}),
        ("gathering", 64, "clustered", "fsync", 80, {}),
        ("gathering", 256, "clustered", "fsync", 12, {}),
        ("gathering", 64, "spread", "fsync", 20, {}),
        ("gathering", 16, "spread", "ssync", 60, {}),
        ("gathering", 64, "loose", "centralized", 40, {}),
        ("oblot-go-to-cog", 16, "spread", "fsync", 60, {"bodies": "points"}),
        ("oblot-go-to-cog", 16, "spread", "ssync", 60, {"bodies": "points"}),
        ("oblot-go-to-cog", 64, "clustered", "ssync", 40, {"bodies": "points"}),
        ("oblot-go-to-cog", 256, "spread", "ssync", 10, {"bodies": "points"}),
        ("oblot-go-to-cog", 64, "clustered", "ssync", 40, {}),
        ("gathering", 16, "clustered", "async", 40, {}),
    ]
    with _recording(out, label):
        for alg, n, kind, sched, max_rounds, model in runs[:2] if quick else runs:
            label[0] = f"run-{alg}-n{n}-{kind}-{sched}"
            fatswarm.run(
                n,
                algorithm=alg,
                seed=3,
                start=kind,
                scheduler=sched,
                max_rounds=max_rounds,
                **model,
            )
    return out


def collect(quick: bool = False) -> list[Round]:
    if quick:
        return spread_rounds()[::5] + contact_rounds()[::9] + error_rounds()
    return (
        spread_rounds()
        + order_rounds()
        + random_rounds()
        + contact_rounds()
        + arc_rounds()
        + error_rounds()
        + recorded_rounds()
    )


# --------------------------------------------------------------------------------------------------
# Digests


def _num(v: Any) -> str:
    return f"{type(v).__name__}:{float(v).hex()}"


def outcome_text(positions: Any, paths: Mapping[Any, Any], points: bool) -> str:
    """Every bit apply_round gives for this round (or the error it raises), as text."""
    from fatswarm.world.physics import apply_round  # the checkout on the path

    given = np.array(positions, dtype=np.float64) if isinstance(positions, np.ndarray) else None
    try:
        out = apply_round(positions, paths, points=points)
    except Exception as exc:  # the referee records any error, by type and text
        return f"raise {type(exc).__name__}: {exc}"
    lines = []
    pos = out.positions
    lines.append(f"positions {type(pos).__name__} {pos.dtype} {pos.shape} {pos.tobytes().hex()}")
    for name in ("traveled", "lengths"):
        d = getattr(out, name)
        lines.append(
            f"{name} {type(d).__name__} " + " ".join(f"{k}={_num(v)}" for k, v in d.items())
        )
    for c in out.collisions:
        p = c.point
        lines.append(
            f"collision {type(c).__name__} {c.robot!r} {c.other!r} {_num(c.t)} "
            f"{type(p).__name__} {_num(p[0])} {_num(p[1])}"
        )
    if given is not None and not np.array_equal(given, positions, equal_nan=True):
        lines.append("positions given were changed")
    return "\n".join(lines)


def digest(positions: Any, paths: Mapping[Any, Any], points: bool) -> str:
    return hashlib.sha256(outcome_text(positions, paths, points).encode()).hexdigest()[:32]


def save(file: FsPath, rounds: list[Round]) -> None:
    digests = {name: digest(pos, paths, pts) for name, pos, paths, pts in rounds}
    if len(digests) != len(rounds):
        raise SystemExit("round names are not unique")
    file.write_text(json.dumps({"count": len(digests), "digests": digests}, indent=0) + "\n")
    with file.with_suffix(".pkl").open("wb") as f:
        pickle.dump(rounds, f)
    print(f"{len(rounds)} rounds digested, saved to {file} and {file.with_suffix('.pkl')}")


def compare(file: FsPath, shown: int = 12) -> int:
    saved = json.loads(file.read_text())["digests"]
    with file.with_suffix(".pkl").open("rb") as f:
        rounds: list[Round] = pickle.load(f)
    differ = []
    for name, pos, paths, pts in rounds:
        if digest(pos, paths, pts) != saved[name]:
            differ.append(name)
    print(f"{len(rounds)} rounds compared, {len(differ)} differences")
    for name in differ[:shown]:
        print(f"  differs: {name}")
    return 1 if differ else 0


def show(file: FsPath, name: str) -> None:
    with file.with_suffix(".pkl").open("rb") as f:
        rounds: list[Round] = pickle.load(f)
    for n, pos, paths, pts in rounds:
        if n == name:
            print(f"{name}: points={pts}\npositions={pos!r}\npaths={paths!r}")
            print(outcome_text(pos, paths, pts))
            return
    raise SystemExit(f"no round {name!r} in {file.with_suffix('.pkl')}")


# --------------------------------------------------------------------------------------------------
# Speed: us CPU per apply_round call


def speed_rounds() -> dict[str, list[Round]]:
    """(a) the bench's spread rounds (every robot steps 1e-4, in a random direction), (b)
    gathering's rounds from a clustered start, at n = 16, 64, 256."""
    import fatswarm  # only where runs are recorded

    out: dict[str, list[Round]] = {}
    for n in SPEED_SIZES:
        spread: list[Round] = []
        for seed in range(4):
            start = _start(n, seed, "spread")
            rng = np.random.default_rng(seed)
            steps = _directions(rng, n, np.full(n, 1e-4))
            spread.append((f"s{seed}", start, _lines(start, range(n), steps), False))
        out[f"spread n={n}"] = spread
        gathered: list[Round] = []
        with _recording(gathered, ["g"]):
            fatswarm.run(n, algorithm="gathering", seed=1, start="clustered", max_rounds=30)
        out[f"gathering n={n}"] = gathered[:30]
    return out


def _as_lines(batch: list[Round]) -> list[tuple[Points, np.ndarray, np.ndarray, bool]]:
    """The rounds of `batch` as apply_lines' arrays (every path one Line, movers increasing)."""
    out = []
    for _, pos, paths, pts in batch:
        movers = sorted(paths)
        ends = [paths[r].segments[0].end for r in movers]
        out.append((pos, np.array(movers, dtype=np.intp), np.array(ends, dtype=np.float64), pts))
    return out


def speed_figures(rounds: dict[str, list[Round]], repeats: int = 5) -> dict[str, float]:
    """us CPU per apply_round call of each set: the best of `repeats` passes; and per
    apply_lines call on the same rounds as arrays, where the checkout has it."""
    from fatswarm.world import physics

    figures: dict[str, float] = {}
    for label, batch in rounds.items():
        calls = max(1, 2000 // len(batch) // max(1, len(batch[0][2]) // 16))
        best = float("inf")
        for _ in range(repeats + 1):
            c0 = time.process_time()
            for _ in range(calls):
                for _, pos, paths, pts in batch:
                    physics.apply_round(pos, paths, points=pts)
            best = min(best, time.process_time() - c0)
        figures[label] = 1e6 * best / (calls * len(batch))
        apply_lines = getattr(physics, "apply_lines", None)
        if apply_lines is None:
            continue
        lines = _as_lines(batch)
        best = float("inf")
        for _ in range(repeats + 1):
            c0 = time.process_time()
            for _ in range(calls):
                for pos, movers, ends, pts in lines:
                    apply_lines(pos, movers, ends, points=pts)
            best = min(best, time.process_time() - c0)
        figures[f"{label} lines"] = 1e6 * best / (calls * len(batch))
    return figures


def _speed_of(tree: FsPath, rounds_file: FsPath) -> dict[str, float]:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    done = subprocess.run(
        [sys.executable, str(FsPath(__file__).resolve()), "--speed-json", str(rounds_file)],
        env=env,
        cwd=tree,
        capture_output=True,
        text=True,
        check=True,
    )
    figures: dict[str, float] = json.loads(done.stdout)
    return figures


def speed_against(other: FsPath | None, alternations: int) -> None:
    """us CPU per call here (and in checkout `other`, alternately, in fresh processes)."""
    here = FsPath(__file__).resolve().parent.parent
    rounds_file = FsPath(f"/tmp/physics-speed-{os.getpid()}.pkl")
    with rounds_file.open("wb") as f:
        pickle.dump(speed_rounds(), f)
    sides = (("there", other), ("here", here)) if other is not None else (("here", here),)
    best: dict[str, dict[str, float]] = {side: {} for side, _ in sides}
    try:
        for k in range(alternations):
            for side, tree in sides:
                assert tree is not None
                figures = _speed_of(tree, rounds_file)
                row = "  ".join(f"{label} {us:7.1f}" for label, us in figures.items())
                print(f"pass {k + 1} {side:5} {row}", file=sys.stderr)
                for label, us in figures.items():
                    best[side][label] = min(best[side].get(label, float("inf")), us)
    finally:
        rounds_file.unlink()
    print(f"us CPU per apply_round call, best of {alternations} alternated processes each")
    if other is None:
        for label, us in best["here"].items():
            print(f"{label:>16} {us:9.1f}")
        return
    print(f"{'rounds':>16} {str(other)[-20:]:>20} {'this checkout':>14} {'ratio':>6}")
    for label, there in best["there"].items():
        now = best["here"][label]
        print(f"{label:>16} {there:>20.1f} {now:>14.1f} {there / now:>5.2f}x")
        lines = best["here"].get(f"{label} lines")
        if lines is not None:
            print(f"{'(apply_lines)':>16} {'':>20} {lines:>14.1f} {there / lines:>5.2f}x")


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--save", type=FsPath, help="collect, digest and write FILE and FILE.pkl")
    p.add_argument(
        "--compare", type=FsPath, help="digest FILE's rounds here; exit 1 on a difference"
    )
    p.add_argument("--show", metavar="NAME", help="print one round of --compare FILE")
    p.add_argument("--quick", action="store_true", help="a small collection")
    p.add_argument("--speed", action="store_true", help="us CPU per apply_round call")
    p.add_argument("--against", type=FsPath, metavar="TREE", help="with --speed: paired with TREE")
    p.add_argument("--rounds", type=int, default=3, help="alternations of --speed (default 3)")
    p.add_argument("--speed-json", type=FsPath, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.speed_json is not None:  # --speed's child: the figures of the checkout on the path
        with args.speed_json.open("rb") as f:
            print(json.dumps(speed_figures(pickle.load(f))))
        return 0
    if args.speed:
        speed_against(None if args.against is None else args.against.resolve(), args.rounds)
        return 0
    if args.show:
        if args.compare is None:
            p.error("--show needs --compare FILE")
        show(args.compare, args.show)
        return 0
    if args.compare is not None:
        return compare(args.compare)
    if args.save is None:
        p.error("give --save FILE, --compare FILE or --speed")
    t0 = time.perf_counter()
    save(args.save, collect(args.quick))
    print(f"{time.perf_counter() - t0:.0f}s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
