"""Start configurations: seeded random families, named degenerate cases, and `--init` files.

Every start is valid: centres at least 2 apart (discs may touch, never overlap), all finite.
Random kinds (r = `agent.geometry.target_radius`, ComputeRadius with a* = max(a, 4)):

| kind      | density                       | smallest enclosing circle (SEC) |
|-----------|-------------------------------|---------------------------------|
| clustered | random gaps between robots    | < r: expansion needed           |
| dense     | packed, many robots touching  | < r: expansion needed           |
| spread    | random gaps between robots    | >= r: no expansion              |
| loose     | robots at least max(a, 2) apart | >= r, up to 3r                |
| clumped   | a packed clump plus outliers  | >= r: no expansion              |
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import Any, Final

import numpy as np

from fatswarm.agent.geometry import target_radius
from fatswarm.domain.draws import START_STREAM
from fatswarm.domain.path import Points
from fatswarm.domain.tolerance import CONTACT, OVERLAP_DISTANCE, OVERLAP_SHOWN, shown_apart, snap
from fatswarm.world.physics import CONTACT_SLACK

KINDS: Final = ("clustered", "dense", "spread", "loose", "clumped")
MAX_OFFSET: Final = 50.0  # starts are translated by up to this much: nothing may rely on the origin
SEC_MARGIN: Final = 1e-3  # relative margin that keeps "needs expansion" robust to rounding


class InitFileError(ValueError):
    """An `--init` file is missing or not a valid start configuration."""


def overlapping_pair(positions: Points) -> tuple[int, int, float] | None:
    """The first pair (i, j, distance) whose discs overlap (centres < 2 - CONTACT_SLACK apart)."""
    pts = np.asarray(positions, dtype=np.float64)
    if len(pts) < 2:
        return None
    diff = pts[:, None, :] - pts[None, :, :]
    dist = np.hypot(diff[..., 0], diff[..., 1])
    np.fill_diagonal(dist, np.inf)
    i, j = np.unravel_index(int(np.argmin(dist)), dist.shape)
    if dist[i, j] < CONTACT - CONTACT_SLACK:
        lo, hi = sorted((int(i), int(j)))
        return lo, hi, float(dist[i, j])
    return None


def _rng(rng_or_seed: np.random.Generator | int) -> np.random.Generator:
    if isinstance(rng_or_seed, np.random.Generator):
        return rng_or_seed
    return np.random.default_rng([START_STREAM, int(rng_or_seed) & 0xFFFFFFFF])


def _fits(p: np.ndarray, placed: list[np.ndarray], sep: float) -> bool:
    if not placed:
        return True
    arr = np.asarray(placed)
    return bool(np.min(np.hypot(arr[:, 0] - p[0], arr[:, 1] - p[1])) >= sep)


def _in_disc(rng: np.random.Generator, radius: float) -> np.ndarray:
    rho = radius * math.sqrt(rng.random())
    phi = 2.0 * math.pi * rng.random()
    return np.array([rho * math.cos(phi), rho * math.sin(phi)])


def _scatter(
    rng: np.random.Generator, count: int, radius: float, sep: float, placed: list[np.ndarray]
) -> bool:
    """Add `count` centres uniformly in the disc, each >= sep from all others; False on failure."""
    for _ in range(count):
        for _attempt in range(400):
            p = _in_disc(rng, radius)
            if _fits(p, placed, sep):
                placed.append(p)
                break
        else:
            return False
    return True


def _clump(rng: np.random.Generator, count: int) -> list[np.ndarray]:
    """A compact packed clump: each new disc touches an earlier one, nearest the centroid wins."""
    placed = [np.zeros(2)]
    while len(placed) < count:
        arr = np.asarray(placed)
        centroid = arr.mean(axis=0)
        best: np.ndarray | None = None
        for _ in range(24):
            base = arr[int(rng.integers(len(arr)))]
            phi = 2.0 * math.pi * rng.random()
            p = base + CONTACT * np.array([math.cos(phi), math.sin(phi)])
            if _fits(p, placed, CONTACT) and (
                best is None or _length(p - centroid) < _length(best - centroid)
            ):
                best = p
        if best is not None:
            placed.append(best)
    return placed


def _length(v: np.ndarray) -> float:
    """|v| of one 2-vector written out: `np.linalg.norm(v)` is sqrt(v . v) through BLAS, whose
    kernel (fused multiply-add or not) varies by CPU."""
    x, y = float(v[0]), float(v[1])
    return math.sqrt(x * x + y * y)


def _radius_about_centroid(pts: np.ndarray) -> float:
    """An upper bound on the SEC radius (the farthest centre from the centroid)."""
    return float(np.max(np.linalg.norm(pts - pts.mean(axis=0), axis=1)))


def _pinned_circle(rng: np.random.Generator, radius: float) -> list[np.ndarray]:
    """Two antipodal centres on the circle: with all others inside, this circle is the SEC."""
    phi = 2.0 * math.pi * rng.random()
    u = np.array([math.cos(phi), math.sin(phi)])
    return [radius * u, -radius * u]


def _dense(rng: np.random.Generator, n: int, a: float, r: float) -> np.ndarray | None:
    pts = np.asarray(_clump(rng, n))
    return pts if _radius_about_centroid(pts) < r * (1 - SEC_MARGIN) else None


def _clustered(rng: np.random.Generator, n: int, a: float, r: float) -> np.ndarray | None:
    hi = r * (1 - SEC_MARGIN)
    lo = min(hi, max(1.0, 1.1 * math.sqrt(n)))
    radius = lo + (hi - lo) * rng.random()
    placed: list[np.ndarray] = []
    ok = _scatter(rng, n, radius, CONTACT + 0.5 * rng.random(), placed)
    return np.asarray(placed) if ok else None


def _spread(rng: np.random.Generator, n: int, a: float, r: float) -> np.ndarray | None:
    return _spread_or_loose(rng, n, a, r, "spread")


def _loose(rng: np.random.Generator, n: int, a: float, r: float) -> np.ndarray | None:
    return _spread_or_loose(rng, n, a, r, "loose")


def _spread_or_loose(
    rng: np.random.Generator, n: int, a: float, r: float, kind: str
) -> np.ndarray | None:
    sep = CONTACT if kind == "spread" else max(CONTACT, a)
    radius = r * (1 + SEC_MARGIN + (0.5 if kind == "spread" else 2.0) * rng.random())
    radius = max(radius, 0.6 * sep * math.sqrt(n) if kind == "loose" else 0.0)
    placed = _pinned_circle(rng, radius)[: min(n, 2)]
    gap = sep + (0.5 * rng.random() if kind == "spread" else 0.0)
    return np.asarray(placed) if _scatter(rng, n - len(placed), radius, gap, placed) else None


def _clumped(rng: np.random.Generator, n: int, a: float, r: float) -> np.ndarray | None:
    if n <= 2:
        return np.asarray(_pinned_circle(rng, r * (1 + SEC_MARGIN))[:n])
    radius = r * (1 + SEC_MARGIN + 0.5 * rng.random())
    clump = np.asarray(_clump(rng, n - 2))
    shift = _in_disc(rng, max(0.0, radius - _radius_about_centroid(clump) - 2.0))
    clump = clump - clump.mean(axis=0) + shift
    placed = _pinned_circle(rng, radius)
    if not all(_fits(p, placed, CONTACT) for p in clump):
        return None
    if np.max(np.linalg.norm(clump, axis=1)) > radius:
        return None
    return np.vstack([np.asarray(placed), clump])


_Attempt = Callable[[np.random.Generator, int, float, float], np.ndarray | None]
_ATTEMPTS: Final[Mapping[str, _Attempt]] = MappingProxyType(
    {
        "clustered": _clustered,
        "dense": _dense,
        "spread": _spread,
        "loose": _loose,
        "clumped": _clumped,
    }
)


def _attempt(rng: np.random.Generator, n: int, kind: str, a: float, r: float) -> np.ndarray | None:
    """One draw of a start of `kind` (see the module table); None if this draw does not fit."""
    attempt = _ATTEMPTS.get(kind)
    if attempt is None:
        raise ValueError(f"unknown start kind {kind!r}; choose one of {', '.join(KINDS)}")
    return attempt(rng, n, a, r)


def random_start(
    n: int, rng_or_seed: np.random.Generator | int, kind: str = "clustered", a: float = 4.0
) -> Points:
    """A valid (n, 2) start of the given kind (see the module table), seeded and reproducible,
    on the world's grid (fatswarm/domain/tolerance.py)."""
    if kind not in KINDS:
        raise ValueError(f"unknown start kind {kind!r}; choose one of {', '.join(KINDS)}")
    if n < 1:
        raise ValueError(f"a start needs at least one robot, got n={n}")
    rng = _rng(rng_or_seed)
    offset = rng.uniform(-MAX_OFFSET, MAX_OFFSET, size=2)
    if n == 1:
        return snap(offset[None, :].astype(np.float64))
    r = target_radius(n, a)
    for _ in range(200):
        pts = _attempt(rng, n, kind, a, r)
        if pts is not None and overlapping_pair(pts) is None:
            order = rng.permutation(n)  # robot numbers carry no geometric meaning
            return snap(np.ascontiguousarray(pts[order] + offset, dtype=np.float64))
    raise RuntimeError(f"could not draw a {kind} start for n={n}, a={a}")  # pragma: no cover


