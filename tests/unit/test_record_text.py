"""The round line written piece by piece (`round_text`) is the very text the writer wrote as one
JSON object before (`json.dumps` of the line's dict); a round's moves as arrays (`LineMoves`) give
the same entry, line and books as their Paths; min_gap over each pair once is the full matrix's."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path as FsPath
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.domain.figures import _GapMemo, min_gap
from fatswarm.domain.path import Arc, Line, Path
from fatswarm.world.core import WorldCore
from fatswarm.world.journal import load_configured
from fatswarm.world.model import RoundBooking
from fatswarm.world.physics import Collision
from fatswarm.world.progress import ProgressTracker
from fatswarm.world.record import (
    LineMoves,
    Move,
    PointsMemo,
    RecordWriter,
    RoundEntry,
    line_text,
    round_entry,
    round_fields,
    round_text,
)
from fatswarm.world.setup import WorldSetup

SETTINGS = settings(max_examples=150, deadline=None)
# the floats whose text is tricky: signed zero, the smallest and largest exponents, the switch to
# exponent form at 1e16 and 1e-4, whole numbers, and the rest
ODD = (-0.0, 0.0, 1e-300, -1e-300, 5e-324, 1e16, -1e16, 1e15, 1e-4, 1e-5, 3.0, -7.0, 2.0**60)
FLOATS = st.one_of(st.sampled_from(ODD), st.floats(allow_nan=False, allow_infinity=False))


class _Old(RecordWriter):
    """The writer's text of a round line as it made it before: one json.dumps of the dict
    `RecordWriter.round` builds (kept, no file)."""

    def __init__(self) -> None:  # (RecordWriter's opens the file: not called)
        self.text = ""

    def put(self, text: str) -> None:
        self.text = text


def old_text(entry: RoundEntry) -> str:
    out = _Old()
    moves = {m.robot: (m.path, m.traveled) for m in entry.moves}
    out.round(entry.round, entry.active, moves, entry.positions, entry.collisions, **entry.extra)
    return out.text


@st.composite
def paths(draw: st.DrawFn) -> Path:
    segments = draw(
        st.lists(
            st.one_of(
                st.builds(lambda x, y: Line((x, y)), FLOATS, FLOATS),
                st.builds(lambda x, y, s: Arc((x, y), s), FLOATS, FLOATS, FLOATS),
            ),
            min_size=1,
            max_size=3,
        )
    )
    return Path(tuple(segments))


@st.composite
def entries(draw: st.DrawFn) -> RoundEntry:
    n = draw(st.integers(1, 6))
    robots = list(range(n))
    movers = draw(st.lists(st.sampled_from(robots), unique=True, max_size=n))
    moved = {r: draw(paths()) for r in movers}
    covered = {r: abs(draw(FLOATS)) for r in movers if draw(st.booleans())}
    positions = np.array(draw(st.lists(st.tuples(FLOATS, FLOATS), min_size=n, max_size=n)))
    collisions = [
        Collision(r, draw(st.sampled_from(robots)), abs(draw(FLOATS)), (draw(FLOATS), 1.5))
        for r in draw(st.lists(st.sampled_from(robots), unique=True, max_size=2))
    ]
    lists = (("timed_out", draw(st.lists(st.sampled_from(robots), unique=True, max_size=2))),)
    model = draw(st.sampled_from([None, {"lights": ["red", "off"] * n}, {"views": {"0": [1]}}]))
    failed = draw(st.sampled_from([None, {0: 'ViewError: \u00e9 "quoted"\n'}]))
    times = draw(
        st.sampled_from([None, {"look": 1.0, "start": 1e16, "end": 2e16, "origin": [0.1, -0.0]}])
    )
    return round_entry(
        draw(st.integers(1, 10**6)),
        sorted(draw(st.lists(st.sampled_from(robots), unique=True, min_size=1))),
        moved,
        covered,
        positions,
        collisions,
        times=times,
        robots=lists,
        model=model,
        failed=failed,
    )


@SETTINGS
@given(entries())
def test_a_round_line_is_the_text_json_dumps_made_of_it(entry: RoundEntry) -> None:
    text = round_text(entry)
    assert text == old_text(entry) == line_text(entry)
    assert json.loads(text)["type"] == "round"


@SETTINGS
@given(entries())
def test_a_round_line_of_moves_given_as_a_tuple_is_the_same_text(entry: RoundEntry) -> None:
    as_tuple = replace(entry, moves=tuple(entry.moves))
    assert round_text(as_tuple) == round_text(entry)


def test_active_robots_given_as_other_numbers_are_written_as_the_lines_dict_writes_them() -> None:
    entry = round_entry(4, [0, 1, 2], {}, {}, np.zeros((3, 2)))
    odd_ones: list[tuple[Any, ...]] = [(np.int64(0), 1, 2), ("0", 1, 2.0), (True, 1, 2)]
    for active in odd_ones:
        odd = replace(entry, active=active)
        assert round_text(odd) == json.dumps(round_fields(odd), separators=(",", ":"))


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
@pytest.mark.parametrize("where", ["position", "end", "traveled", "sweep", "extra"])
def test_a_round_line_refuses_what_json_refuses(bad: float, where: str) -> None:
    """NaN and infinity: no record holds them; refused as `json.dumps(allow_nan=False)` does."""
    path = Path((Arc((0.0, 1.0), bad if where == "sweep" else 0.5),))
    if where == "end":
        path = Path((Line((bad, 0.0)),))
    entry = round_entry(
        1,
        [0, 1],
        {0: path},
        {0: bad if where == "traveled" else 1.0},
        np.array([[0.0, bad if where == "position" else 0.0], [4.0, 0.0]]),
        times={"look": bad} if where == "extra" else None,
    )
    with pytest.raises(ValueError) as new:
        round_text(entry)
    with pytest.raises(ValueError) as old:
        old_text(entry)
    assert str(new.value) == str(old.value)


def test_extra_fields_named_as_the_lines_own_go_the_dicts_way() -> None:
    entry = RoundEntry(1, (0,), (), np.zeros((1, 2)), (), {"round": 7, "type": "x", "z": 1})
    assert (
        round_text(entry)
        == old_text(entry)
        == '{"type":"x","round":7,'
        + ('"active":[0],"moves":[],"positions":[[0.0,0.0]],"collisions":[],"z":1}')
    )


def test_extra_fields_not_named_by_text_are_refused_as_before() -> None:
    entry = RoundEntry(1, (0,), (), np.zeros((1, 2)), (), {3: "x"})  # type: ignore[dict-item]
    with pytest.raises(TypeError, match="keywords must be strings"):
        old_text(entry)
    with pytest.raises(TypeError, match="keywords must be strings"):
        round_text(entry)


def line_moves(draw: Any, n: int) -> tuple[dict[int, Path], dict[int, float], LineMoves]:
    movers = sorted(draw(st.lists(st.integers(0, n - 1), unique=True, max_size=n)))
    ends = np.array([[draw(FLOATS), draw(FLOATS)] for _ in movers]).reshape(-1, 2)
    traveled = np.array([abs(draw(FLOATS)) for _ in movers], dtype=np.float64)
    moved = {r: Path((Line((float(x), float(y))),)) for r, (x, y) in zip(movers, ends, strict=True)}
    covered = dict(zip(movers, traveled.tolist(), strict=True))
    return moved, covered, LineMoves(np.array(movers, dtype=np.intp), ends, traveled)


@SETTINGS
@given(st.data())
def test_moves_as_arrays_make_the_entry_and_line_their_paths_make(data: st.DataObject) -> None:
    n = data.draw(st.integers(1, 6))
    moved, covered, lines = line_moves(data.draw, n)
    positions = np.array(data.draw(st.lists(st.tuples(FLOATS, FLOATS), min_size=n, max_size=n)))
    of_paths = round_entry(3, list(range(n)), moved, covered, positions)
    of_arrays = round_entry(3, list(range(n)), lines, None, positions)
    assert round_text(of_arrays) == round_text(of_paths) == old_text(of_paths)
    assert of_arrays.moves == of_paths.moves == tuple(of_paths.moves)
    assert len(of_arrays.moves) == len(moved)
    assert [type(m.traveled) for m in of_arrays.moves] == [float] * len(moved)
    assert all(type(m.robot) is int for m in of_arrays.moves)
    assert round_text(of_arrays) == round_text(of_paths)  # (again, once the moves are made)


def test_moves_are_read_as_a_sequence_and_equal_their_tuple() -> None:
    lines = LineMoves(np.array([1, 4]), np.array([[0.5, -0.0], [1e16, 3.0]]), np.array([2.0, 0.0]))
    first = Move(1, Path((Line((0.5, -0.0)),)), 2.0)
    assert lines[0] == first and lines[-1].robot == 4 and lines[:1] == (first,)
    assert list(lines) == list(lines.made()) and len(lines) == 2
    assert lines == lines.made() and lines.made() == lines and lines != (first,)
    assert repr(lines) == repr(lines.made())


@st.composite
def booked_rounds(draw: st.DrawFn) -> list[tuple[dict[int, Path], dict[int, float], LineMoves]]:
    return [line_moves(draw, 5) for _ in range(draw(st.integers(1, 4)))]


@SETTINGS
@given(booked_rounds())
def test_the_tracker_books_moves_as_arrays_as_it_books_their_paths(
    rounds: Sequence[tuple[Mapping[int, Path], Mapping[int, float], LineMoves]],
) -> None:
    by_paths, by_arrays = ProgressTracker(5, lambda _: False), ProgressTracker(5, lambda _: False)
    before = np.zeros((5, 2))
    for k, (moved, covered, lines) in enumerate(rounds, start=1):
        after = before + k
        by_paths.observe(range(5), moved.keys(), before, after, covered)
        by_arrays.observe(range(5), lines.robots(), before, after, lines.traveled.tolist())
        before = after
    assert by_arrays.snapshot() == by_paths.snapshot()


def _full_min_gap(points: np.ndarray) -> float:
    """min_gap as it was measured up to PAIRWISE_UP_TO robots: every ordered pair at once."""
    dx = points[:, None, 0] - points[None, :, 0]
    dy = points[:, None, 1] - points[None, :, 1]
    squares = dx * dx + dy * dy
    np.fill_diagonal(squares, np.inf)
    return math.sqrt(float(np.min(squares))) - 2.0


@settings(max_examples=200, deadline=None)
@given(
    st.integers(2, 80).flatmap(
        lambda n: st.lists(st.tuples(FLOATS, FLOATS).map(list), min_size=n, max_size=n)
    )
)
def test_min_gap_over_each_pair_once_is_the_full_matrix_bits(points: Any) -> None:
    pts = np.array(points, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        expected, got = _full_min_gap(pts), min_gap(pts)
    assert got is not None
    assert np.float64(got).view(np.int64) == np.float64(expected).view(np.int64)


def _core() -> WorldCore:
    start = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0], [10.0, 10.0]])
    setup = WorldSetup("t", 4, 1, "ssync", start, 50, params={"a": 4.0})
    return WorldCore(setup, load_configured(setup))


@pytest.mark.parametrize("measured", ["none", "array", "mapping"])
def test_the_core_books_a_round_as_arrays_as_it_books_its_paths(measured: str) -> None:
    """`account` of a RoundBooking whose moves are a LineMoves: the very books (lengths, moved,
    the tracker's figures) that their Paths give; physics' lengths where given."""
    by_paths, by_arrays = _core(), _core()
    before = by_paths.positions
    ends = before[[0, 2]] + np.array([[0.1, 0.7], [-0.3, 1e-5]])
    traveled = np.array([0.5, 1e-5])
    lines = LineMoves(np.array([0, 2]), ends, traveled)
    moved = {0: Path((Line(tuple(ends[0].tolist())),)), 2: Path((Line(tuple(ends[1].tolist())),))}
    after = before.copy()
    after[[0, 2]] = ends
    lengths = {"none": None, "array": np.array([0.25, 2.5]), "mapping": {2: 2.5}}[measured]
    common: dict[str, Any] = {"round": 1, "active": (0, 1, 2), "timed_out": (1,), "before": before}
    common |= {"after": after, "collisions": ()}
    by_paths.account(
        RoundBooking(
            paths=moved,
            traveled=dict(zip([0, 2], traveled.tolist(), strict=True)),
            lengths={0: 0.25, 2: 2.5} if measured == "array" else lengths,
            **common,
        )
    )
    by_arrays.account(RoundBooking(paths=lines, traveled=None, lengths=lengths, **common))
    assert by_arrays.last_length == by_paths.last_length
    assert [type(k) for k in by_arrays.last_length] == [float] * 4
    assert (
        (by_arrays.moved, by_arrays.timeouts)
        == (by_paths.moved, by_paths.timeouts)
        == (
            (0, 2),
            [0, 1, 0, 0],
        )
    )
    assert by_arrays.tracker.snapshot() == by_paths.tracker.snapshot()


@settings(max_examples=120, deadline=None)
@given(st.data(), st.sampled_from([3, 81, 120, 200]))
def test_min_gap_kept_round_to_round_is_min_gap_of_each_round(data: st.DataObject, n: int) -> None:
    """Few movers a round (the memo measures only their pairs), or many, or the closest pair
    moving: each round's value is min_gap's, to the bit."""
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    pts = rng.uniform(-2.0 * n, 2.0 * n, (n, 2))
    memo = _GapMemo()
    for _ in range(data.draw(st.integers(1, 12))):
        few = st.integers(0, max(1, n // 4))
        movers = rng.choice(n, size=data.draw(st.one_of(few, st.integers(0, n))), replace=False)
        how = data.draw(st.sampled_from(["onto", "some", "all"]))
        if how == "onto":  # a mover comes close to someone, or onto him
            other = int(rng.integers(n))
            pts[movers] = pts[other] + data.draw(st.sampled_from([0.0, 1e-300, 2.5, -0.0]))
        elif how == "some":
            pts[movers] += rng.normal(size=(len(movers), 2)) * data.draw(st.sampled_from([1, 9]))
        else:  # every robot a little (the near pairs of the last whole measure answer)
            pts += rng.normal(size=(n, 2)) * data.draw(st.sampled_from([1e-4, 0.05, 0.3]))
        got, expected = memo.min_gap(pts), min_gap(pts)
        assert got is not None and expected is not None
        assert np.float64(got).view(np.int64) == np.float64(expected).view(np.int64)


@SETTINGS
@given(st.data())
def test_positions_kept_from_the_line_before_give_the_text_of_the_positions(
    data: st.DataObject,
) -> None:
    """Rows the same to the bit keep their text; a row whose zero changed sign, or any other
    bit, is written anew; a new number of robots starts afresh."""
    memo = PointsMemo()
    n = data.draw(st.integers(0, 7))
    pts = np.array(data.draw(st.lists(st.tuples(FLOATS, FLOATS), min_size=n, max_size=n)))
    pts = pts.reshape(-1, 2)
    for _ in range(data.draw(st.integers(1, 6))):
        if data.draw(st.booleans()) and n:
            rows = data.draw(st.lists(st.integers(0, n - 1), max_size=n))
            pts = pts.copy()
            pts[rows] = data.draw(st.sampled_from([-0.0, 0.0, 1e16, 3.0, 1e-300]))
        elif data.draw(st.booleans()):
            n = data.draw(st.integers(0, 7))
            pts = np.array(data.draw(st.lists(st.tuples(FLOATS, FLOATS), min_size=n, max_size=n)))
            pts = pts.reshape(-1, 2)
        view = pts if data.draw(st.booleans()) else np.asfortranarray(pts)
        expected = json.dumps([[float(x), float(y)] for x, y in pts], separators=(",", ":"))
        assert memo.text(view) == expected


def test_a_writer_writes_a_run_of_round_lines_as_json_dumps_did(tmp_path: FsPath) -> None:
    pts = np.array([[0.0, 1.0], [-0.0, 2.5], [1e16, -1e-300]])
    entries = []
    for k in range(1, 6):
        pts = pts.copy()
        pts[k % 3] = [pts[k % 3, 0] * -1.0, 0.1 * k]  # one robot, its zero's sign flipped too
        entries.append(round_entry(k, [0, 1, 2], {}, {}, pts))
    with RecordWriter(tmp_path / "run.jsonl") as w:
        for entry in entries:
            w.append(entry)
    assert (tmp_path / "run.jsonl").read_text().splitlines() == [old_text(e) for e in entries]


@pytest.mark.parametrize("n", [2, 81, 120, 300])
@pytest.mark.parametrize("step", [1e-4, 0.02, 0.4, 3.0])
def test_min_gap_kept_while_every_robot_moves_is_min_gap_of_each_round(n: int, step: float) -> None:
    rng = np.random.default_rng(n)
    pts = rng.uniform(-1.5 * n, 1.5 * n, (n, 2)) + 1e5 * (n == 300)  # (far from the origin too)
    memo = _GapMemo()
    for _ in range(40):
        pts = pts + rng.normal(size=(n, 2)) * step
        got, expected = memo.min_gap(pts), min_gap(pts)
        assert got is not None and expected is not None
        assert np.float64(got).view(np.int64) == np.float64(expected).view(np.int64)
