"""The books' fast paths give every bit their general paths give: a round's lengths as arrays
(`LineMoves.lengths`) are `path_length`'s of each Line; the core books physics' lengths of every
mover as it books them measured; `configuration_changed`'s bound answers as the largest shift;
min_gap over each pair as complex numbers, and kept from round to round from KEPT_FROM robots,
is min_gap's of each round as it was measured; a run's figures folded with the positions compared
as bytes are those of every round measured anew."""

from __future__ import annotations

import math
import struct
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.domain.figures import (
    KEPT_FROM,
    PAIRWISE_UP_TO,
    FigureValue,
    RunFolder,
    _closest,
    _GapMemo,
    derived_figures,
    min_gap,
    round_value,
    summarise,
)
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Line, Path, path_length
from fatswarm.world.core import WorldCore
from fatswarm.world.journal import load_configured
from fatswarm.world.model import RoundBooking
from fatswarm.world.progress import MOVE_TOLERANCE, ProgressTracker, configuration_changed
from fatswarm.world.record import LineMoves
from fatswarm.world.setup import WorldSetup

SETTINGS = settings(max_examples=150, deadline=None)
ODD = (-0.0, 0.0, 1e-300, -1e-300, 5e-324, 1e16, -1e16, 1e308, -1e308, 3.0, -7.0, 2.0**60)
FLOATS = st.one_of(st.sampled_from(ODD), st.floats(allow_nan=False, allow_infinity=False))
ANY_FLOATS = st.one_of(FLOATS, st.sampled_from([math.nan, math.inf, -math.inf]))


def bits(values: Any) -> list[int]:
    """Each float's bits (NaN's sign and payload too)."""
    return [struct.unpack("<q", struct.pack("<d", v))[0] for v in values]


@SETTINGS
@given(st.data())
def test_line_lengths_are_path_length_of_each_line(data: st.DataObject) -> None:
    n = data.draw(st.integers(1, 6))
    movers = sorted(data.draw(st.lists(st.integers(0, n - 1), unique=True, max_size=n)))
    before = np.array(
        data.draw(st.lists(st.tuples(ANY_FLOATS, ANY_FLOATS), min_size=n, max_size=n))
    )
    ends = np.array([[data.draw(ANY_FLOATS), data.draw(ANY_FLOATS)] for _ in movers]).reshape(-1, 2)
    lines = LineMoves(np.array(movers, dtype=np.intp), ends, np.zeros(len(movers)))
    expected = [
        path_length((float(before[r, 0]), float(before[r, 1])), Path((Line((float(x), float(y))),)))
        for r, (x, y) in zip(movers, ends, strict=True)
    ]
    got = lines.lengths(before)
    assert [type(k) for k in got] == [float] * len(movers)
    assert bits(got) == bits(expected)


def _core() -> WorldCore:
    start = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0], [10.0, 10.0]])
    setup = WorldSetup("t", 4, 1, "ssync", start, 50, params={"a": 4.0})
    return WorldCore(setup, load_configured(setup))


@pytest.mark.parametrize("order", ["movers'", "reversed"])
def test_physics_lengths_of_every_mover_are_booked_as_the_paths_books_them(order: str) -> None:
    """Physics measured every mover (a mapping, in any order): its lengths are the books', as
    the Paths' booking of the same round keeps them; nothing is measured again."""
    by_paths, by_arrays = _core(), _core()
    before = by_paths.positions
    ends = before[[0, 2, 3]] + np.array([[0.1, 0.7], [-0.3, 1e-5], [2.0, 2.0]])
    traveled = np.array([0.5, 1e-5, 1.0])
    lines = LineMoves(np.array([0, 2, 3]), ends, traveled)
    moved = {r: Path((Line(tuple(e)),)) for r, e in zip([0, 2, 3], ends.tolist(), strict=True)}
    lengths = {0: 0.25, 2: 2.5, 3: 7.0}  # (not the lines' own: they are physics' here)
    if order == "reversed":
        lengths = dict(reversed(lengths.items()))
    after = before.copy()
    after[[0, 2, 3]] = ends
    common: dict[str, Any] = {"round": 1, "active": (0, 1, 2, 3), "timed_out": (1,)}
    common |= {"before": before, "after": after, "collisions": (), "lengths": lengths}
    by_paths.account(
        RoundBooking(
            paths=moved, traveled=dict(zip([0, 2, 3], traveled.tolist(), strict=True)), **common
        )
    )
    by_arrays.account(RoundBooking(paths=lines, traveled=None, **common))
    assert by_arrays.last_length == by_paths.last_length == [0.25, 0.0, 2.5, 7.0]
    assert [type(k) for k in by_arrays.last_length] == [float] * 4
    assert by_arrays.tracker.snapshot() == by_paths.tracker.snapshot()


