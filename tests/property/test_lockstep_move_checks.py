"""The lock step's shortcut for a move's checks (`plain_path`) takes a path only where the wire's
checks (`MoveSubmitted.of`, the codec's record form) give that very path back: same move or same
refusal, for any path, out-of-range, non-finite and oddly typed ones included."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.deploy.engine.lockstep import plain_path
from fatswarm.domain.path import Arc, Line, Path
from fatswarm.domain.wire import MAX_COORD, MAX_SWEEP, ProtocolError
from fatswarm.world.protocol import MoveSubmitted

EDGES = (0.0, -0.0, MAX_COORD, -MAX_COORD, math.nextafter(MAX_COORD, math.inf), 1e300, math.inf)
edges = st.sampled_from(
    (*EDGES, math.nan, -math.inf, MAX_SWEEP, -MAX_SWEEP, math.nextafter(MAX_SWEEP, math.inf))
)
floats = st.one_of(st.floats(), st.floats(-2e9, 2e9), st.floats(-40.0, 40.0), edges)
numbers: st.SearchStrategy[Any] = st.one_of(
    floats,
    floats,
    floats,
    st.integers(-(10**10), 10**10),
    floats.map(np.float64),
    st.booleans(),
    st.just("1.0"),
)
points: st.SearchStrategy[Any] = st.one_of(
    st.tuples(numbers, numbers),
    st.tuples(numbers, numbers).map(list),
    st.tuples(numbers),
    st.tuples(numbers, numbers, numbers),
)
segments: st.SearchStrategy[Any] = st.one_of(
    st.builds(Line, points), st.builds(Arc, points, numbers), st.just("line")
)


def outcome(make: Any, path: Any) -> object:
    """What a check gives: the move's fields in bits (repr), or the refusal's words."""
    try:
        move = make(path)
    except ProtocolError as exc:
        return f"refused: {exc}"
    except Exception as exc:  # a path that cannot even be encoded
        return f"raised {type(exc).__name__}"
    return repr((move.robot, move.round, move.path, move.colour))


def shortcut(path: Any) -> MoveSubmitted:
    """The lock step's way (`_Bus._delivered`, colour None)."""
    if plain_path(path):
        return MoveSubmitted(3, 9, path, None)
    return MoveSubmitted.of(3, 9, path, None)


# 600 examples draw every kind of outcome 2000 drew (each refusal's reason, an accepted move, the
# shortcut taken or not), in a third of the time
@settings(max_examples=600, deadline=None)
@given(st.lists(segments, max_size=4).map(lambda segs: Path(tuple(segs))))
def test_the_shortcut_gives_the_wire_s_move_or_its_refusal(path: Path) -> None:
    want = outcome(lambda p: MoveSubmitted.of(3, 9, p, None), path)
    assert outcome(shortcut, path) == want
    if plain_path(path):
        assert want == repr((3, 9, path, None))


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3), st.floats(-6.0, 6.0))))
def test_the_shortcut_takes_the_moves_algorithms_make(
    pts: list[tuple[float, float, float]],
) -> None:
    segs = tuple(Line((x, y)) if i % 2 else Arc((x, y), w) for i, (x, y, w) in enumerate(pts))
    assert plain_path(Path(segs[:64]))


def test_the_shortcut_leaves_other_shapes_to_the_wire() -> None:
    assert not plain_path(Path(tuple([Line((1.0, 0.0))] * 65)))
    assert not plain_path(Path([Line((1.0, 0.0))]))  # type: ignore[arg-type]
    assert not plain_path((Line((1.0, 0.0)),))  # type: ignore[arg-type]


@pytest.mark.parametrize(
    "path",
    [
        Path((Arc((MAX_COORD, 0.0), math.pi),)),  # centre inside, the arc's end outside
        Path((Line((MAX_COORD, 0.0)), Arc((0.0, 0.0), math.pi / 2))),  # end (0, 1e9): inside
        Path((Line((MAX_COORD, MAX_COORD)), Arc((0.0, 0.0), math.pi / 4))),  # end outside
        Path((Arc((1.0, 0.0), MAX_SWEEP),)),
        Path((Arc((1.0, 0.0), -math.nextafter(MAX_SWEEP, math.inf)),)),
        Path((Line((-0.0, 0.0)),)),
    ],
)
def test_the_shortcut_at_the_edges_of_the_bounds(path: Path) -> None:
    assert outcome(shortcut, path) == outcome(lambda p: MoveSubmitted.of(3, 9, p, None), path)