# ---------------------------------------------------------------------------------------------
# Named degenerate starts (issue 2, item 9)


def _polygon(n: int, radius: float, phase: float = 0.0) -> Points:
    k = np.arange(n)
    ang = phase + 2.0 * math.pi * k / n
    return np.column_stack([radius * np.cos(ang), radius * np.sin(ang)])


def _mirror_pairs(pairs: Sequence[tuple[float, float]], on_l: Sequence[float]) -> Points:
    pts = [(x, y) for x, y in pairs] + [(-x, y) for x, y in pairs] + [(0.0, y) for y in on_l]
    return np.asarray(pts, dtype=np.float64)


def degenerate_starts() -> dict[str, tuple[Points, float]]:
    """Hand-made starts that stress special cases: name -> ((n, 2) positions, a)."""
    side_for = 4.0
    starts: dict[str, tuple[Points, float]] = {
        # All robots on the vertical line L through the SEC centre (symmetric, all on the axis).
        "all-on-L": (np.column_stack([np.zeros(6), 2.2 * np.arange(6)]), 4.0),
        # All on a horizontal line: mirror symmetric with exactly one robot on L (odd count).
        "horizontal-line-odd": (np.column_stack([2.5 * np.arange(-3, 4), np.zeros(7)]), 4.0),
        "horizontal-line-even": (np.column_stack([2.5 * np.arange(6), np.zeros(6)]), 4.0),
        # Symmetric about L with a robot at o (the SEC's north point), and without one.
        "symmetric-robot-at-o": (
            _mirror_pairs([(4.0, -3.0), (2.0, 0.0)], [5.0, -1.0]),
            4.0,
        ),
        "symmetric-no-robot-at-o": (
            _mirror_pairs([(3.0, 4.0), (4.0, -3.0), (1.2, 0.0)], []),
            4.0,
        ),
        # Touching robots: a hexagonal rosette and a straight chain, all at contact distance.
        "touching-rosette": (np.vstack([np.zeros((1, 2)), _polygon(6, CONTACT)]), 4.0),
        "touching-chain": (np.column_stack([CONTACT * np.arange(5), np.zeros(5)]), 4.0),
        # Smallest swarms.
        "n2-touching": (np.array([[0.0, 0.0], [CONTACT, 0.0]]), 4.0),
        "n2-formed-rotated": (_polygon(2, 3.0, math.pi / 6), 4.0),
        "n3-uneven": (np.array([[0.0, 0.0], [3.0, 1.0], [-1.0, 2.5]]), 4.0),
        "n4-symmetric": (np.array([[-1.5, 0.0], [1.5, 0.0], [0.0, 2.5], [0.0, -3.0]]), 4.0),
        # A regular polygon whose side is below a: uniform, but too small.
        "small-uniform": (_polygon(6, 3.0), side_for),
        # Already a regular polygon with side >= a, not aligned with o: must stay put.
        "formed-rotated": (_polygon(8, target_radius(8, 4.0) + 0.5, 0.3), 4.0),
        # A large circle with unevenly spaced robots (no expansion, long slides).
        "large-uneven-circle": (
            30.0
            * np.column_stack(
                [
                    np.cos(np.array([0.0, 0.3, 0.5, 1.1, 1.9, 2.0, 3.0, 3.9, 4.4, 5.6])),
                    np.sin(np.array([0.0, 0.3, 0.5, 1.1, 1.9, 2.0, 3.0, 3.9, 4.4, 5.6])),
                ]
            ),
            4.0,
        ),
        # a just above the paper's bound 3 (ComputeRadius uses a* = max(a, 4)).
        "low-a-cluster": (np.vstack([np.zeros((1, 2)), _polygon(5, 2.3)]), 3.2),
    }
    starts = {name: (snap(pts), a) for name, (pts, a) in starts.items()}  # on the world's grid
    for name, (pts, _a) in starts.items():
        bad = overlapping_pair(pts)
        assert bad is None, f"degenerate start {name} overlaps: {bad}"
    return starts