def _changed_as_it_was(before: np.ndarray, after: np.ndarray) -> bool:
    shift = np.hypot(after[:, 0] - before[:, 0], after[:, 1] - before[:, 1])
    return bool(shift.max() > MOVE_TOLERANCE)


# shifts at the tolerance: on it, a bit either side, and the diagonal that crosses it
NEAR_TOLERANCE = (
    0.0,
    MOVE_TOLERANCE,
    np.nextafter(MOVE_TOLERANCE, 0.0),
    np.nextafter(MOVE_TOLERANCE, 1.0),
    MOVE_TOLERANCE / math.sqrt(2.0),
    np.nextafter(MOVE_TOLERANCE / math.sqrt(2.0), 1.0),
    np.nextafter(MOVE_TOLERANCE / math.sqrt(2.0), 0.0),
    7.0710678118654757e-10,
    1e-300,
)
SHIFTS = st.one_of(
    st.sampled_from(NEAR_TOLERANCE).flatmap(lambda d: st.sampled_from([d, -d])),
    st.sampled_from([math.nan, math.inf, -math.inf]),
    st.floats(-1e-8, 1e-8),
)


@settings(max_examples=400, deadline=None)
@given(st.data())
def test_configuration_changed_is_whether_the_largest_shift_is_above_the_tolerance(
    data: st.DataObject,
) -> None:
    n = data.draw(st.integers(1, 5))
    before = np.array(data.draw(st.lists(st.tuples(FLOATS, FLOATS), min_size=n, max_size=n)))
    shifts = np.array(data.draw(st.lists(st.tuples(SHIFTS, SHIFTS), min_size=n, max_size=n)))
    with np.errstate(over="ignore", invalid="ignore"):
        after = before + shifts
        assert configuration_changed(before, after) == _changed_as_it_was(before, after)


