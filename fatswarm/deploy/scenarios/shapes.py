"""Near-degenerate shapes as pure functions of explicit parameters: exact mirror images and
translations, nudges, polygons, rims, lattices, lines, chains and exact ties. The adversarial
families (`families.py`) draw the parameters from a seed; the hypothesis strategies pass them."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fatswarm.agent.geometry import target_radius
from fatswarm.domain.path import Points
from fatswarm.domain.tolerance import CONTACT
from fatswarm.world.physics import CONTACT_SLACK

SAFE_SQUEEZE: Final = 0.5 * CONTACT_SLACK
"""The most a built pair is set below contact (2 - 5e-8): touching to the world, not overlap."""
ACCEPT_DISTANCE: Final = CONTACT - 0.6 * CONTACT_SLACK
"""Builders accept a pair at >= 2 - 6e-8: 4e-8 above overlap, room for exact translations."""
PERTURB_RANGE: Final = (1e-12, 1e-6)  # near-symmetric: how far a robot leaves its mirror position
NEAR_RANGE: Final = (1e-9, 1e-6)  # near contact, near the axis, lattice and line nudges
OFFSET_RANGE: Final = (1e5, 1e6)  # |translation| of the offset family, per coordinate
RIM_PERIMETER: Final = (1.5, 4.0)  # rim circle perimeter, as a multiple of 2n (the robots' span)

# Rotated square lattices with exact decimal coordinates: steps (p, q) with p^2 + q^2 = 4 exactly.
PYTHAGOREAN_STEPS: Final = ((2.0, 0.0), (1.2, 1.6), (0.56, 1.92), (1.872, 0.704), (1.0752, 1.6864))
STEP_PLACES: Final = (0, 1, 2, 3, 4)  # decimals each step needs (fewer: shorter than 2)
LATTICES: Final = ("square", "square-rotated", "hex", "hex-vertical")
TIES: Final = ("axis-side", "two-pairs")
TIE_MIN_N: Final = 7  # pins (3) + the tied robots (3 or 4); below this the ties do not fit


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


def is_clear(p: NDArray[np.float64], placed: NDArray[np.float64], distance: float) -> bool:
    """True if p is at least `distance` from every row of `placed` ((k, 2), k may be 0)."""
    if len(placed) == 0:
        return True
    return bool(np.hypot(placed[:, 0] - p[0], placed[:, 1] - p[1]).min() >= distance)


def _others(points: NDArray[np.float64], index: int) -> NDArray[np.float64]:
    return np.delete(points, index, axis=0)


def unit_vector(angle: float) -> NDArray[np.float64]:
    return np.array([math.cos(angle), math.sin(angle)])


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


def along(points: Points, direction: NDArray[np.float64]) -> NDArray[np.float64]:
    """Every point's dot product with `direction`, written out (each product rounded, then the
    sum) rather than `points @ direction`: BLAS's kernel, and so its last bits, vary by CPU."""
    out: NDArray[np.float64] = points[:, 0] * direction[0] + points[:, 1] * direction[1]
    return out


def nudge_extreme(points: ArrayLike, direction: ArrayLike, magnitude: float) -> Points:
    """Move the robot farthest along `direction` by `magnitude` along it: it nears nobody.

    For p maximising u.p and any q, d/dt |p + t u - q|^2 = 2 u.(p - q) >= 0, so no distance drops.
    """
    pts = np.array(points, dtype=np.float64)
    u = np.asarray(direction, dtype=np.float64)
    u = u / float(np.hypot(u[0], u[1]))
    index = int(np.argmax(along(pts, u)))
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
    pick = (
        direction if direction is not None else (lambda g: unit_vector(g.uniform(0, 2 * math.pi)))
    )
    pts = np.array(points, dtype=np.float64)
    skip = set(avoid)
    allowed = [i for i in range(len(pts)) if i not in skip] or list(range(len(pts)))
    u = pick(rng)
    for _ in range(60):
        i = allowed[int(rng.integers(len(allowed)))]
        moved = pts[i] + magnitude * u
        if is_clear(moved, _others(pts, i), ACCEPT_DISTANCE):
            pts[i] = moved
            return pts, i
        u = pick(rng)
    for _ in range(200):  # the extreme robot along u nears nobody; want one not in `avoid`
        index = int(np.argmax(along(pts, u)))
        if index not in skip:
            break
        u = pick(rng)
    return nudge_extreme(pts, u, magnitude), index


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