# ---------------------------------------------------------------------------------------------
# --init files


def _coordinate(value: Any, path: str, i: int) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InitFileError(
            f"init file {path}: position {i} must hold finite numbers, got {value!r}"
        )
    return float(value)


def load_init(path: str, *, points: bool = False) -> tuple[Points, float | None]:
    """Read `{"positions": [[x, y], ...], "a": 4.0}` (a optional: absent, not null) -> ((n, 2)
    positions, a or None). `points`: point robots, which may share a point (no overlap check).

    Raises InitFileError with a one-line message saying what to fix.
    """
    data = _read_json(path)
    if not isinstance(data, dict) or "positions" not in data:
        raise InitFileError(f'init file {path} must hold {{"positions": [[x, y], ...], "a": 4.0}}')
    pts = _positions(data["positions"], path)
    bad = None if points else overlapping_pair(pts)
    if bad is not None:
        i, j, dist = bad
        raise InitFileError(
            f"init file {path}: robots {i} and {j} overlap (centres "
            f"{shown_apart(dist, OVERLAP_DISTANCE)} apart, need >= {OVERLAP_SHOWN})"
        )
    if "a" not in data:
        return pts, None
    a = data["a"]  # present: a number, whatever else it is ("4", true or null alike)
    if isinstance(a, bool) or not isinstance(a, (int, float)) or not math.isfinite(a):
        shown = json.dumps(a) if a is None or isinstance(a, bool) else repr(a)
        raise InitFileError(
            f"init file {path}: 'a' must be a number, got {shown} (leave 'a' out for the default)"
        )
    return pts, float(a)