def test_numpys_hypot_is_never_below_either_side() -> None:
    """What `configuration_changed`'s bound rests on: hypot(a, b) >= |a| and >= |b|, here over
    a million pairs of every scale, at and around the tolerance, and with zeros."""
    rng = np.random.default_rng(30)
    k = 1_000_000
    a = rng.standard_normal(k) * 10.0 ** rng.integers(-320, 300, k)
    b = rng.standard_normal(k) * 10.0 ** rng.integers(-320, 300, k)
    b[: k // 4] = a[: k // 4] * rng.uniform(0.0, 1e-8, k // 4)  # one side far the smaller
    a[k // 4 : k // 2] = MOVE_TOLERANCE * rng.uniform(0.5, 1.5, k // 4)
    b[k // 4 : k // 2] = MOVE_TOLERANCE * rng.uniform(0.0, 1.0, k // 4)
    b[-1000:] = 0.0
    with np.errstate(over="ignore", invalid="ignore"):
        h = np.hypot(a, b)
    assert bool((h >= np.abs(a)).all()) and bool((h >= np.abs(b)).all())


def _closest_as_it_was(pts: np.ndarray) -> tuple[float, int, int]:
    """_closest up to PAIRWISE_UP_TO robots as it was: each coordinate gathered apart."""
    first, second = np.triu_indices(len(pts), 1)
    xs, ys = pts[:, 0], pts[:, 1]
    dx, dy = xs[first] - xs[second], ys[first] - ys[second]
    squares = dx * dx + dy * dy
    k = int(squares.argmin())
    return float(squares[k]), int(first[k]), int(second[k])


@SETTINGS
@given(
    st.integers(2, PAIRWISE_UP_TO).flatmap(
        lambda n: st.lists(st.tuples(ANY_FLOATS, ANY_FLOATS), min_size=n, max_size=n)
    ),
    st.booleans(),
)
def test_every_pair_as_complex_numbers_is_every_pair_apart(points: Any, fortran: bool) -> None:
    """The least square and its pair (the first of the least, in the pairs' order), NaN too."""
    pts = np.array(points, dtype=np.float64)
    if fortran:
        pts = np.asfortranarray(pts)
    with np.errstate(over="ignore", invalid="ignore"):
        got, expected = _closest(pts), _closest_as_it_was(pts)
    assert bits([got[0]]) == bits([expected[0]]) and got[1:] == expected[1:]


STEPS = st.sampled_from([1e-4, 0.01, 0.05, 0.3, 3.0])


@settings(max_examples=120, deadline=None)
@given(st.data(), st.sampled_from([KEPT_FROM, 64, PAIRWISE_UP_TO]))
def test_min_gap_kept_round_to_round_from_kept_from_robots_is_min_gap_of_each(
    data: st.DataObject, n: int
) -> None:
    """Every robot moving a little (the near pairs answer) or far (they do not, and wait), some
    onto others, a round with a NaN or an infinity: each round's value is min_gap's, to the bit."""
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    pts = rng.uniform(-2.0 * n, 2.0 * n, (n, 2)) + data.draw(st.sampled_from([0.0, 1e5]))
    memo = _GapMemo()
    for _ in range(data.draw(st.integers(1, 30))):
        how = data.draw(st.sampled_from(["all", "all", "all", "some", "onto", "odd"]))
        pts = pts.copy()
        if how == "all":
            pts += rng.normal(size=(n, 2)) * data.draw(STEPS)
        elif how == "some":
            movers = rng.choice(n, size=data.draw(st.integers(0, n)), replace=False)
            pts[movers] += rng.normal(size=(len(movers), 2)) * data.draw(STEPS)
        elif how == "onto":  # a robot onto another, or next to it
            i, j = rng.choice(n, size=2, replace=False)
            pts[i] = pts[j] + data.draw(st.sampled_from([0.0, 1e-300, 2.5, -0.0]))
        else:  # a NaN or an infinity for one round
            odd = pts.copy()
            odd[int(rng.integers(n))] = data.draw(st.sampled_from([math.nan, math.inf]))
            with np.errstate(over="ignore", invalid="ignore"):
                got, expected = memo.min_gap(odd), min_gap(odd)
            assert got is not None and expected is not None
            assert math.isnan(got) == math.isnan(expected)
            assert math.isnan(got) or bits([got]) == bits([expected])
            continue
        got, expected = memo.min_gap(pts), min_gap(pts)
        assert got is not None and expected is not None
        assert bits([got]) == bits([expected])


@SETTINGS
@given(st.data())
def test_a_runs_figures_folded_are_those_of_every_round_measured_anew(
    data: st.DataObject,
) -> None:
    """Rounds that repeat the positions (to the bit, or but a zero's sign), NaN among them, and
    rounds with failures: the folder's values are each round's derived figures summarised."""
    n = data.draw(st.integers(1, 6))
    folder, expected = RunFolder(), dict[str, FigureValue]()
    pts = np.array(data.draw(st.lists(st.tuples(FLOATS, FLOATS), min_size=n, max_size=n)))
    pts = pts.reshape(-1, 2)
    for round_no in range(1, data.draw(st.integers(1, 8)) + 1):
        how = data.draw(st.sampled_from(["same", "zero", "nan", "new"]))
        if how == "zero":
            pts = np.where(pts == 0.0, -pts, pts)
        elif how == "nan" and n:
            pts = pts.copy()
            pts[0, 0] = math.nan
        elif how == "new":
            pts = np.array(data.draw(st.lists(st.tuples(FLOATS, FLOATS), min_size=n, max_size=n)))
            pts = pts.reshape(-1, 2)
        failed = data.draw(st.sampled_from([{}, {"failed": {"1": "ValueError: x"}}]))
        with np.errstate(over="ignore", invalid="ignore"):
            folder.add(pts, round_no, failed)
            for f in derived_figures():
                value = round_value(f, pts, round_no, failed)
                expected[f.name] = summarise(f.summary, expected.get(f.name), value)
        got = folder.snapshot()
        assert got.keys() == expected.keys()
        for name, value in expected.items():
            if isinstance(value, float):
                assert isinstance(got[name], float)
                assert bits([got[name]]) == bits([value]) or math.isnan(value)
            else:
                assert got[name] == value


class _TrackerAsItWas(ProgressTracker):
    """`observe` as it was: each robot made an int, checked by its least and largest, and the
    moves counted one by one."""

    def observe(  # type: ignore[override]
        self,
        active: Any,
        movers: Any,
        before: np.ndarray,
        after: np.ndarray,
        traveled: Any = None,
        collisions: int = 0,
    ) -> Status | None:
        active_set = {int(r) for r in active}
        if any(not 0 <= r < self.n for r in [*active_set, *movers]):
            bad = [r for r in active_set | set(movers) if not 0 <= r < self.n]
            raise ValueError(f"robots {sorted(bad)} are not in 0..{self.n - 1}")
        active_set |= self._crashed
        self._count(active_set, movers, False, traveled, collisions)
        self._derived.add(after, self._rounds, None)
        if _changed_as_it_was(before, after):
            self._seen_since_change, self._wanting_since_change = set(), set()
        else:
            self._seen_since_change |= active_set
            self._wanting_since_change |= set(movers)
            if len(self._seen_since_change) == self.n:
                formed = not self._wanting_since_change and bool(self.goal(after))
                self._status = Status.FORMED if formed else Status.STALLED
        return self._status


ROBOT = st.integers(-1, 4).flatmap(
    lambda r: st.sampled_from([r, np.int64(r), float(r), r + 0.5, bool(r) if r in (0, 1) else r])
)


@settings(max_examples=300, deadline=None)
@given(st.data())
def test_the_tracker_counts_as_it_did_robot_by_robot(data: st.DataObject) -> None:
    """Robots as ints, numpy ints, whole floats, halves, bools, repeated or not of the run (then
    refused with the same words): the snapshot, status and error are the ones it gave."""
    n = 4
    now, was = ProgressTracker(n, lambda _: True), _TrackerAsItWas(n, lambda _: True)
    pts = np.zeros((n, 2))
    for _ in range(data.draw(st.integers(1, 6))):
        everyone = data.draw(st.booleans())
        active: Any = list(range(n)) if everyone else data.draw(st.lists(ROBOT, max_size=6))
        movers: Any = list(range(n)) if everyone else data.draw(st.lists(ROBOT, max_size=6))
        after = pts + data.draw(st.sampled_from([0.0, 1.0]))
        traveled = [1.0] * len(movers)
        outcomes = []
        for tracker in (now, was):
            try:
                outcomes.append(repr(tracker.observe(active, movers, pts, after, traveled)))
            except (ValueError, TypeError, IndexError) as exc:
                outcomes.append(f"{type(exc).__name__}: {exc}")
        assert outcomes[0] == outcomes[1]
        if "Error" in outcomes[0] or now.done:
            break
        assert now.snapshot() == was.snapshot()
        pts = after
