"""Adversarial starts: seeded families of near-degenerate configurations that random starts miss.

Each start is deterministic from (family, n, seed) and valid (every pair of centres at least
2 - CONTACT_SLACK apart). The builders below are pure functions of explicit parameters, so the
hypothesis strategies (tests/property/strategies.py) build the same classes without seeds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fatswarm.agent.geometry import target_radius
from fatswarm.domain.draws import ADVERSARIAL_STREAM, CASES_STREAM
from fatswarm.domain.path import Points
from fatswarm.domain.tolerance import CONTACT
from fatswarm.world.physics import CONTACT_SLACK, validate_configuration

SEED_MASK: Final = 0xFFFFFFFF
MAX_N: Final = 400  # largest n any family builds (rejection sampling stays fast up to here)

SAFE_SQUEEZE: Final = 0.5 * CONTACT_SLACK
"""The most a built pair is set below contact (2 - 5e-8): touching to the world, not overlap."""
ACCEPT_DISTANCE: Final = CONTACT - 0.6 * CONTACT_SLACK
"""Builders accept a pair at >= 2 - 6e-8: 4e-8 above overlap, room for exact translations."""
PERTURB_RANGE: Final = (1e-12, 1e-6)  # near-symmetric: how far a robot leaves its mirror position
NEAR_RANGE: Final = (1e-9, 1e-6)  # near contact, near the axis, lattice and line nudges
OFFSET_RANGE: Final = (1e5, 1e6)  # |translation| of the offset family, per coordinate
FORMED_MAX_OFFSET: Final = 1e5
FORMED_SIDE: Final = 4.0  # least side of a formed polygon: a = 4 accepts it
DECIMALS: Final = (3, 4, 5, 6, 7)  # lattices are written to this many decimals
RIM_PERIMETER: Final = (1.5, 4.0)  # rim circle perimeter, as a multiple of 2n (the robots' span)
SIDES: Final = (3.2, 4.0, 6.0)  # a of an adversarial case: just above 3, the default, wide

# Rotated square lattices with exact decimal coordinates: steps (p, q) with p^2 + q^2 = 4 exactly.
PYTHAGOREAN_STEPS: Final = ((2.0, 0.0), (1.2, 1.6), (0.56, 1.92), (1.872, 0.704), (1.0752, 1.6864))
STEP_PLACES: Final = (0, 1, 2, 3, 4)  # decimals each step needs (fewer: shorter than 2)
LATTICES: Final = ("square", "square-rotated", "hex", "hex-vertical")
TIES: Final = ("axis-side", "two-pairs")
TIE_MIN_N: Final = 7  # pins (3) + the tied robots (3 or 4); below this the ties do not fit


@dataclass(frozen=True, slots=True)
class Family:
    """One adversarial family: its name, what it stresses, and the n it builds."""

    name: str
    description: str
    n_min: int
    n_max: int = MAX_N


FAMILY_TABLE: Final = (
    Family(
        "near-symmetric",
        "mirror symmetric about a vertical line, then 1-3 robots moved by "
        "1e-12..1e-6; some with a pair 1 +- 1e-9..1e-6 from the axis, some with exact ties",
        2,
    ),
    Family(
        "exact-symmetric",
        "exactly mirrored about x = c (c an integer): random, a pair "
        "touching across the axis or 1e-9..1e-6 from touching, exact ties of candidates",
        2,
    ),
    Family(
        "near-touching",
        "clusters and chains with neighbours 2 +- 1e-9..1e-6 apart (never "
        "below 2 - 5e-8), and exactly touching chains",
        2,
    ),
    Family(
        "lattice",
        "square (also Pythagorean-rotated) and hexagonal touching lattices written "
        "to 3-7 decimals, some with one robot nudged by 1e-9..1e-6",
        2,
    ),
    Family(
        "vertical-line",
        "touching robots on x = 0 (y = 0, 2, 4, ...), one moved by "
        "1e-9..1e-6 sideways or along the line",
        2,
    ),
    Family(
        "offset", "another family or a random cluster translated exactly by 1e5..1e6 in x and y", 2
    ),
    Family(
        "rim",
        "robots near one circle of perimeter 1.5-4 x 2n: on it (some touching), in a "
        "thin annulus, on a jittered regular polygon, along a parabola arc",
        3,
    ),
    Family(
        "formed",
        "an already formed regular n-gon of side >= 4, rotated at random, possibly "
        "offset by up to 1e5",
        2,
    ),
)
FAMILIES: Final[tuple[str, ...]] = tuple(f.name for f in FAMILY_TABLE)
DESCRIPTIONS: Final[Mapping[str, str]] = MappingProxyType(
    {f.name: f.description for f in FAMILY_TABLE}
)
OFFSET_BASES: Final = (
    "near-symmetric",
    "exact-symmetric",
    "near-touching",
    "lattice",
    "vertical-line",
    "rim",
    "cluster",
)


class ConstructionError(RuntimeError):
    """A builder could not place its robots: a bug in this module, never the caller's fault."""


class _Retry(Exception):
    """One construction attempt failed (a rejection loop gave up); draw again."""


@dataclass(frozen=True, slots=True, eq=False)
class AdversarialStart:
    """A built start: (n, 2) positions, which variant of the family, and its mirror axis if any.

    `axis_x` is the x of the vertical mirror line of the (unperturbed) configuration, or None.
    """

    family: str
    variant: str
    n: int
    seed: int
    positions: Points
    axis_x: float | None = None


