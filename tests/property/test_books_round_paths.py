"""The books' per-round fast paths give what their general paths give: min_gap of a few robots in
Python floats, `configuration_changed` reading a few shifts in Python, the tracker told that every
robot moved as `range(n)` (and counting such rounds apart), the same active tuple round after round,
the core booking a round where every robot moved on a line, and the folder's summaries and
snapshot."""

from __future__ import annotations

import math
import struct
from typing import Any

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from fatswarm.domain.figures import (
    FEW_UP_TO,
    RunFolder,
    Summary,
    _closest,
    _pair_squares,
    derived_figures,
    summarise,
)
from fatswarm.domain.path import Line, Path
from fatswarm.world.core import WorldCore
from fatswarm.world.journal import load_configured
from fatswarm.world.model import RoundBooking
from fatswarm.world.progress import (
    FEW_SHIFTS,
    MOVE_TOLERANCE,
    ProgressTracker,
    configuration_changed,
)
from fatswarm.world.record import LineMoves
from fatswarm.world.setup import WorldSetup

# Examples: 250 and 200 reach every line and branch of fatswarm that 500 and 400 did (coverage
# --branch of this file's derandomized draws, measured), in three quarters of the time.

ODD = (-0.0, 0.0, 1e-300, 5e-324, 1e16, -1e16, 1e308, -1e308, 3.0, -7.0, 2.0**60)
FLOATS = st.one_of(st.sampled_from(ODD), st.floats(allow_nan=False, allow_infinity=False))
ANY_FLOATS = st.one_of(FLOATS, st.sampled_from([math.nan, -math.nan, math.inf, -math.inf]))


def bits(values: Any) -> list[int]:
    """Each float's bits (NaN's sign and payload too)."""
    return [struct.unpack("<q", struct.pack("<d", v))[0] for v in values]


