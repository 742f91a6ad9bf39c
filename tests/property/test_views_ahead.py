"""A round's views built at once (`Looks.prepare`) are the very arrays each Look builds alone."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.agent.uniform_circle import ALGORITHM
from fatswarm.domain import draws
from fatswarm.domain.draws import LOOK_STREAM, _mix64, view_order, view_orders
from fatswarm.domain.robot_model import PAPER_MODEL, FrameChange, Frames, RobotModel
from fatswarm.domain.seam import Configured
from fatswarm.world.looks import Looks

MODELS = (
    PAPER_MODEL,
    RobotModel(frames=Frames.DISORIENTED, frame_change=FrameChange.EVERY_LOOK),
    RobotModel(frames=Frames.CHIRALITY),
)


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**64 - 1), st.integers(1, 10**6), st.integers(1, 40), st.data())
def test_view_orders_rows_are_view_order(
    seed: int, round_no: int, n: int, data: st.DataObject
) -> None:
    robots = data.draw(st.lists(st.integers(0, 10**4), max_size=5))
    rows = view_orders(seed, round_no, robots, n)
    assert rows.shape == (len(robots), n)
    for row, robot in zip(rows, robots, strict=True):
        assert np.array_equal(row, view_order(seed, round_no, robot, n))


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**64 - 1), st.integers(1, 10**6), st.integers(1, 40), st.data())
def test_view_order_is_the_scalar_splitmix64_hash_order(
    seed: int, round_no: int, k: int, data: st.DataObject
) -> None:
    """The robots' keys hashed at once in uint64 arrays are the Python-int hashes: index i
    hashes as splitmix64 of key + i times its increment."""
    robots = data.draw(st.lists(st.integers(0, 2**20), min_size=1, max_size=5))
    base = _mix64(_mix64(LOOK_STREAM ^ seed) ^ round_no)
    for row, robot in zip(view_orders(seed, round_no, robots, k), robots, strict=True):
        key = _mix64(base ^ robot)
        hashes = [_mix64((key + i * 0x9E3779B97F4A7C15) & (2**64 - 1)) for i in range(k)]
        assert row.tolist() == sorted(range(k), key=hashes.__getitem__)


@settings(max_examples=100, deadline=None)
@given(
    st.integers(2, 30),
    st.integers(0, 2**32),
    st.integers(1, 500),
    st.sampled_from(range(len(MODELS))),
    st.data(),
)
def test_prepared_views_are_the_views_built_alone(
    n: int, seed: int, look_round: int, model: int, data: st.DataObject
) -> None:
    setting = Configured.of(ALGORITHM, n)
    rng = np.random.default_rng(seed)
    positions = np.round(rng.uniform(-50.0, 50.0, (n, 2)), 6)
    robots = data.draw(st.lists(st.integers(0, n - 1), unique=True))
    alone = Looks(MODELS[model], setting, n, seed, False)
    ahead = Looks(MODELS[model], setting, n, seed, False)
    ahead.prepare(positions, look_round, robots)
    for robot in range(n):
        want = alone.view(positions, robot, look_round)[0]
        got = ahead.view(positions, robot, look_round)[0]
        assert got.dtype == want.dtype and got.shape == want.shape
        assert got.tobytes() == want.tobytes()


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**64 - 1), st.integers(1, 10**6), st.integers(70, 130), st.integers(60, 90))
def test_view_orders_of_a_whole_round_are_view_order_of_each_robot(
    seed: int, round_no: int, k: int, m: int
) -> None:
    """From SORT_VALUES hashes on, `view_orders` sorts them as values with the index in their low
    bits: still each robot's own `view_order`, the argsort of its hashes."""
    robots = list(range(3, 3 + m))
    rows = view_orders(seed, round_no, robots, k)
    assert rows.size >= draws.SORT_VALUES and rows.dtype == np.int64
    want = draws._hashes(seed, round_no, robots, k).argsort(axis=1)
    assert np.array_equal(rows, want)
    for row, robot in list(zip(rows, robots, strict=True))[:: m // 5]:
        assert np.array_equal(row, view_order(seed, round_no, robot, k))
    skipped = want + (want >= np.array(robots)[:, None])  # robot robots[i] itself left out
    assert np.array_equal(view_orders(seed, round_no, robots, k, True), skipped)
    small = robots[:3]  # argsorted: under SORT_VALUES
    assert np.array_equal(view_orders(seed, round_no, small, k, True), skipped[:3])


def test_hashes_alike_in_their_high_bits_are_argsorted_as_they_are(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Two hashes of a row that differ only in the bits the index replaces: that row is ordered
    by its hashes whole, not by the indices."""
    rng = np.random.default_rng(4)
    hashes = rng.integers(0, 2**63, size=(70, 64), dtype=np.uint64) * np.uint64(2)
    hashes[5, 40] = hashes[5, 3] + np.uint64(1)  # hash 40 after hash 3, index 40 after 3 too
    hashes[9, 2] = hashes[9, 30] + np.uint64(1)  # hash 2 after hash 30: index 2 would go first
    hashes[9, 7] = hashes[9, 7] | np.uint64(63)  # high bits alone apart
    monkeypatch.setattr(draws, "_hashes", lambda *a: hashes[list(a[2])].copy())
    got = view_orders(1, 2, list(range(70)), 64)
    assert np.array_equal(got, hashes.argsort(axis=1))
    assert got[9].tolist().index(30) < got[9].tolist().index(2)
    skipped = got + (got >= np.arange(70)[:, None])
    assert np.array_equal(view_orders(1, 2, list(range(70)), 64, True), skipped)


@settings(max_examples=60, deadline=None)
@given(
    st.integers(0, 2**64 - 1),
    st.integers(1, 10**6),
    st.sampled_from([1, 2, 7, 40, 90]),
    st.integers(1, 40),
    st.integers(1, 5),
    st.booleans(),
)
def test_view_orders_of_several_rounds_are_each_rounds_own(
    seed: int, round_no: int, k: int, m: int, rounds: int, among_all: bool
) -> None:
    """`rounds` at once (what a lock step draws ahead): round r's rows are that round's own,
    below SORT_VALUES hashes and from it on."""
    robots = list(range(2, 2 + m))
    got = view_orders(seed, round_no, robots, k, among_all, rounds)
    want = [view_orders(seed, round_no + r, robots, k, among_all) for r in range(rounds)]
    assert got.shape == (rounds * m, k) and got.dtype == np.int64
    assert np.array_equal(got, np.concatenate(want))


def test_hashes_alike_from_bit_33_up_are_ordered_by_the_last_step(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Hashes are sorted without splitmix64's last step, x ^ (x >> 31), which leaves bits 33 up
    as they are; where two of a row share those bits and the last step swaps their order, the
    row is still in its whole hashes' order."""
    rng = np.random.default_rng(8)
    before = rng.integers(0, 2**63, size=(70, 64), dtype=np.uint64) * np.uint64(2)
    s31 = np.uint64(31)
    swapped = 0
    for row in (4, 11, 12):  # three rows with two such hashes each
        high = before[row, 5] & ~np.uint64(2**33 - 1)
        while True:
            low = rng.integers(0, 2**33, size=2, dtype=np.uint64)
            pair = high | low
            last = pair ^ (pair >> s31)
            if (pair[0] < pair[1]) != (last[0] < last[1]):
                break
        before[row, 5], before[row, 50] = pair
        swapped += 1

    def hashes(*a: object, last: bool = True, rounds: int = 1) -> np.ndarray:
        rows = before[np.asarray(a[2], dtype=np.intp)]
        if len(a) > 4:
            last = bool(a[4])
        return rows ^ (rows >> s31) if last else rows.copy()

    monkeypatch.setattr(draws, "_hashes", hashes)
    whole = before ^ (before >> s31)
    assert swapped == 3
    assert np.array_equal(view_orders(1, 2, list(range(70)), 64), whole.argsort(axis=1))
    assert not np.array_equal(before.argsort(axis=1), whole.argsort(axis=1))


@settings(max_examples=30, deadline=None)
@given(
    st.integers(2, 24),
    st.integers(0, 2**32),
    st.sampled_from(range(len(MODELS))),
    st.lists(st.integers(1, 3), min_size=1, max_size=150),
    st.data(),
)
def test_views_at_once_round_after_round_are_the_views_built_alone(
    n: int, seed: int, model: int, steps: list[int], data: st.DataObject
) -> None:
    """Round after round, a lock step's views at once come of view orders drawn ahead; rounds
    that skip ahead and subsets of the robots get the very views each Look builds alone."""
    setting = Configured.of(ALGORITHM, n)
    positions = np.round(np.random.default_rng(seed).uniform(-50.0, 50.0, (n, 2)), 6)
    ahead = Looks(MODELS[model], setting, n, seed, False)
    alone = Looks(MODELS[model], setting, n, seed, False)
    look_round = 0
    for step in steps:
        look_round += step
        robots = list(range(n)) if step == 1 else [r for r in range(n) if (r + look_round) % 3]
        views = ahead.views_at_once(positions, look_round, robots)
        assert views is not None
        for row, robot in enumerate(robots):
            assert views[row].tobytes() == alone.view(positions, robot, look_round)[0].tobytes()
