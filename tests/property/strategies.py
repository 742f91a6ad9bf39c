"""Hypothesis strategies for adversarial starts: the classes of deploy/scenarios/adversarial.py,
drawn here.

Each strategy draws the parameters that define its class (n, cells, perturbations 10**-k with k in
6..12) so that hypothesis can shrink them, and returns a valid (n, 2) float64 start (no two centres
closer than 2 - CONTACT_SLACK). Property tests over the algorithm live in the test modules.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
from hypothesis import assume
from hypothesis import strategies as st
from numpy.typing import NDArray

from fatswarm.deploy.scenarios import shapes as adv
from fatswarm.domain.path import Points

CELL: Final = 2.5  # grid spacing of jittered cells
JITTER: Final = 0.2  # |jitter| of a cell's robot: every pair of cells stays >= 2.1 apart
ROWS: Final = 12  # rows of the mirror half-grid (n <= 12 fits on the axis alone)
N_MAX: Final = 12
RIM_N_MAX: Final = 30
SQUEEZE_MIN_EXPONENT: Final = 8  # 10**-8 <= SAFE_SQUEEZE: only this close may go below contact

exponents = st.integers(6, 12)
magnitudes = exponents.map(lambda k: 10.0**-k)
jitters = st.floats(-JITTER, JITTER, allow_nan=False)


def _contact_distances() -> st.SearchStrategy[float]:
    """2 exactly, 2 + 10**-k, or 2 - 10**-k for k >= 8 (touching, never overlap)."""
    return st.one_of(
        st.just(2.0),
        magnitudes.map(lambda m: 2.0 + m),
        st.integers(SQUEEZE_MIN_EXPONENT, 12).map(lambda k: 2.0 - 10.0**-k),
    )


@st.composite
def near_symmetric_starts(draw: st.DrawFn) -> Points:
    """Mirror symmetric jittered half-grid cells about x = c (maybe a pair 1 + 10**-k from it),
    then one robot moved by 10**-k across the axis direction: symmetric only within 2e-6."""
    n = draw(st.integers(3, N_MAX))
    near_axis = draw(st.booleans())
    pair_count = draw(st.integers(int(near_axis), n // 2))
    axis_rows = draw(
        st.lists(
            st.integers(0, ROWS - 1),
            min_size=n - 2 * pair_count,
            max_size=n - 2 * pair_count,
            unique=True,
        )
    )
    cells = draw(
        st.lists(
            st.tuples(st.integers(0, ROWS - 1), st.integers(1, 3)),
            min_size=pair_count - near_axis,
            max_size=pair_count - near_axis,
            unique=True,
        )
    )
    pairs = [(CELL * col + draw(jitters), CELL * row + draw(jitters)) for row, col in cells]
    if near_axis:  # a row of its own above the grid: mirror discs 2 * 10**-k from touching
        pairs.append((1.0 + draw(magnitudes), CELL * ROWS))
    heights = [CELL * row + draw(jitters) for row in axis_rows]
    axis = float(draw(st.integers(-50, 50)))
    pts = adv.mirror_configuration(np.asarray(pairs).reshape(-1, 2), heights, axis)
    index = draw(st.integers(0, n - 1))
    angle = draw(st.floats(-math.pi / 3, math.pi / 3))
    direction = np.array([math.cos(angle), math.sin(angle)])
    # Off the axis: move away from it (never nearer the mirror disc); on the axis: either way.
    if pts[index, 0] < axis or (pts[index, 0] == axis and draw(st.booleans())):
        direction[0] = -direction[0]
    pts[index] += draw(magnitudes) * direction
    return pts


@st.composite
def _chains(draw: st.DrawFn) -> Points:
    """A chain whose links point within 50 degrees of one heading: only neighbours can touch."""
    n = draw(st.integers(3, N_MAX))
    heading = draw(st.floats(0.0, 2.0 * math.pi))
    pts = np.zeros((n, 2))
    for k in range(1, n):
        turn = draw(st.floats(-5.0 * math.pi / 18.0, 5.0 * math.pi / 18.0))
        link = draw(_contact_distances())
        pts[k] = pts[k - 1] + link * np.array([math.cos(heading + turn), math.sin(heading + turn)])
    return pts


@st.composite
def _hex_clusters(draw: st.DrawFn) -> Points:
    """Distinct cells of a 4 x 4 hexagonal patch at spacing 2 +- 10**-k (or exactly 2)."""
    n = draw(st.integers(3, N_MAX))
    cells = np.asarray(
        draw(
            st.lists(
                st.tuples(st.integers(0, 3), st.integers(0, 3)), min_size=n, max_size=n, unique=True
            )
        ),
        dtype=np.float64,
    )
    spacing = draw(_contact_distances())
    unit = np.column_stack(
        [cells[:, 0] + 0.5 * np.mod(cells[:, 1], 2.0), cells[:, 1] * 0.5 * math.sqrt(3.0)]
    )
    return spacing * unit + float(draw(st.integers(-20, 20)))


def near_touching_starts() -> st.SearchStrategy[Points]:
    """Chains and hexagonal clusters whose neighbours are 2, 2 + 10**-k or 2 - 10**-k apart."""
    return st.one_of(_chains(), _hex_clusters())


@st.composite
def lattice_starts(draw: st.DrawFn) -> Points:
    """Cells of a square, Pythagorean-rotated or hexagonal touching lattice written to 3..7
    decimals, maybe with one robot nudged by 10**-k (any robot when k >= 8, else an outer one)."""
    n = draw(st.integers(3, N_MAX))
    kind = draw(st.sampled_from(adv.LATTICES))
    decimals = draw(st.integers(3, 7))
    cells = draw(
        st.lists(
            st.tuples(st.integers(-3, 3), st.integers(-3, 3)), min_size=n, max_size=n, unique=True
        )
    )
    origin = (draw(st.integers(-2000, 2000)) / 100.0, draw(st.integers(-2000, 2000)) / 100.0)
    # a step written to fewer decimals than it has is no longer 2 long: the discs would overlap
    step = draw(
        st.sampled_from(
            [k for k in range(1, len(adv.PYTHAGOREAN_STEPS)) if adv.STEP_PLACES[k] <= decimals]
        )
    )
    pts = adv.lattice_points(kind, cells, decimals, origin, step)
    if draw(st.booleans()):
        k = draw(exponents)
        angle = draw(st.floats(0.0, 2.0 * math.pi))
        direction = np.array([math.cos(angle), math.sin(angle)])
        if k >= SQUEEZE_MIN_EXPONENT:  # 10**-8 toward a touching neighbour is still touching
            pts[draw(st.integers(0, n - 1))] += 10.0**-k * direction
        else:
            pts = adv.nudge_extreme(pts, direction, 10.0**-k)
    return pts


@st.composite
def rim_starts(draw: st.DrawFn) -> Points:
    """3..30 robots on a circle of perimeter 1.5..4 x 2n (zero gap weights: touching), in an
    annulus of width 10**-k, or on a regular polygon with vertices jittered by 10**-k."""
    n = draw(st.integers(3, RIM_N_MAX))
    radius = draw(st.floats(*adv.RIM_PERIMETER)) * 2.0 * n / (2.0 * math.pi)
    center = (draw(st.floats(-10.0, 10.0)), draw(st.floats(-10.0, 10.0)))
    phase = draw(st.floats(0.0, 2.0 * math.pi))
    shape = draw(st.sampled_from(("circle", "annulus", "polygon")))
    if shape == "polygon":
        pts = adv.regular_polygon(n, 2.0 * radius * math.sin(math.pi / n), phase, center)
        angles = np.asarray(draw(st.lists(st.floats(0.0, 2.0 * math.pi), min_size=n, max_size=n)))
        jitter: NDArray[np.float64] = draw(magnitudes) * np.column_stack(
            [np.cos(angles), np.sin(angles)]
        )
        return pts + jitter
    weights = np.asarray(draw(st.lists(st.floats(0.0, 1.0), min_size=n, max_size=n)))
    if weights.sum() <= 0.0:
        weights[0] = 1.0
    radial = None
    if shape == "annulus":
        width = draw(magnitudes) * radius
        radial = width * np.asarray(draw(st.lists(st.floats(-1.0, 1.0), min_size=n, max_size=n)))
    return adv.rim_points(center, radius, weights, phase, radial)


@st.composite
def tied_symmetric_starts(draw: st.DrawFn) -> Points:
    """Exactly symmetric starts (n in 7..12) with an exact tie for a target of the SEC: a robot on
    the axis and a side robot at equal height and distance, or two mirror pairs at equal distance.
    The tie's structure is drawn here; a numpy seed places the other robots."""
    n = draw(st.integers(adv.TIE_MIN_N, N_MAX))
    tie = draw(st.sampled_from(adv.TIES))
    robot_at_o = draw(st.booleans())
    factor = draw(st.floats(1.02, 1.3))
    seed = draw(st.integers(0, 2**32 - 1))
    made = adv.tied_symmetric(np.random.default_rng(seed), tie, n, robot_at_o, factor)
    assume(made is not None)
    assert made is not None
    pairs, heights = made
    lift = float(draw(st.integers(-30, 30)))
    pairs = pairs + np.array([0.0, lift])
    return adv.mirror_configuration(pairs, heights + lift, float(draw(st.integers(-50, 50))))


@st.composite
def offset_starts(draw: st.DrawFn) -> Points:
    """Any other adversarial start translated exactly by 1e5..1e6 (either sign) in x and y."""
    base = draw(
        st.one_of(
            near_symmetric_starts(),
            near_touching_starts(),
            lattice_starts(),
            rim_starts(),
            tied_symmetric_starts(),
        )
    )
    offset = [
        draw(st.floats(*adv.OFFSET_RANGE)) * draw(st.sampled_from((-1.0, 1.0))) for _ in range(2)
    ]
    return adv.translate_exactly(base, offset)


def any_adversarial_start() -> st.SearchStrategy[Points]:
    """One start from any of the strategies above."""
    return st.one_of(
        near_symmetric_starts(),
        near_touching_starts(),
        lattice_starts(),
        offset_starts(),
        rim_starts(),
        tied_symmetric_starts(),
    )


__all__ = [
    "any_adversarial_start",
    "lattice_starts",
    "near_symmetric_starts",
    "near_touching_starts",
    "offset_starts",
    "rim_starts",
    "tied_symmetric_starts",
]