@dataclass(frozen=True, slots=True)
class Case:
    """One adversarial run: the start (family, n, seed) and the side a it is run with."""

    family: str
    n: int
    seed: int
    a: float

    def start(self) -> Points:
        """The (n, 2) start of this case."""
        return adversarial_start(self.family, self.n, self.seed)


# ---------------------------------------------------------------------------------------------
# Small geometric helpers


def min_separation(points: ArrayLike) -> float:
    """The least distance between two centres (inf below two robots): how close to contact."""
    pts = np.asarray(points, dtype=np.float64)
    if len(pts) < 2:
        return math.inf
    dist = np.hypot(pts[:, None, 0] - pts[None, :, 0], pts[:, None, 1] - pts[None, :, 1])
    np.fill_diagonal(dist, np.inf)
    return float(dist.min())


def _clear(p: NDArray[np.float64], placed: NDArray[np.float64], distance: float) -> bool:
    """True if p is at least `distance` from every row of `placed` ((k, 2), k may be 0)."""
    if len(placed) == 0:
        return True
    return bool(np.hypot(placed[:, 0] - p[0], placed[:, 1] - p[1]).min() >= distance)


def _others(points: NDArray[np.float64], index: int) -> NDArray[np.float64]:
    return np.delete(points, index, axis=0)


def _log_uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    lo, hi = bounds
    return float(10.0 ** rng.uniform(math.log10(lo), math.log10(hi)))


def _unit(angle: float) -> NDArray[np.float64]:
    return np.array([math.cos(angle), math.sin(angle)])


def _direction_across(rng: np.random.Generator) -> NDArray[np.float64]:
    """A random unit vector with |x| >= 1/2, so a move along it always leaves a mirror position."""
    angle = rng.uniform(-math.pi / 3, math.pi / 3) + (math.pi if rng.random() < 0.5 else 0.0)
    return _unit(angle)


def _contact_distance(rng: np.random.Generator) -> float:
    """2 + eps or 2 - eps with eps log-uniform in NEAR_RANGE; below 2 only down to SAFE_SQUEEZE."""
    eps = _log_uniform(rng, NEAR_RANGE)
    if eps <= SAFE_SQUEEZE and rng.random() < 0.5:
        return CONTACT - eps
    return CONTACT + eps


def exact_quantum(bound: float) -> float:
    """A power of two q: multiples of q below `bound` in magnitude, and their sums, are exact."""
    exponent = math.frexp(max(abs(bound), 1.0))[1] + 1  # 2**exponent > 2 * bound
    return 2.0 ** (exponent - 53)


def exact_translation(points: ArrayLike, offset: ArrayLike) -> tuple[Points, NDArray[np.float64]]:
    """(points + offset with no rounding, the offset actually applied): both are first put on a
    common power-of-two grid, the spacing of doubles at the result's magnitude (2^-31 at 1e6).

    The relative geometry is kept bit for bit after moving each centre by at most half a grid
    step (distances change by < 1e-9); a multiple of the grid (an integer axis) moves exactly.
    """
    pts = np.asarray(points, dtype=np.float64)
    off = np.asarray(offset, dtype=np.float64).reshape(2)
    q = exact_quantum(float(np.abs(pts).max(initial=0.0)) + float(np.abs(off).max()) + 1.0)
    applied = np.rint(off / q) * q
    out: Points = np.rint(pts / q) * q + applied
    return out, applied


def translate_exactly(points: ArrayLike, offset: ArrayLike) -> Points:
    """Points + offset with no rounding (see `exact_translation`)."""
    return exact_translation(points, offset)[0]


def nudge_extreme(points: ArrayLike, direction: ArrayLike, magnitude: float) -> Points:
    """Move the robot farthest along `direction` by `magnitude` along it: it nears nobody.

    For p maximising u.p and any q, d/dt |p + t u - q|^2 = 2 u.(p - q) >= 0, so no distance drops.
    """
    pts = np.array(points, dtype=np.float64)
    u = np.asarray(direction, dtype=np.float64)
    u = u / float(np.hypot(u[0], u[1]))
    index = int(np.argmax(pts @ u))
    pts[index] += magnitude * u
    return pts


def nudge(
    rng: np.random.Generator,
    points: Points,
    magnitude: float,
    direction: Callable[[np.random.Generator], NDArray[np.float64]] | None = None,
    avoid: Sequence[int] = (),
) -> tuple[Points, int]:
    """Move one random robot (not in `avoid`) by `magnitude` in a random direction, keeping every
    pair >= ACCEPT_DISTANCE; falls back to `nudge_extreme`. Returns (points, robot moved)."""
    pick = direction if direction is not None else (lambda g: _unit(g.uniform(0, 2 * math.pi)))
    pts = np.array(points, dtype=np.float64)
    skip = set(avoid)
    allowed = [i for i in range(len(pts)) if i not in skip] or list(range(len(pts)))
    u = pick(rng)
    for _ in range(60):
        i = allowed[int(rng.integers(len(allowed)))]
        moved = pts[i] + magnitude * u
        if _clear(moved, _others(pts, i), ACCEPT_DISTANCE):
            pts[i] = moved
            return pts, i
        u = pick(rng)
    for _ in range(200):  # the extreme robot along u nears nobody; want one not in `avoid`
        index = int(np.argmax(pts @ u))
        if index not in skip:
            break
        u = pick(rng)
    return nudge_extreme(pts, u, magnitude), index


