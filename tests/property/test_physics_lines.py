"""A round of straight lines as arrays (`apply_lines`) gives apply_round's every bit and error, and
apply_round's path for single Lines gives what its general path (segment by segment) gives."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.domain.path import Line, Path
from fatswarm.domain.tolerance import GRID, snap
from fatswarm.world.physics import (
    NEAR_BRUTE,
    NEAR_REACH,
    InvalidRoundError,
    RoundOutcome,
    _boxes_close,
    _near_pairs,
    _nearest_corners,
    _rows,
    apply_lines,
    apply_round,
)

CORNERS = np.array([[0, 0], [0, 1], [1, 0], [1, 1]], dtype=np.float64)  # _snap_one's order
STEPS = (0.0, 1e-9, 1e-4, 0.3, 1.0, 2.5, 6.0)  # lengths of moves: none, tiny, small, contacts


def bits(run: Any) -> str:
    """Every bit of an outcome (or the error raised) as text."""
    try:
        out: RoundOutcome = run()
    except Exception as exc:  # the error itself is compared: type and message
        return f"raise {type(exc).__name__}: {exc}"
    rows = [f"{out.positions.dtype} {out.positions.shape} {out.positions.tobytes().hex()}"]
    for name in ("traveled", "lengths"):
        d = getattr(out, name)
        rows.append(name + " ".join(f" {k!r}={type(v).__name__}:{v.hex()}" for k, v in d.items()))
    rows += [f"{c.robot!r} {c.other!r} {c.t.hex()} {c.point[0].hex()} {c.point[1].hex()}"
             for c in out.collisions]  # fmt: skip
    return "\n".join(rows)


@st.composite
def line_rounds(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
    """Robots on distinct cells of a grid of pitch 2.2 (touching possible after jitter, overlap
    not), maybe far from the origin; some of them move in a straight line of a drawn length,
    some to a half-grid point; point robots or discs."""
    side = draw(st.integers(1, 7))
    cells = draw(st.lists(st.integers(0, side * side - 1), min_size=1, max_size=40, unique=True))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    grid = np.array([[c % side, c // side] for c in cells], dtype=np.float64) * 2.2
    offset = draw(st.sampled_from([0.0, 1e3, 3e5 - 0.5]))
    start = snap(grid + rng.uniform(-0.1, 0.1, grid.shape) + offset)
    n = len(start)
    movers = np.flatnonzero(rng.random(n) < draw(st.floats(0.1, 1.0)))
    lengths = rng.choice(STEPS, size=len(movers)) * rng.uniform(0.5, 1.5, len(movers))
    angle = rng.uniform(0.0, 2.0 * np.pi, len(movers))
    ends = start[movers] + np.column_stack([np.cos(angle), np.sin(angle)]) * lengths[:, None]
    if draw(st.booleans()):  # some ends halfway between grid points: ties of the snap
        half = rng.random(len(movers)) < 0.5
        ends[half] = snap(ends[half]) + GRID / 2.0
    return start, movers.astype(np.intp), ends, draw(st.booleans())


def as_paths(movers: np.ndarray, ends: np.ndarray, kind: type = float) -> Mapping[int, Path]:
    return {
        int(r): Path((Line((kind(x), kind(y))),))
        for r, (x, y) in zip(movers.tolist(), ends.tolist(), strict=True)
    }


@settings(max_examples=300, deadline=None)
@given(line_rounds())
def test_apply_lines_gives_apply_rounds_bits(case: tuple[Any, ...]) -> None:
    start, movers, ends, points = case
    by_paths = bits(lambda: apply_round(start, as_paths(movers, ends), points=points))
    assert bits(lambda: apply_lines(start, movers, ends, points=points)) == by_paths


@settings(max_examples=300, deadline=None)
@given(line_rounds())
def test_single_lines_give_the_general_paths_bits(case: tuple[Any, ...]) -> None:
    """Ends as numpy floats take apply_round's general path (segment tables), the same values."""
    start, movers, ends, points = case
    general = bits(lambda: apply_round(start, as_paths(movers, ends, np.float64), points=points))
    assert bits(lambda: apply_round(start, as_paths(movers, ends), points=points)) == general


@pytest.mark.parametrize(
    ("movers", "ends"),
    [
        ([0, 3], [[1.0, 0.0], [2.0, 0.0]]),  # robot 3 does not exist
        ([-1, 0], [[1.0, 0.0], [2.0, 0.0]]),
        ([0, 1], [[np.nan, 0.0], [2.0, 0.0]]),
        ([0, 1], [[1.0, 0.0], [np.inf, 0.0]]),
        ([0, 1], [[1.7e308, 1.7e308], [2.0, 0.0]]),  # too long to simulate
        ([0], [[1.5, 0.0]]),  # pushes robot 0 into robot 1, which stays: a contact
    ],
)
def test_apply_lines_raises_what_apply_round_raises(movers: list[int], ends: list[Any]) -> None:
    start = np.array([[0.0, 0.0], [2.5, 0.0], [0.0, 5.0]])
    m, e = np.array(movers), np.array(ends, dtype=np.float64)
    assert bits(lambda: apply_lines(start, m, e)) == bits(
        lambda: apply_round(start, as_paths(m, e))
    )


def test_apply_lines_refuses_movers_out_of_order_or_mismatched() -> None:
    start = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 4.0]])
    with pytest.raises(InvalidRoundError, match="increasing order"):
        apply_lines(start, np.array([1, 0]), np.zeros((2, 2)))
    with pytest.raises(InvalidRoundError, match="increasing order"):
        apply_lines(start, np.array([1, 1]), np.zeros((2, 2)))
    with pytest.raises(InvalidRoundError, match=r"\(m, 2\)"):
        apply_lines(start, np.array([0, 1]), np.zeros((3, 2)))
    with pytest.raises(InvalidRoundError, match="int array"):
        apply_lines(start, np.array([0.0, 1.0]), np.zeros((2, 2)))