def vertical_line(n: int) -> Points:
    """n touching robots on x = 0 at y = 0, 2, 4, ..."""
    return np.column_stack([np.zeros(n), CONTACT * np.arange(n)])


def horizontal_rows(rows: Sequence[tuple[float, float, Sequence[float]]]) -> Points:
    """Robots in horizontal rows: each row is (x of its first robot, its y, the gaps between
    neighbouring centres along it, one fewer than its robots)."""
    out: list[tuple[float, float]] = []
    for x0, y, gaps in rows:
        xs = x0 + np.concatenate([[0.0], np.cumsum(np.asarray(gaps, dtype=np.float64))])
        out.extend((float(x), float(y)) for x in xs)
    return np.asarray(out, dtype=np.float64).reshape(-1, 2)


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
# Symmetric configurations with exact ties


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
                and is_clear(p, full, CONTACT + 0.2)
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
    for _ in range(200):
        t = right[int(rng.integers(len(right)))]
        made = _tie(rng, tie, n, t, radius)
        if made is None:
            continue
        tied, core_pairs, core_heights, reach = made
        if min_separation(np.vstack([tied, pins_full])) < CONTACT + 0.2:
            continue
        base_pairs = np.vstack([pins_pairs, core_pairs])
        base_heights = np.concatenate([pins_heights, core_heights])
        away = [(t, reach + 0.5)]
        filled = _fill_symmetric(rng, base_pairs, base_heights, n - 3 - len(tied), radius, away)
        if filled is not None:
            return filled
    return None


# The tied robots of one draw: ((k, 2) positions, their pair offsets, their axis heights, their
# distance to the target they tie for).
_Tie = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float]


def _tie(
    rng: np.random.Generator, tie: str, n: int, t: NDArray[np.float64], radius: float
) -> _Tie | None:
    """The robots tied for target t (`tied_symmetric`), or None if this draw does not fit."""
    inner = radius - 1.5
    if tie == "axis-side":
        return _axis_side_tie(rng, n, t, inner)
    if tie == "two-pairs":
        return _two_pairs_tie(rng, n, t, radius, inner)
    raise ValueError(f"unknown tie {tie!r}; choose one of {', '.join(TIES)}")


def _axis_side_tie(
    rng: np.random.Generator, n: int, t: NDArray[np.float64], inner: float
) -> _Tie | None:
    """A robot on the axis and a side robot (with its mirror) at one height, as far from t."""
    if n < TIE_MIN_N - 1:
        raise ValueError(f"the axis-side tie needs n >= {TIE_MIN_N - 1}, got {n}")
    w = 2.0 * float(t[0])
    if w < CONTACT + 0.5 or w > inner:
        return None
    ymax = math.sqrt(inner * inner - w * w)
    y = float(rng.uniform(-ymax, ymax))
    tied = np.array([[0.0, y], [w, y], [-w, y]])
    core_pairs = np.array([[w, y]])
    core_heights = np.array([y])
    return tied, core_pairs, core_heights, float(np.hypot(*(tied[0] - t)))


def _two_pairs_tie(
    rng: np.random.Generator, n: int, t: NDArray[np.float64], radius: float, inner: float
) -> _Tie | None:
    """Two mirror pairs at the same distance from t."""
    if n < TIE_MIN_N:
        raise ValueError(f"the two-pairs tie needs n >= {TIE_MIN_N}, got {n}")
    rho = float(rng.uniform(CONTACT + 0.5, max(CONTACT + 0.6, 0.6 * radius)))
    angles = rng.uniform(0.0, 2.0 * math.pi, size=2)
    ps = np.array([t + rho * unit_vector(float(a)) for a in angles])
    if (np.hypot(ps[:, 0], ps[:, 1]) > inner).any() or (ps[:, 0] < 1.1).any():
        return None
    if np.hypot(*(ps[0] - ps[1])) < CONTACT + 0.2:
        return None
    tied = np.vstack([ps, ps * [-1.0, 1.0]])
    return tied, ps, np.empty(0), rho


__all__ = [
    "ACCEPT_DISTANCE",
    "LATTICES",
    "NEAR_RANGE",
    "OFFSET_RANGE",
    "PERTURB_RANGE",
    "PYTHAGOREAN_STEPS",
    "RIM_PERIMETER",
    "SAFE_SQUEEZE",
    "STEP_PLACES",
    "TIES",
    "TIE_MIN_N",
    "exact_quantum",
    "exact_translation",
    "grid_walk",
    "hex_row_height",
    "horizontal_rows",
    "is_clear",
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
    "unit_vector",
    "vertical_line",
]