def _circle_intersection(
    p: NDArray[np.float64], r1: float, q: NDArray[np.float64], r2: float, left: bool
) -> NDArray[np.float64] | None:
    """A point at distance r1 from p and r2 from q (left or right of p -> q), or None."""
    d = float(np.hypot(*(q - p)))
    if d <= 0.0:
        return None
    along = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d)
    h2 = r1 * r1 - along * along
    if h2 < 0.0:
        return None
    e = (q - p) / d
    perp = np.array([-e[1], e[0]]) * (1.0 if left else -1.0)
    out: NDArray[np.float64] = p + along * e + math.sqrt(h2) * perp
    return out


# ---------------------------------------------------------------------------------------------
# Public builders: pure functions of explicit parameters (the strategies use them too)


def mirror_configuration(
    pair_offsets: ArrayLike, axis_heights: ArrayLike, axis_x: float = 0.0
) -> Points:
    """Robots exactly mirrored about x = axis_x: pairs (axis_x +- dx, y), then robots on the axis.

    `pair_offsets` is (p, 2) of (dx > 0, y); dx and axis_x are rounded to a power-of-two grid so
    that axis_x + dx and axis_x - dx are exact (the mirror image of the set is the set, bitwise).
    """
    pairs = np.asarray(pair_offsets, dtype=np.float64).reshape(-1, 2)
    heights = np.asarray(axis_heights, dtype=np.float64).reshape(-1)
    if len(pairs) and not (pairs[:, 0] > 0.0).all():
        raise ValueError("mirror pairs need an offset dx > 0 from the axis (dx = 0 is on the axis)")
    reach = float(np.abs(pairs[:, 0]).max(initial=0.0))
    q = exact_quantum(abs(axis_x) + reach + 1.0)
    axis = float(np.rint(axis_x / q) * q)
    dx = np.rint(pairs[:, 0] / q) * q
    right = np.column_stack([axis + dx, pairs[:, 1]])
    left = np.column_stack([axis - dx, pairs[:, 1]])
    on_axis = np.column_stack([np.full(len(heights), axis), heights])
    return np.vstack([right, left, on_axis]).astype(np.float64)


def regular_polygon(n: int, side: float, angle: float, center: ArrayLike = (0.0, 0.0)) -> Points:
    """The n vertices of a regular n-gon of the given side, first vertex at `angle` (radians)."""
    if n < 2:
        raise ValueError(f"a regular polygon needs n >= 2, got {n}")
    radius = side / (2.0 * math.sin(math.pi / n))
    theta = angle + 2.0 * math.pi * np.arange(n) / n
    c = np.asarray(center, dtype=np.float64)
    return np.column_stack([c[0] + radius * np.cos(theta), c[1] + radius * np.sin(theta)])


def rim_min_gap(radius: float) -> float:
    """Least angle between two robots on a circle of `radius` (their chord is then exactly 2)."""
    if radius < 1.0:
        raise ValueError(f"robots fit on a circle only if its radius is >= 1, got {radius}")
    return 2.0 * math.asin(CONTACT / (2.0 * radius))


def rim_points(
    center: ArrayLike,
    radius: float,
    gap_weights: ArrayLike,
    phase: float = 0.0,
    radial_offsets: ArrayLike | None = None,
) -> Points:
    """Robots on a circle (radius + radial_offsets[i]): the angular gaps are the least gap for the
    innermost radius plus the spare angle shared out by `gap_weights` (zero weight: touching)."""
    weights = np.asarray(gap_weights, dtype=np.float64).reshape(-1)
    n = len(weights)
    radial = np.zeros(n) if radial_offsets is None else np.asarray(radial_offsets, np.float64)
    inner = radius + float(radial.min(initial=0.0))
    least = rim_min_gap(inner)
    spare = 2.0 * math.pi - n * least
    if spare < 0.0:
        raise ValueError(f"{n} robots do not fit on a circle of radius {inner:.6g}")
    total = float(weights.sum())
    if not (weights >= 0.0).all() or total <= 0.0:
        raise ValueError("gap weights must be >= 0 with a positive sum")
    gaps = least + spare * weights / total
    theta = phase + np.concatenate([[0.0], np.cumsum(gaps[:-1])])
    c = np.asarray(center, dtype=np.float64)
    r = radius + radial
    return np.column_stack([c[0] + r * np.cos(theta), c[1] + r * np.sin(theta)])


def hex_row_height(decimals: int) -> float:
    """sqrt(3) written to `decimals` places, rounded up when rounding down would make diagonal
    neighbours overlap (1.732 -> 1.733; 1.7320508 stays: 2 - 7e-9 is touching)."""
    scale = 10.0**decimals
    h = round(math.sqrt(3.0), decimals)
    if math.hypot(1.0, h) < ACCEPT_DISTANCE:
        h = math.ceil(math.sqrt(3.0) * scale) / scale
    return h