def test_apply_lines_without_movers_moves_nobody() -> None:
    start = np.array([[0.0, 0.0], [4.0, 0.0]])
    out = apply_lines(start, np.zeros(0, dtype=np.intp), np.zeros((0, 2)))
    assert out.positions.tobytes() == start.tobytes() and out.traveled == {}


@pytest.mark.parametrize(
    ("movers", "steps"),
    [
        ([0, 1, 2], [[1e-4, 0.0], [0.0, 1e-4], [0.5, 0.5]]),  # everyone, nobody near
        ([0, 1, 2], [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]),  # everyone, nobody moves
        ([0, 1, 2], [[0.0, 0.0], [1e-4, 0.0], [0.0, 0.0]]),  # everyone, one moves
        ([1], [[0.3, 0.0]]),  # some
        ([0, 1, 2], [[2.0, 0.0], [-2.0, 0.0], [0.0, -1.0]]),  # contacts
        ([], []),  # nobody
    ],
)
@pytest.mark.parametrize("points", [False, True])
def test_apply_lines_neither_writes_nor_returns_the_given_positions(
    movers: list[int], steps: list[list[float]], points: bool
) -> None:
    """apply_lines reads the caller's positions without a copy: the outcome is a new array."""
    start = np.array([[0.0, 0.0], [2.5, 0.0], [0.0, 5.0]])
    kept = start.copy()
    ids = np.array(movers, dtype=np.intp)
    ends = start[ids] + np.array(steps, dtype=np.float64).reshape(-1, 2)
    out = apply_lines(start, ids, ends, points=points)
    assert not np.shares_memory(out.positions, start)
    assert start.tobytes() == kept.tobytes()


@settings(max_examples=80, deadline=None)
@given(st.integers(1, 40), st.integers(0, 2**32 - 1), st.floats(0.1, 1.0))
def test_near_pairs_are_the_pairs_boxes_close_finds(n: int, seed: int, share: float) -> None:
    """The gathered near-pair test (every pair, or a sort's window) finds the very (mover, robot)
    pairs `_boxes_close` finds among all of them, in the brute force's order when it says so."""
    rng = np.random.default_rng(seed)
    movers = np.flatnonzero(rng.random(n) < share)
    if not len(movers):
        movers = np.array([0], dtype=np.intp)
    lo = rng.uniform(-3.0, 3.0, (n, 2)) * np.sqrt(n)
    boxes = np.stack((lo, lo))
    boxes[1, movers] += rng.uniform(0.0, 1.5, (len(movers), 2))
    pi, pj = movers.repeat(n), np.tile(np.arange(n), len(movers))
    close = _boxes_close(_rows(boxes), pi, pj, NEAR_REACH) & (pi != pj)
    found = _near_pairs(boxes, movers, len(movers) == n)
    if not close.any():
        assert found is None
        return
    assert found is not None
    si, sj, brute = found
    assert brute == (len(movers) * n <= NEAR_BRUTE)
    if brute:
        assert si.tolist() == pi[close].tolist() and sj.tolist() == pj[close].tolist()
    else:
        got = zip(si.tolist(), sj.tolist(), strict=True)
        assert sorted(got) == sorted(zip(pi[close].tolist(), pj[close].tolist(), strict=True))


def _first_corners(p: np.ndarray) -> np.ndarray:
    """Each point's nearest grid corner as `_snap_one` picks it: the first of the four by
    distance (a stable sort: ties to the first)."""
    expected = []
    for x, y in p.tolist():
        corners = np.floor(np.array([x, y]) / GRID) * GRID + CORNERS * GRID
        order = np.argsort(np.hypot(corners[:, 0] - x, corners[:, 1] - y), kind="stable")
        expected.append(corners[order[0]] + 0.0)
    return np.array(expected)


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 80), st.integers(0, 2**32 - 1))
def test_nearest_corners_are_the_snaps_nearest_corners(m: int, seed: int) -> None:
    """`_nearest_corners` (each coordinate alone, or by distances near 0) picks `_snap_one`'s
    first corner, ties (half-grid points) and points near 0 included."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(-1e3, 1e3, (m, 2))
    p[: m // 3] = snap(p[: m // 3]) + GRID / 2.0
    p[m // 3 : m // 2] = rng.uniform(-3 * GRID, 3 * GRID, (m // 2 - m // 3, 2))
    assert _nearest_corners(p).tobytes() == _first_corners(p).tobytes()


@settings(max_examples=60, deadline=None)
@given(st.integers(-20, 23), st.integers(-3, 3), st.integers(0, 2**32 - 1))
def test_nearest_corners_of_points_within_ulps_of_a_half_grid_point(
    exponent: int, ulps: int, seed: int
) -> None:
    """Points a few ulps off the middle between grid points, at every magnitude of the range where
    each coordinate is rounded alone and just outside it, pick `_snap_one`'s first corner."""
    rng = np.random.default_rng(seed)
    size = 2.0**exponent * rng.uniform(1.0, 2.0, 40) * rng.choice([-1.0, 1.0], 40)
    x = np.floor(size / GRID) * GRID + GRID / 2.0
    for _ in range(abs(ulps)):
        x = np.nextafter(x, np.inf if ulps > 0 else -np.inf)
    y = np.where(rng.random(40) < 0.5, x[::-1], np.floor(size / GRID) * GRID)
    p = np.column_stack([x, y]) if seed % 2 else np.column_stack([y, x])
    assert _nearest_corners(p).tobytes() == _first_corners(p).tobytes()
