"""How each adversarial family draws a start: a variant and its parameters from a seeded
generator, built from the shapes (`shapes.py`). `adversarial.py` names the families, seeds them,
retries a draw that did not fit and checks what they build."""

from __future__ import annotations

import math
from typing import Final

import numpy as np
from numpy.typing import NDArray

from fatswarm.deploy.scenarios.shapes import (
    ACCEPT_DISTANCE,
    LATTICES,
    NEAR_RANGE,
    PERTURB_RANGE,
    PYTHAGOREAN_STEPS,
    RIM_PERIMETER,
    SAFE_SQUEEZE,
    TIE_MIN_N,
    grid_walk,
    hex_row_height,
    horizontal_rows,
    is_clear,
    lattice_points,
    mirror_configuration,
    nudge,
    regular_polygon,
    rim_points,
    tied_symmetric,
    unit_vector,
    vertical_line,
)
from fatswarm.domain.path import Points
from fatswarm.domain.tolerance import CONTACT

FORMED_MAX_OFFSET: Final = 1e5
FORMED_SIDE: Final = 4.0  # least side of a formed polygon: a = 4 accepts it
DECIMALS: Final = (3, 4, 5, 6, 7)  # lattices are written to this many decimals


class ConstructionError(RuntimeError):
    """A builder could not place its robots: a bug in this module, never the caller's fault."""


class Retry(Exception):
    """One construction attempt failed (a rejection loop gave up); draw again."""


Built = tuple[str, Points, float | None]  # (variant, positions, mirror axis x or None)


# ---------------------------------------------------------------------------------------------
# Drawn distances and directions


def _log_uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    lo, hi = bounds
    return float(10.0 ** rng.uniform(math.log10(lo), math.log10(hi)))


def _direction_across(rng: np.random.Generator) -> NDArray[np.float64]:
    """A random unit vector with |x| >= 1/2, so a move along it always leaves a mirror position."""
    angle = rng.uniform(-math.pi / 3, math.pi / 3) + (math.pi if rng.random() < 0.5 else 0.0)
    return unit_vector(angle)


def _contact_distance(rng: np.random.Generator) -> float:
    """2 + eps or 2 - eps with eps log-uniform in NEAR_RANGE; below 2 only down to SAFE_SQUEEZE."""
    eps = _log_uniform(rng, NEAR_RANGE)
    if eps <= SAFE_SQUEEZE and rng.random() < 0.5:
        return CONTACT - eps
    return CONTACT + eps


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
            if is_clear(p, full, separation):
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


def _axis_x(rng: np.random.Generator) -> float:
    return 0.0 if rng.random() < 0.3 else float(rng.integers(-50, 51))


def draw_exact_symmetric(rng: np.random.Generator, n: int, variant: str | None = None) -> Built:
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


def draw_near_symmetric(rng: np.random.Generator, n: int) -> Built:
    base = ["random", "near-axis-pair"] + (["tie-axis-side"] if n >= TIE_MIN_N else [])
    choice = base[int(rng.integers(len(base)))]
    variant, pts, axis = draw_exact_symmetric(rng, n, choice)
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


# ---------------------------------------------------------------------------------------------
# Touching, lattices, lines


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
                cand = placed[i] + d1 * unit_vector(float(rng.uniform(0.0, 2.0 * math.pi)))
            if cand is None or not is_clear(cand, placed, ACCEPT_DISTANCE):
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
            cand = pts[k - 1] + link * unit_vector(heading + turn)
            if is_clear(cand, pts[: k - 1], ACCEPT_DISTANCE):
                heading += turn
                pts[k] = cand
                break
        else:
            return None
    return pts


def draw_near_touching(rng: np.random.Generator, n: int) -> Built:
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
        raise Retry
    return variant, pts + rng.integers(-20, 21, size=2).astype(np.float64), None


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
        if is_clear(p, np.asarray(chosen).reshape(-1, 2), ACCEPT_DISTANCE):
            chosen.append(p)
            if len(chosen) == n:
                return np.asarray(chosen)
    return None


def draw_lattice(rng: np.random.Generator, n: int) -> Built:
    kind = LATTICES[int(rng.integers(len(LATTICES)))]
    decimals = DECIMALS[int(rng.integers(len(DECIMALS)))]
    step = int(rng.integers(1, len(PYTHAGOREAN_STEPS)))
    pts = _lattice_patch(rng, kind, n, decimals, step)
    if pts is None:
        raise Retry
    variant = f"{kind}-{decimals}dp"
    if rng.random() < 0.5:
        pts, _ = nudge(rng, pts, _log_uniform(rng, NEAR_RANGE))
        variant += "+nudged"
    return variant, pts, None


def draw_vertical_line(rng: np.random.Generator, n: int) -> Built:
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


def draw_cluster(rng: np.random.Generator, n: int) -> Built:
    separation = _symmetric_separation(rng)
    radius = 1.1 * separation * math.sqrt(n) + 1.0
    pts = np.empty((0, 2))
    for attempt in range(400 * n):
        if attempt % 300 == 299:
            radius *= 1.1
        p = rng.uniform(-radius, radius, size=2)
        if is_clear(p, pts, separation):
            pts = np.vstack([pts, p])
            if len(pts) == n:
                return "cluster", pts, None
    raise Retry