@settings(max_examples=200, deadline=None)
@given(
    st.integers(2, FEW_UP_TO).flatmap(
        lambda n: st.lists(st.tuples(ANY_FLOATS, ANY_FLOATS), min_size=n, max_size=n)
    ),
    st.booleans(),
)
@example([(-0.0, math.nan), (-math.nan, -0.0)], False)  # a NaN whose sign Python's ops flip
def test_min_gap_of_a_few_robots_in_python_floats_is_every_pair_in_numpy(
    points: Any, repeat: bool
) -> None:
    """The least square to the bit (NaN's too) and its pair: the first of the least, or the first
    NaN, in the pairs' order, as numpy's argmin over every pair's square."""
    pts = np.array(points, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        if repeat:  # ties: a pair at the same distance as another
            pts[-1] = pts[0] - (pts[1] - pts[0])
        first, second, squares = _pair_squares(pts)
        got = _closest(pts)
    k = int(squares.argmin())
    assert bits([got[0]]) == bits([float(squares[k])])
    assert got[1:] == (int(first[k]), int(second[k]))


def _changed_by_numpy(before: np.ndarray, after: np.ndarray) -> bool:
    delta = after - before
    if np.abs(delta).max() > MOVE_TOLERANCE:
        return True
    return bool(np.hypot(delta[:, 0], delta[:, 1]).max() > MOVE_TOLERANCE)


HALF = 0.5 * MOVE_TOLERANCE
NEAR = (0.0, HALF, np.nextafter(HALF, 0.0), np.nextafter(HALF, 1.0), MOVE_TOLERANCE)
SHIFTS = st.one_of(
    st.sampled_from(
        (*NEAR, np.nextafter(MOVE_TOLERANCE, 1.0), MOVE_TOLERANCE / math.sqrt(2.0), 1e-4)
    ).flatmap(lambda d: st.sampled_from([d, -d])),
    st.sampled_from([math.nan, math.inf, -math.inf, 1e308]),
    st.floats(-2e-9, 2e-9),
)


@settings(max_examples=250, deadline=None)
@given(st.data())
def test_a_few_shifts_read_in_python_answer_as_numpy(data: st.DataObject) -> None:
    """Up to FEW_SHIFTS robots (and one more, numpy's alone), shifts about half the tolerance and
    the tolerance, NaN, infinities and sums that overflow: the answer numpy's measure gives."""
    n = data.draw(st.integers(1, FEW_SHIFTS + 1))
    before = np.array(data.draw(st.lists(st.tuples(FLOATS, FLOATS), min_size=n, max_size=n)))
    shifts = np.array(data.draw(st.lists(st.tuples(SHIFTS, SHIFTS), min_size=n, max_size=n)))
    with np.errstate(over="ignore", invalid="ignore"):
        after = before + shifts
        assert configuration_changed(before, after) == _changed_by_numpy(before, after)


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_every_robot_moved_told_as_a_range_counts_as_the_list_of_every_robot(
    data: st.DataObject,
) -> None:
    """Rounds where every robot moved (told as range(n), or listed), others where some did, the
    same active tuple given again or a new one, crashes: the same snapshots and statuses."""
    n = data.draw(st.integers(1, 5))
    fast, listed = ProgressTracker(n, lambda _: False, 40), ProgressTracker(n, lambda _: False, 40)
    pts = np.zeros((n, 2))
    every = tuple(range(n))
    for _ in range(data.draw(st.integers(1, 12))):
        how = data.draw(st.sampled_from(["every", "every", "some", "crash", "stay"]))
        if how == "crash":
            robots = data.draw(st.lists(st.integers(0, n - 1), max_size=2))
            fast.crash(robots)
            listed.crash(robots)
        some = sorted(data.draw(st.sets(st.integers(0, n - 1))))
        active = every if data.draw(st.booleans()) else tuple(some)
        after = pts + (0.0 if how == "stay" else data.draw(st.sampled_from([0.0, 1.0])))
        moved_all = how == "every"
        movers = range(n) if moved_all else some
        traveled = [0.5] * (n if moved_all else len(some))
        for tracker, moving in ((fast, movers), (listed, list(movers))):
            tracker.observe(active, moving, pts, after, traveled)
        assert fast.snapshot() == listed.snapshot()
        assert fast.status == listed.status
        if fast.done:
            break
        pts = after


def _core(n: int) -> WorldCore:
    start = np.array([[10.0 * i, 0.0] for i in range(n)])
    setup = WorldSetup("t", n, 1, "fsync", start, 50, params={"a": 4.0})
    return WorldCore(setup, load_configured(setup))


@pytest.mark.parametrize("measured", ["array", "mapping", "none"])
def test_a_round_where_every_robot_moved_on_a_line_books_as_its_paths(measured: str) -> None:
    """Every robot active and moving (LineMoves of 0..n-1): the agents' books, the movers and the
    figures are those of the same round booked as Paths."""
    n = 4
    by_paths, by_arrays = _core(n), _core(n)
    before = by_paths.positions
    ends = before + np.array([[0.1, 0.7], [-0.3, 1e-5], [2.0, 2.0], [0.0, -0.25]])
    traveled = np.array([0.5, 1e-5, 1.0, 0.25])
    robots = list(range(n))
    lines = LineMoves(np.arange(n), ends, traveled)
    moved = {r: Path((Line(tuple(e)),)) for r, e in zip(robots, ends.tolist(), strict=True)}
    lengths: Any = {
        "array": np.array([0.25, 2.5, 7.0, 0.5]),
        "mapping": {3: 0.5, 0: 0.25, 2: 7.0, 1: 2.5},
        "none": None,
    }[measured]
    after = ends.copy()
    common: dict[str, Any] = {"round": 1, "active": tuple(robots), "timed_out": ()}
    common |= {"before": before, "after": after, "collisions": ()}
    by_paths.account(
        RoundBooking(
            paths=moved,
            traveled=dict(zip(robots, traveled.tolist(), strict=True)),
            lengths=dict(enumerate(lengths.tolist())) if measured == "array" else lengths,
            **common,
        )
    )
    by_arrays.account(RoundBooking(paths=lines, traveled=None, lengths=lengths, **common))
    assert lines.every(n) and not LineMoves(np.arange(1, n), ends[1:], traveled[1:]).every(n)
    assert by_arrays.last_length == by_paths.last_length
    assert [type(k) for k in by_arrays.last_length] == [float] * n
    assert by_arrays.last_active == by_paths.last_active == [1] * n
    assert by_arrays.moved == by_paths.moved == tuple(robots)
    assert by_arrays.tracker.snapshot() == by_paths.tracker.snapshot()


NUMBERS = st.one_of(st.integers(-5, 5), FLOATS, st.sampled_from([math.nan, -0.0, 0.0]))


@settings(max_examples=300, deadline=None)
@given(NUMBERS, NUMBERS)
def test_the_least_and_largest_so_far_are_min_and_max_of_the_two(so_far: Any, value: Any) -> None:
    """NaN either side, a zero's sign, an int beside a float: the very object min and max give."""
    assert summarise(Summary.MIN, so_far, value) is min(so_far, value)
    assert summarise(Summary.MAX, so_far, value) is max(so_far, value)


def test_a_folders_snapshot_has_every_derived_figure_in_order_whatever_it_started_from() -> None:
    names = [f.name for f in derived_figures()]
    for start in ({}, dict(reversed([(name, None) for name in names])), {names[0]: 1.5}):
        folder = RunFolder(start)
        assert list(folder.snapshot()) == names
        folder.add(np.array([[0.0, 0.0], [3.0, 4.0]]), 1, {})
        assert list(folder.snapshot()) == names
        assert folder.snapshot()["min_gap"] == (1.5 if start.get("min_gap") == 1.5 else 3.0)