def _read_json(path: str) -> Any:
    """The JSON value of the file at `path`; InitFileError if it cannot be read or parsed."""
    try:
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except OSError as exc:
        raise InitFileError(f"cannot read init file {path}: {exc.strerror}") from None
    except json.JSONDecodeError as exc:
        raise InitFileError(
            f"init file {path} is not JSON (line {exc.lineno}: {exc.msg})"
        ) from None
    except UnicodeDecodeError:
        raise InitFileError(f"init file {path} is not UTF-8 text") from None


def _positions(raw: Any, path: str) -> Points:
    """The (n, 2) positions of an init file's 'positions' list; InitFileError if malformed."""
    if not isinstance(raw, list) or not raw:
        raise InitFileError(f"init file {path}: 'positions' must be a non-empty list of [x, y]")
    pts = np.empty((len(raw), 2), dtype=np.float64)
    for i, pair in enumerate(raw):
        if not isinstance(pair, list) or len(pair) != 2:
            raise InitFileError(f"init file {path}: position {i} must be [x, y], got {pair!r}")
        pts[i] = (_coordinate(pair[0], path, i), _coordinate(pair[1], path, i))
    return pts


__all__ = [
    "CONTACT_SLACK",
    "KINDS",
    "InitFileError",
    "degenerate_starts",
    "load_init",
    "overlapping_pair",
    "random_start",
    "target_radius",
]
