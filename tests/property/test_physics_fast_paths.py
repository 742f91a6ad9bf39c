"""The physics' fast paths give what the brute force they replaced gives, bit for bit and in the
same order: candidate pairs by sort and sweep, and the snap of movers far from everyone at once."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.domain.path import Arc, Line, Path, PathFormatError
from fatswarm.domain.tolerance import CONTACT, GRID
from fatswarm.world import motion, physics
from fatswarm.world.motion import IntArray, Motion, build_motion
from fatswarm.world.physics import BOX_MARGIN, BRUTE_PAIRS, SNAP_FEW, _candidate_pairs, _snap_movers

# Examples: 150 reach every line and branch of fatswarm that 300 did (coverage --branch of this
# file's derandomized draws, measured), in half the time.

_CORNERS = np.array([[0, 0], [0, 1], [1, 0], [1, 1]], dtype=np.float64)


def brute_pairs(mo: Motion, first: IntArray, second: IntArray) -> tuple[IntArray, IntArray]:
    """The candidate pairs as physics made them before the sweep (every pair of first x second)."""
    pi = np.repeat(first, len(second))
    pj = np.tile(second, len(first))
    boxes = np.concatenate([mo.start, mo.start], axis=1)
    boxes[mo.robots] = mo.box
    bi, bj = boxes[pi], boxes[pj]
    gx = np.maximum(0.0, np.maximum(bj[:, 0] - bi[:, 2], bi[:, 0] - bj[:, 2]))
    gy = np.maximum(0.0, np.maximum(bj[:, 1] - bi[:, 3], bi[:, 1] - bj[:, 3]))
    in_first = np.zeros(len(mo.start), dtype=np.bool_)
    in_first[first] = True
    keep = (gx * gx + gy * gy < (2.0 + BOX_MARGIN) ** 2) & (pi != pj) & ~(in_first[pj] & (pj < pi))
    return pi[keep], pj[keep]


def brute_snap(final: np.ndarray, movers: IntArray) -> None:
    """The snap of movers as physics made it before (each mover against every other robot)."""
    for robot in movers:
        p = final[robot].copy()
        base = np.floor(p / GRID) * GRID
        corners = base + _CORNERS * GRID
        order = np.argsort(np.hypot(corners[:, 0] - p[0], corners[:, 1] - p[1]), kind="stable")
        others = np.delete(final, robot, axis=0)
        before = np.hypot(others[:, 0] - p[0], others[:, 1] - p[1])
        floor = np.minimum(before, CONTACT)
        chosen = corners[order[0]]
        for k in order:
            c = corners[k]
            if (np.hypot(others[:, 0] - c[0], others[:, 1] - c[1]) >= floor).all():
                chosen = c
                break
        final[robot] = chosen + 0.0


@st.composite
def swarms(draw: st.DrawFn) -> tuple[np.ndarray, dict[int, Path], list[int]]:
    """Robots on a jittered grid (some touching, pitch near 2), straight moves for some, and a
    subset of robots in a drawn order."""
    n = draw(st.integers(1, 40))
    cols = draw(st.integers(1, 8))
    pitch = draw(st.sampled_from([2.0, 2.0 + 1e-9, 2.0005, 2.5, 7.0]))
    jitter = st.floats(-1e-3, 1e-3, allow_nan=False)
    start = np.array(
        [[pitch * (i % cols) + draw(jitter), pitch * (i // cols) + draw(jitter)] for i in range(n)]
    )
    step = st.floats(-3.0, 3.0, allow_nan=False)
    paths = {
        i: Path((Line((float(start[i, 0]) + draw(step), float(start[i, 1]) + draw(step))),))
        for i in range(n)
        if draw(st.booleans())
    }
    order = draw(st.permutations(range(n)))
    subset = order[: draw(st.integers(0, n))]
    return start, paths, subset


@contextmanager
def pairs_limit(limit: int) -> Iterator[None]:
    """physics.BRUTE_PAIRS set to `limit` (0: always the sort and sweep, and the snap of movers in
    bulk) for a while."""
    physics.BRUTE_PAIRS, physics.SNAP_FEW = limit, limit and SNAP_FEW
    try:
        yield
    finally:
        physics.BRUTE_PAIRS, physics.SNAP_FEW = BRUTE_PAIRS, SNAP_FEW


LIMITS = pytest.mark.parametrize("limit", [0, BRUTE_PAIRS], ids=["sweep", "every-pair"])


@LIMITS
@settings(max_examples=150, deadline=None)
@given(case=swarms())
def test_candidate_pairs_are_the_brute_force_ones_in_its_order(
    limit: int, case: tuple[np.ndarray, dict[int, Path], list[int]]
) -> None:
    start, paths, subset = case
    mo = build_motion(start, sorted(paths.items()))
    second = np.arange(len(start), dtype=np.intp)
    for first, other in ((mo.robots, second), (np.array(subset[:2], dtype=np.intp), mo.robots)):
        with pairs_limit(limit):
            got = _candidate_pairs(mo, first, other)
        want = brute_pairs(mo, first, other)
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])


@LIMITS
@settings(max_examples=150, deadline=None)
@given(case=swarms(), nudge=st.floats(-2e-9, 2e-9, allow_nan=False))
def test_snap_is_the_brute_force_snap(
    limit: int, case: tuple[np.ndarray, dict[int, Path], list[int]], nudge: float
) -> None:
    start, _, subset = case
    final = start + nudge
    movers = np.array(subset, dtype=np.intp)
    got, want = final.copy(), final.copy()
    with pairs_limit(limit):
        _snap_movers(got, movers)
    brute_snap(want, movers)
    assert got.tobytes() == want.tobytes()


def _same_motion(a: Motion, b: Motion) -> None:
    for name in ("start", "row_of", "robots", "nseg", "seg", "t1", "total", "end", "box", "stop"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.shape == y.shape and x.dtype == y.dtype, name
        assert x.tobytes() == y.tobytes(), name  # the same bits, -0.0 and inf included


_coord = st.floats(-1e6, 1e6, allow_nan=False) | st.sampled_from([0.0, -0.0, 1e-300, 2.0])


@given(
    start=st.lists(st.tuples(_coord, _coord), min_size=1, max_size=12),
    ends=st.lists(st.one_of(st.none(), st.tuples(_coord, _coord)), max_size=12),
    shift=st.one_of(st.none(), st.tuples(_coord, _coord)),
)
def test_motion_of_single_lines_is_the_segment_tables(
    start: list[tuple[float, float]],
    ends: list[tuple[float, float] | None],
    shift: tuple[float, float] | None,
) -> None:
    """Rounds of one straight segment per mover (zero-length ones, -0.0, shifted frames) are
    tabulated as arrays with the very floats the general segment loop gives."""
    points = np.array(start, dtype=np.float64)
    moves = [  # a move to where the robot is (None) is a zero-length line
        (robot, Path((Line(end if end is not None else tuple(points[robot].tolist())),)))
        for robot, end in enumerate(ends[: len(start)])
    ]
    fast = motion._single_lines(points, moves, shift)
    assert fast is not None
    _same_motion(fast, motion._tabulated(points, moves, shift))
    _same_motion(build_motion(points, moves, shift), fast)


def test_motion_declines_what_is_not_single_lines() -> None:
    """Arcs, several segments or non-float coordinates go the general way."""
    start = np.zeros((2, 2))
    for path in (
        Path((Arc((1.0, 0.0), 0.5),)),
        Path((Line((1.0, 0.0)), Line((2.0, 0.0)))),
        Path((Line((1, 0.0)),)),
    ):
        assert motion._single_lines(start, [(0, path)], None) is None


def test_motion_refuses_a_line_too_long_to_simulate_by_its_robot() -> None:
    with pytest.raises(PathFormatError, match="robot 1: the path is too long"):
        build_motion(
            np.zeros((2, 2)),
            [(0, Path((Line((1.0, 0.0)),))), (1, Path((Line((1.7e308, 1.7e308)),)))],
        )