def lattice_points(
    kind: str, cells: ArrayLike, decimals: int, origin: ArrayLike = (0.0, 0.0), step: int = 1
) -> Points:
    """Centres of lattice `cells` ((k, 2) integers), spacing 2, written to `decimals` places.

    kind: 'square', 'square-rotated' (steps PYTHAGOREAN_STEPS[step], exact in decimal), 'hex'
    (rows hex_row_height apart, odd rows shifted by 1) or 'hex-vertical' (the same, transposed).
    """
    ij = np.asarray(cells, dtype=np.float64).reshape(-1, 2)
    i, j = ij[:, 0], ij[:, 1]
    if kind == "square":
        pts = np.column_stack([2.0 * i, 2.0 * j])
    elif kind == "square-rotated":
        p, q = PYTHAGOREAN_STEPS[step % len(PYTHAGOREAN_STEPS)]
        pts = np.column_stack([i * p - j * q, i * q + j * p])
    elif kind in ("hex", "hex-vertical"):
        h = hex_row_height(decimals)
        pts = np.column_stack([2.0 * i + np.mod(j, 2.0), j * h])
        if kind == "hex-vertical":
            pts = pts[:, ::-1]
    else:
        raise ValueError(f"unknown lattice {kind!r}; choose one of {', '.join(LATTICES)}")
    out: Points = np.round(pts + np.asarray(origin, dtype=np.float64), decimals)
    return out