# ---------------------------------------------------------------------------------------------
# Horizontal rows


def _split(rng: np.random.Generator, n: int, parts: int) -> list[int]:
    """n robots in `parts` rows of at least one each, the cuts drawn at random."""
    cuts = sorted(int(c) for c in rng.choice(np.arange(1, n), size=parts - 1, replace=False))
    return [b - a for a, b in zip([0, *cuts], [*cuts, n], strict=True)]


def _row_gaps(rng: np.random.Generator, count: int, kind: str) -> list[float]:
    """The gaps between `count` + 1 neighbours of a row: touching, near touching, or mixed."""
    if kind == "touching":
        return [CONTACT] * count
    if kind == "near":
        return [_contact_distance(rng) for _ in range(count)]
    return [
        CONTACT if rng.random() < 0.5 else CONTACT + float(rng.uniform(0.0, 2.0))
        for _ in range(count)
    ]


def draw_rows(rng: np.random.Generator, n: int) -> Built:
    """One to three horizontal rows of touching (or near-touching) robots, each at least 2 above
    the one below, shifted sideways at random."""
    count = min(n, (1, 2, 3)[int(rng.choice(3, p=[0.5, 0.3, 0.2]))])
    kind = ("touching", "near", "mixed")[int(rng.choice(3, p=[0.5, 0.25, 0.25]))]
    y, rows = 0.0, []
    for size in _split(rng, n, count):
        shift = float(rng.integers(-n, n + 1)) if rng.random() < 0.5 else rng.uniform(-n, n)
        rows.append((float(shift), y, _row_gaps(rng, size - 1, kind)))
        y += CONTACT if rng.random() < 0.4 else float(rng.uniform(CONTACT, 4.0 * CONTACT))
    pts = horizontal_rows(rows)
    return f"{count}-row-{kind}", pts + rng.integers(-20, 21, size=2).astype(np.float64), None


def _stack_step(rng: np.random.Generator, kind: str) -> tuple[float, float]:
    """(sideways shift, height) of one row over the one below, touching it: a square stack, a
    brick wall (hex rows, the height written to 3-7 decimals) or a slant by up to 1."""
    if kind == "square":
        return 0.0, CONTACT
    if kind == "brick":
        return 1.0, hex_row_height(DECIMALS[int(rng.integers(len(DECIMALS)))])
    shift = float(rng.uniform(0.0, 1.0))  # (shift, h) and (shift - 2, h): both >= 2 away
    return shift, math.sqrt(CONTACT * CONTACT - shift * shift)


def draw_stacked_rows(rng: np.random.Generator, n: int) -> Built:
    """Two or more rows of touching robots stacked on one another, each row touching the one
    below: square, brick wall or slanted; the top row may be short (left, centred or right)."""
    count = int(rng.integers(2, max(2, (n + 1) // 2) + 1))
    width = -(-n // count)
    count = -(-n // width)
    kind = ("square", "brick", "slant")[int(rng.integers(3))]
    shift, height = _stack_step(rng, kind)
    align = ("left", "centre", "right")[int(rng.integers(3))]
    rows = []
    for k in range(count):
        size = min(width, n - k * width)
        spare = width - size  # the top row's robots sit on whole cells, touching the row below
        lead = CONTACT * {"left": 0, "centre": spare // 2, "right": spare}[align]
        offset = shift * (k % 2) if kind == "brick" else shift * k
        rows.append((offset + lead, k * height, [CONTACT] * (size - 1)))
    pts = horizontal_rows(rows)
    variant = f"{kind}-{count}x{width}-{align}"
    if rng.random() < 0.3:
        pts, _ = nudge(rng, pts, _log_uniform(rng, NEAR_RANGE))
        variant += "+nudged"
    return variant, pts + rng.integers(-20, 21, size=2).astype(np.float64), None


# ---------------------------------------------------------------------------------------------
# Rims and formed polygons


def draw_rim(rng: np.random.Generator, n: int) -> Built:
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
    # the rotation written out, not `local @ R` (BLAS's kernel, and so the bits, vary by CPU)
    turned = np.column_stack([x * c - local[:, 1] * s, x * s + local[:, 1] * c])
    return variant, turned + center, None


def draw_formed(rng: np.random.Generator, n: int) -> Built:
    pick = int(rng.integers(3))
    side = (FORMED_SIDE, float(rng.uniform(4.0, 6.0)), float(rng.uniform(6.0, 9.0)))[pick]
    far = bool(rng.random() < 0.5)
    center = rng.uniform(
        -FORMED_MAX_OFFSET if far else -10.0, FORMED_MAX_OFFSET if far else 10.0, size=2
    )
    pts = regular_polygon(n, side, float(rng.uniform(0.0, 2.0 * math.pi)), center)
    return f"{('side=4', 'side=4..6', 'side=6..9')[pick]}{'+offset' if far else ''}", pts, None


__all__ = [
    "Built",
    "ConstructionError",
    "Retry",
    "draw_cluster",
    "draw_exact_symmetric",
    "draw_formed",
    "draw_lattice",
    "draw_near_symmetric",
    "draw_near_touching",
    "draw_rim",
    "draw_rows",
    "draw_stacked_rows",
    "draw_vertical_line",
]