def _lattice_patch(
    rng: np.random.Generator, kind: str, n: int, decimals: int, step: int
) -> Points | None:
    """n lattice robots: the cells nearest a random point, or rows of a random width."""
    origin = np.round(rng.uniform(-20.0, 20.0, size=2), decimals)
    if rng.random() < 0.6:  # a round patch about a random point
        m = math.isqrt(n) + 3
        box = np.array([(i, j) for j in range(-m, m + 1) for i in range(-m, m + 1)], np.float64)
        raw = lattice_points(kind, box, decimals, step=step)
        aim = rng.uniform(-1.5, 1.5, size=2)
        key = np.hypot(raw[:, 0] - aim[0], raw[:, 1] - aim[1])
        cells = box[np.lexsort((box[:, 0], box[:, 1], key))]
    else:  # rows of a random width, filled row by row, with a spare row
        width = int(rng.integers(1, 2 * math.isqrt(n) + 2))
        k = np.arange(n + width)
        cells = np.column_stack([k % width, k // width]).astype(np.float64)
    pts = lattice_points(kind, cells, decimals, origin, step)
    chosen: list[NDArray[np.float64]] = []
    for p in pts:  # drop any point the rounding would make overlap (none expected)
        if _clear(p, np.asarray(chosen).reshape(-1, 2), ACCEPT_DISTANCE):
            chosen.append(p)
            if len(chosen) == n:
                return np.asarray(chosen)
    return None


def vertical_line(n: int) -> Points:
    """n touching robots on x = 0 at y = 0, 2, 4, ..."""
    return np.column_stack([np.zeros(n), CONTACT * np.arange(n)])


def grid_walk(steps: Sequence[int]) -> Points:
    """An exactly touching chain on the square lattice of pitch 2: step codes 0..3 are E, N, W, S.

    A step onto a used cell turns to the next free direction; a dead end restarts beside the
    earliest cell with a free neighbour (the chain branches). Coordinates are exact integers.
    """
    moves = ((1, 0), (0, 1), (-1, 0), (0, -1))
    cells = [(0, 0)]
    used = {(0, 0)}
    for code in steps:
        x, y = cells[-1]
        for turn in range(4):
            dx, dy = moves[(code + turn) % 4]
            if (x + dx, y + dy) not in used:
                break
        else:
            x, y, dx, dy = next(
                (cx, cy, mx, my)
                for cx, cy in cells
                for mx, my in moves
                if (cx + mx, cy + my) not in used
            )
        cells.append((x + dx, y + dy))
        used.add(cells[-1])
    return CONTACT * np.asarray(cells, dtype=np.float64)


# ---------------------------------------------------------------------------------------------
# Symmetric configurations


def _random_mirror_half(
    rng: np.random.Generator,
    n: int,
    separation: float,
    near_axis: float | None,
    axis_count: int | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Random (pair offsets, axis heights) for n robots about x = 0, all >= separation apart.

    `near_axis`: the first pair has offset exactly this (1 + delta: discs nearly touching across
    the axis). Robots on the axis: `axis_count` or n mod 2 plus a few.
    """
    if axis_count is None:
        axis_count = n % 2 + 2 * int(rng.integers(0, n // 6 + 1))
    if near_axis is not None and n - axis_count < 2:
        axis_count = n - 2
    pair_count = (n - axis_count) // 2
    radius = 1.2 * separation * math.sqrt(n) + 1.0
    full = np.empty((0, 2))
    pairs: list[tuple[float, float]] = []
    heights: list[float] = []
    if near_axis is not None:
        y0 = float(rng.uniform(-radius, radius))
        pairs.append((near_axis, y0))
        full = np.array([[near_axis, y0], [-near_axis, y0]])
    kinds = ["pair"] * (pair_count - len(pairs)) + ["axis"] * axis_count
    for kind in (kinds[k] for k in rng.permutation(len(kinds))):
        for attempt in range(2000):
            if attempt % 200 == 199:
                radius *= 1.1
            y = float(rng.uniform(-radius, radius))
            x = 0.0 if kind == "axis" else float(rng.uniform(0.5 * separation, radius))
            p = np.array([x, y])
            if _clear(p, full, separation):
                break
        else:
            raise ConstructionError(f"could not place a symmetric robot for n={n}")
        if kind == "axis":
            heights.append(y)
            full = np.vstack([full, p])
        else:
            pairs.append((x, y))
            full = np.vstack([full, p, [-x, y]])
    return np.asarray(pairs, dtype=np.float64).reshape(-1, 2), np.asarray(heights, np.float64)


def _symmetric_separation(rng: np.random.Generator) -> float:
    return CONTACT if rng.random() < 0.4 else CONTACT + float(rng.uniform(0.0, 1.5))


def _near_axis_offset(rng: np.random.Generator) -> float:
    """1 + delta, delta log-uniform in NEAR_RANGE, or 1 - delta when the pair still only touches."""
    delta = _log_uniform(rng, NEAR_RANGE)
    if delta <= 0.5 * SAFE_SQUEEZE and rng.random() < 0.4:
        return 1.0 - delta
    return 1.0 + delta


def _pins(radius: float, robot_at_o: bool) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Three robots fixing the SEC (centre 0, `radius`) as an equilateral triangle: one on the axis
    at the north point o (or the south point) and a pair 120 degrees from it."""
    s = 0.5 * math.sqrt(3.0) * radius
    if robot_at_o:
        return np.array([[s, -0.5 * radius]]), np.array([radius])
    return np.array([[s, 0.5 * radius]]), np.array([-radius])


def _targets(n: int, radius: float, robot_at_o: bool) -> NDArray[np.float64]:
    """The algorithm's target points on the SEC (centre 0), from o, or o +- pi/n without a robot
    at o (agent.geometry.targets_on)."""
    theta = 2.0 * math.pi * np.arange(n) / n + (0.0 if robot_at_o else math.pi / n)
    return np.column_stack([radius * np.sin(theta), radius * np.cos(theta)])


def _fill_symmetric(
    rng: np.random.Generator,
    pairs: NDArray[np.float64],
    heights: NDArray[np.float64],
    count: int,
    radius: float,
    keep_away: Sequence[tuple[NDArray[np.float64], float]],
) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """Add `count` robots, mirror symmetric, strictly inside the circle (centre 0, radius - 1.5),
    >= 2.2 from everyone and farther than d from each (point, d) of `keep_away`."""
    full = np.vstack(
        [pairs, pairs * [-1.0, 1.0], np.column_stack([np.zeros(len(heights)), heights])]
    )
    new_pairs = [tuple(p) for p in pairs]
    new_heights = list(heights)
    todo = ["axis"] * (count % 2) + ["pair"] * (count // 2)
    inner = radius - 1.5
    for kind in todo:
        for _ in range(3000):
            y = float(rng.uniform(-inner, inner))
            x = 0.0 if kind == "axis" else float(rng.uniform(1.1, inner))
            p = np.array([x, y])
            if (
                math.hypot(x, y) <= inner
                and _clear(p, full, CONTACT + 0.2)
                and all(
                    np.hypot(*(p - a)) > d and np.hypot(*(p * [-1, 1] - a)) > d
                    for a, d in keep_away
                )
            ):
                break
        else:
            return None
        if kind == "axis":
            new_heights.append(y)
            full = np.vstack([full, p])
        else:
            new_pairs.append((x, y))
            full = np.vstack([full, p, [-x, y]])
    return np.asarray(new_pairs, np.float64).reshape(-1, 2), np.asarray(new_heights, np.float64)


def tied_symmetric(
    rng: np.random.Generator, tie: str, n: int, robot_at_o: bool, radius_factor: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """(pair offsets, axis heights) about x = 0 with an exact tie for a target T_k of the SEC.

    'axis-side' (n >= 6): a robot A on the axis and a side robot B (with its mirror) at the same
    height and the same distance from T_k. 'two-pairs' (n >= 7): two mirror pairs at the same
    distance from T_k. The SEC (radius = radius_factor x the target radius for a = 6, so no a of
    the cases expands it) is pinned by three robots; the others are farther from T_k and its
    mirror than the tied robots. None if this draw does not fit (try another rng state).
    """
    radius = radius_factor * max(target_radius(n, 6.0), 4.0 * math.sqrt(n), 8.0)
    pins_pairs, pins_heights = _pins(radius, robot_at_o)
    pins_full = np.vstack(
        [
            pins_pairs,
            pins_pairs * [-1.0, 1.0],
            np.column_stack([[0.0] * len(pins_heights), pins_heights]),
        ]
    )
    targets = _targets(n, radius, robot_at_o)
    right = [t for t in targets if t[0] > 1.0]
    if not right:
        return None
    inner = radius - 1.5
    for _ in range(200):
        t = right[int(rng.integers(len(right)))]
        if tie == "axis-side":
            if n < TIE_MIN_N - 1:
                raise ValueError(f"the axis-side tie needs n >= {TIE_MIN_N - 1}, got {n}")
            w = 2.0 * float(t[0])
            if w < CONTACT + 0.5 or w > inner:
                continue
            ymax = math.sqrt(inner * inner - w * w)
            y = float(rng.uniform(-ymax, ymax))
            tied = np.array([[0.0, y], [w, y], [-w, y]])
            core_pairs = np.array([[w, y]])
            core_heights = np.array([y])
            reach = float(np.hypot(*(tied[0] - t)))
        elif tie == "two-pairs":
            if n < TIE_MIN_N:
                raise ValueError(f"the two-pairs tie needs n >= {TIE_MIN_N}, got {n}")
            rho = float(rng.uniform(CONTACT + 0.5, max(CONTACT + 0.6, 0.6 * radius)))
            angles = rng.uniform(0.0, 2.0 * math.pi, size=2)
            ps = np.array([t + rho * _unit(float(a)) for a in angles])
            if (np.hypot(ps[:, 0], ps[:, 1]) > inner).any() or (ps[:, 0] < 1.1).any():
                continue
            if np.hypot(*(ps[0] - ps[1])) < CONTACT + 0.2:
                continue
            tied = np.vstack([ps, ps * [-1.0, 1.0]])
            core_pairs, core_heights = ps, np.empty(0)
            reach = rho
        else:
            raise ValueError(f"unknown tie {tie!r}; choose one of {', '.join(TIES)}")
        if min_separation(np.vstack([tied, pins_full])) < CONTACT + 0.2:
            continue
        base_pairs = np.vstack([pins_pairs, core_pairs])
        base_heights = np.concatenate([pins_heights, core_heights])
        away = [(t, reach + 0.5)]
        filled = _fill_symmetric(rng, base_pairs, base_heights, n - 3 - len(tied), radius, away)
        if filled is not None:
            return filled
    return None


# ---------------------------------------------------------------------------------------------
# The families


_Built = tuple[str, Points, float | None]  # (variant, positions, mirror axis x or None)


def _axis_x(rng: np.random.Generator) -> float:
    return 0.0 if rng.random() < 0.3 else float(rng.integers(-50, 51))


def _exact_symmetric(rng: np.random.Generator, n: int, variant: str | None = None) -> _Built:
    options = ["random", "axis-touching", "near-axis-pair"]
    if n >= TIE_MIN_N:
        options += ["tie-axis-side", "tie-two-pairs"]
    variant = variant or options[int(rng.integers(len(options)))]
    axis = _axis_x(rng)
    lift = float(rng.uniform(-30.0, 30.0))
    if variant.startswith("tie-"):
        tie = variant.removeprefix("tie-")
        made = tied_symmetric(rng, tie, n, bool(rng.random() < 0.5), rng.uniform(1.02, 1.3))
        if made is not None:
            pairs, heights = made
            pairs = pairs + np.array([0.0, lift])
            return variant, mirror_configuration(pairs, heights + lift, axis), axis
        variant = "random"  # the tie did not fit this draw
    near = {"axis-touching": 1.0, "near-axis-pair": _near_axis_offset(rng)}.get(variant)
    pairs, heights = _random_mirror_half(rng, n, _symmetric_separation(rng), near)
    pairs = pairs + np.array([0.0, lift])
    return variant, mirror_configuration(pairs, heights + lift, axis), axis


def _near_symmetric(rng: np.random.Generator, n: int) -> _Built:
    base = ["random", "near-axis-pair"] + (["tie-axis-side"] if n >= TIE_MIN_N else [])
    choice = base[int(rng.integers(len(base)))]
    variant, pts, axis = _exact_symmetric(rng, n, choice)
    count = 1 if n < 3 or rng.random() < 0.6 else int(rng.integers(2, 4))
    assert axis is not None
    mirror = pts * [-1.0, 1.0] + [2.0 * axis, 0.0]
    partner = np.hypot(
        mirror[:, None, 0] - pts[None, :, 0], mirror[:, None, 1] - pts[None, :, 1]
    ).argmin(axis=1)
    moved: list[int] = []
    for _ in range(count):  # distinct mirror classes, so no image is off by two perturbations
        pts, index = nudge(rng, pts, _log_uniform(rng, PERTURB_RANGE), _direction_across, moved)
        moved += [index, int(partner[index])]
        if len(set(moved)) >= n:
            break
    return f"{variant}+perturbed{len(set(moved[::2]))}", pts, axis


def _near_touching_cluster(rng: np.random.Generator, n: int) -> Points | None:
    """A packed cluster: each robot 2 +- eps from one or two earlier ones, nearest the centre."""
    pts = np.zeros((n, 2))
    k = 1
    stuck = 0
    while k < n:
        placed = pts[:k]
        centroid = placed.mean(axis=0)
        best: NDArray[np.float64] | None = None
        for _ in range(16):
            i = int(rng.integers(k))
            d1 = _contact_distance(rng)
            gaps = np.hypot(placed[:, 0] - placed[i, 0], placed[:, 1] - placed[i, 1])
            near = np.flatnonzero((gaps > 0.0) & (gaps < 2.0 * CONTACT - 1e-6))
            cand: NDArray[np.float64] | None
            if len(near) and rng.random() < 0.75:
                j = int(near[int(rng.integers(len(near)))])
                left = bool(rng.random() < 0.5)
                cand = _circle_intersection(placed[i], d1, placed[j], _contact_distance(rng), left)
            else:
                cand = placed[i] + d1 * _unit(float(rng.uniform(0.0, 2.0 * math.pi)))
            if cand is None or not _clear(cand, placed, ACCEPT_DISTANCE):
                continue
            if best is None or np.hypot(*(cand - centroid)) < np.hypot(*(best - centroid)):
                best = cand
        if best is None:
            stuck += 1
            if stuck > 50:
                return None
            continue
        pts[k] = best
        k += 1
    return pts


def _chain(rng: np.random.Generator, n: int, exact_links: bool) -> Points | None:
    """A chain turning by at most 70 degrees per link; links 2 exactly or 2 +- eps."""
    pts = np.zeros((n, 2))
    heading = float(rng.uniform(0.0, 2.0 * math.pi))
    for k in range(1, n):
        for _ in range(40):
            turn = float(rng.uniform(-7.0, 7.0)) * math.pi / 18.0
            link = CONTACT if exact_links else _contact_distance(rng)
            cand = pts[k - 1] + link * _unit(heading + turn)
            if _clear(cand, pts[: k - 1], ACCEPT_DISTANCE):
                heading += turn
                pts[k] = cand
                break
        else:
            return None
    return pts


def _near_touching(rng: np.random.Generator, n: int) -> _Built:
    variant = ("cluster", "chain", "touching-chain", "grid-walk")[int(rng.integers(4))]
    pts: Points | None
    if variant == "cluster":
        pts = _near_touching_cluster(rng, n)
    elif variant in ("chain", "touching-chain"):
        pts = _chain(rng, n, exact_links=variant == "touching-chain")
    else:
        walk = grid_walk([int(c) for c in rng.integers(0, 4, size=n - 1)])
        return variant, walk + rng.integers(-20, 21, size=2).astype(np.float64), None
    if pts is None:
        raise _Retry
    return variant, pts + rng.integers(-20, 21, size=2).astype(np.float64), None


def _lattice(rng: np.random.Generator, n: int) -> _Built:
    kind = LATTICES[int(rng.integers(len(LATTICES)))]
    decimals = DECIMALS[int(rng.integers(len(DECIMALS)))]
    step = int(rng.integers(1, len(PYTHAGOREAN_STEPS)))
    pts = _lattice_patch(rng, kind, n, decimals, step)
    if pts is None:
        raise _Retry
    variant = f"{kind}-{decimals}dp"
    if rng.random() < 0.5:
        pts, _ = nudge(rng, pts, _log_uniform(rng, NEAR_RANGE))
        variant += "+nudged"
    return variant, pts, None


def _vertical_line(rng: np.random.Generator, n: int) -> _Built:
    variant = ("exact", "sideways", "along", "squeezed")[
        int(rng.choice(4, p=[0.1, 0.35, 0.3, 0.25]))
    ]
    pts = vertical_line(n)
    k = int(rng.integers(n))
    delta = _log_uniform(rng, NEAR_RANGE)
    if variant == "sideways":
        pts[k, 0] = delta if rng.random() < 0.5 else -delta
    elif variant == "along":  # robot k and all above it move up: one gap of 2 + delta
        k = max(k, 1)
        pts[k:, 1] += delta
    elif variant == "squeezed":  # robot k moves toward a neighbour: 2 - delta, still touching
        delta = _log_uniform(rng, (NEAR_RANGE[0], SAFE_SQUEEZE))
        pts[k, 1] += delta if k == 0 else -delta
    return variant, pts, 0.0


def _cluster(rng: np.random.Generator, n: int) -> _Built:
    separation = _symmetric_separation(rng)
    radius = 1.1 * separation * math.sqrt(n) + 1.0
    pts = np.empty((0, 2))
    for attempt in range(400 * n):
        if attempt % 300 == 299:
            radius *= 1.1
        p = rng.uniform(-radius, radius, size=2)
        if _clear(p, pts, separation):
            pts = np.vstack([pts, p])
            if len(pts) == n:
                return "cluster", pts, None
    raise _Retry


def _offset(rng: np.random.Generator, n: int) -> _Built:
    bases = [b for b in OFFSET_BASES if b == "cluster" or _family(b).n_min <= n]
    base = bases[int(rng.integers(len(bases)))]
    child = np.random.default_rng(rng.integers(0, 2**63))
    variant, pts, axis = _attempts(_BUILDERS[base], child, n, base)
    off = rng.uniform(*OFFSET_RANGE, size=2) * np.where(rng.random(2) < 0.5, -1.0, 1.0)
    moved, applied = exact_translation(pts, off)
    new_axis = None if axis is None else axis + float(applied[0])  # exact: an integer axis
    return f"{base}:{variant}", moved, new_axis


def _rim(rng: np.random.Generator, n: int) -> _Built:
    variant = ("circle", "circle-touching", "annulus", "polygon", "parabola")[int(rng.integers(5))]
    radius = float(rng.uniform(*RIM_PERIMETER)) * CONTACT * n / (2.0 * math.pi)
    center = rng.uniform(-10.0, 10.0, size=2)
    phase = float(rng.uniform(0.0, 2.0 * math.pi))
    if variant in ("circle", "circle-touching"):
        weights = rng.dirichlet(np.ones(n))
        if variant == "circle-touching":  # some neighbours exactly touching
            weights[rng.random(n) < 0.5] = 0.0
            if weights.sum() <= 0.0:
                weights[0] = 1.0
        return variant, rim_points(center, radius, weights, phase), None
    if variant == "annulus":
        width = radius * _log_uniform(rng, (1e-9, 1e-2))
        radial = rng.uniform(-width, width, size=n)
        return variant, rim_points(center, radius, rng.dirichlet(np.ones(n)), phase, radial), None
    if variant == "polygon":
        side = 2.0 * radius * math.sin(math.pi / n)
        jitter = _log_uniform(rng, (1e-9, min(1e-1, 0.4 * (side - CONTACT))))
        pts = regular_polygon(n, side, phase, center)
        angles = rng.uniform(0.0, 2.0 * math.pi, size=n)
        pts = pts + jitter * np.sqrt(rng.random(n))[:, None] * np.column_stack(
            [np.cos(angles), np.sin(angles)]
        )
        return variant, pts, None
    # parabola y = x^2 / (2 radius): its osculating circle at the vertex is the rim circle
    spare = (float(rng.uniform(*RIM_PERIMETER)) - 1.0) * CONTACT * (n - 1)
    steps = CONTACT + spare * rng.dirichlet(np.ones(n - 1))
    x = np.concatenate([[0.0], np.cumsum(steps)])
    x -= x[-1] * float(rng.uniform(0.2, 0.8))
    local = np.column_stack([x, x * x / (2.0 * radius)])
    c, s = math.cos(phase), math.sin(phase)
    return variant, local @ np.array([[c, s], [-s, c]]) + center, None


def _formed(rng: np.random.Generator, n: int) -> _Built:
    pick = int(rng.integers(3))
    side = (FORMED_SIDE, float(rng.uniform(4.0, 6.0)), float(rng.uniform(6.0, 9.0)))[pick]
    far = bool(rng.random() < 0.5)
    center = rng.uniform(
        -FORMED_MAX_OFFSET if far else -10.0, FORMED_MAX_OFFSET if far else 10.0, size=2
    )
    pts = regular_polygon(n, side, float(rng.uniform(0.0, 2.0 * math.pi)), center)
    return f"{('side=4', 'side=4..6', 'side=6..9')[pick]}{'+offset' if far else ''}", pts, None


_BUILDERS: Final[Mapping[str, Callable[[np.random.Generator, int], _Built]]] = MappingProxyType(
    {
        "near-symmetric": _near_symmetric,
        "exact-symmetric": _exact_symmetric,
        "near-touching": _near_touching,
        "lattice": _lattice,
        "vertical-line": _vertical_line,
        "offset": _offset,
        "rim": _rim,
        "formed": _formed,
        "cluster": _cluster,
    }
)


def _family(name: str) -> Family:
    for fam in FAMILY_TABLE:
        if fam.name == name:
            return fam
    raise ValueError(f"unknown adversarial family {name!r}; choose one of {', '.join(FAMILIES)}")


def _attempts(
    builder: Callable[[np.random.Generator, int], _Built],
    rng: np.random.Generator,
    n: int,
    name: str,
) -> _Built:
    for _ in range(50):
        try:
            variant, pts, axis = builder(rng, n)
        except _Retry:
            continue
        pts = np.ascontiguousarray(pts, dtype=np.float64)
        if (
            pts.shape == (n, 2)
            and np.isfinite(pts).all()
            and min_separation(pts) >= (CONTACT - CONTACT_SLACK)
        ):
            return variant, pts, axis
    raise ConstructionError(f"could not build a valid {name} start for n={n}")  # pragma: no cover


def family_range(family: str) -> tuple[int, int]:
    """The least and greatest n the family builds."""
    fam = _family(family)
    return fam.n_min, fam.n_max


def build_adversarial(family: str, n: int, seed: int) -> AdversarialStart:
    """The start of (family, n, seed) with its variant and mirror axis; ValueError if n is out of
    the family's range or the family is unknown."""
    fam = _family(family)
    if (
        isinstance(n, bool)
        or not isinstance(n, (int, np.integer))
        or not (fam.n_min <= n <= fam.n_max)
    ):
        raise ValueError(f"family {family!r} builds n from {fam.n_min} to {fam.n_max}, got n={n!r}")
    n = int(n)
    rng = np.random.default_rng([ADVERSARIAL_STREAM, seed & SEED_MASK, n, FAMILIES.index(family)])
    variant, pts, axis = _attempts(_BUILDERS[family], rng, n, family)
    validate_configuration(pts)  # the contract: never an overlapping start
    return AdversarialStart(family, variant, n, seed, pts, axis)


def adversarial_start(family: str, n: int, seed: int) -> Points:
    """A valid (n, 2) start of the family, the same for the same (family, n, seed)."""
    return build_adversarial(family, n, seed).positions


def adversarial_cases(count: int, seed: int, n_max: int = 40) -> list[Case]:
    """`count` cases spread round-robin over the families, each family's n cycling through a
    shuffled n_min..n_max, a drawn from SIDES (for 'formed' only sides the polygon meets)."""
    if count < 0:
        raise ValueError(f"count must be >= 0, got {count}")
    families = [f for f in FAMILY_TABLE if f.n_min <= min(n_max, f.n_max)]
    if not families:
        raise ValueError(f"n_max must be at least 2 for any family to apply, got {n_max}")
    rng = np.random.default_rng([CASES_STREAM, seed & SEED_MASK])
    queues: dict[str, list[int]] = {f.name: [] for f in families}
    cases: list[Case] = []
    for index in range(count):
        fam = families[index % len(families)]
        queue = queues[fam.name]
        if not queue:
            sizes = np.arange(fam.n_min, min(n_max, fam.n_max) + 1)
            queue.extend(int(v) for v in rng.permutation(sizes))
        n = queue.pop()
        case_seed = int(rng.integers(0, 2**31))
        sides: Sequence[float] = SIDES
        if fam.name == "formed":  # keep it formed: a must not exceed the polygon's side
            side = min_separation(adversarial_start(fam.name, n, case_seed))
            sides = [s for s in SIDES if s <= side + 1e-9]
        cases.append(Case(fam.name, n, case_seed, float(sides[int(rng.integers(len(sides)))])))
    return cases


__all__ = [
    "DESCRIPTIONS",
    "FAMILIES",
    "FAMILY_TABLE",
    "SIDES",
    "AdversarialStart",
    "Case",
    "ConstructionError",
    "Family",
    "adversarial_cases",
    "adversarial_start",
    "build_adversarial",
    "exact_quantum",
    "exact_translation",
    "family_range",
    "grid_walk",
    "hex_row_height",
    "lattice_points",
    "min_separation",
    "mirror_configuration",
    "nudge",
    "nudge_extreme",
    "regular_polygon",
    "rim_min_gap",
    "rim_points",
    "tied_symmetric",
    "translate_exactly",
    "vertical_line",
]
