"""orjson's text of a float array is taken for the record only where it is `repr`'s (the text
`json.dumps` writes): every value 0 or of magnitude in [1e-4, 1e16); anything else, and an orjson
that formats otherwise, goes back to `repr`, so records stay byte for byte."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import orjson
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from fatswarm.world import float_text
from fatswarm.world.float_text import HIGH, LOW, floats_text, taken
from fatswarm.world.record import LineMoves, PointsMemo, round_entry, round_text

SETTINGS = settings(max_examples=300, deadline=None)
BOUNDS = (LOW, HIGH, 1e-5, 1e15, 1e17, 5e-324, 2.0**-1022)
ANY = st.one_of(
    st.sampled_from([*BOUNDS, 0.0, -0.0, float("nan"), float("inf")]),
    st.sampled_from(BOUNDS).map(lambda b: float(np.nextafter(b, 0.0))),
    st.sampled_from(BOUNDS).map(lambda b: float(np.nextafter(b, np.inf))),
    st.floats(),
).map(lambda x: x if hash(x) % 2 else -x)
TAKEN = st.one_of(
    st.sampled_from([0.0, -0.0, LOW, -LOW, float(np.nextafter(HIGH, 0.0))]),
    st.floats(LOW, HIGH, exclude_max=True),
    st.floats(-HIGH, -LOW, exclude_min=True),
)


def dumps(values: np.ndarray[Any, Any]) -> str:
    return json.dumps(values.tolist(), separators=(",", ":"))


@SETTINGS
@given(hnp.arrays(np.float64, hnp.array_shapes(min_dims=1, max_dims=2, max_side=6), elements=ANY))
@example(np.array([1e-4, -0.0, 9999999999999998.0]))
@example(np.array([[1e16, 1.0]]))
def test_the_text_is_json_dumps_text_or_none_where_a_value_is_outside_the_range(
    values: np.ndarray[Any, Any],
) -> None:
    made = floats_text(values)
    size = np.abs(values)
    inside = bool(((size == 0) | ((size >= LOW) & (size < HIGH))).all())
    assert (made is not None) == inside == taken(values)
    if made is not None:
        assert made == dumps(values)


@SETTINGS
@given(hnp.arrays(np.float64, st.integers(1, 40), elements=TAKEN))
def test_every_value_in_the_range_is_written_as_its_repr(values: np.ndarray[Any, Any]) -> None:
    made = floats_text(values)
    assert made is not None
    assert made[1:-1].split(",") == [repr(x) for x in values.tolist()]


def test_drawn_bit_patterns_across_the_range_are_written_as_their_repr() -> None:
    bounds = np.array([LOW, HIGH]).view(np.int64)  # positive floats order as their bits do
    bits = np.random.default_rng(30).integers(bounds[0], bounds[1], 200_000, dtype=np.int64)
    values = bits.view(np.float64) * np.where(bits % 3 == 0, -1.0, 1.0)
    made = floats_text(values)
    assert made is not None
    assert made == "[" + ",".join(map(repr, values.tolist())) + "]"


@pytest.mark.parametrize(
    "value", [float(np.nextafter(LOW, 0.0)), HIGH, 1e-5, 5e-324, float("nan"), float("-inf")]
)
def test_a_value_just_outside_the_range_is_left_to_repr(value: float) -> None:
    assert floats_text(np.array([1.0, value, 2.0])) is None


def test_an_array_of_another_dtype_or_order_is_handled(monkeypatch: pytest.MonkeyPatch) -> None:
    assert floats_text(np.array([1, 2])) is None  # ints: not this path's
    fortran = np.asfortranarray(np.array([[0.5, 1.5], [2.5, 3.5]]))
    assert floats_text(fortran) == dumps(fortran)
    assert floats_text(np.empty((0, 2))) == "[]"


def test_an_orjson_that_formats_otherwise_turns_the_path_off(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    assert float_text._agrees()
    sample = float_text._sample()
    wrong = json.dumps(sample.tolist(), separators=(",", ":")).replace("0.1,", "1e-1,")
    monkeypatch.setattr(orjson, "dumps", lambda *_, **__: wrong.encode())
    assert wrong != json.dumps(sample.tolist(), separators=(",", ":"))
    assert not float_text._agrees()
    monkeypatch.setattr(float_text, "AGREES", False)
    assert floats_text(np.array([0.5])) is None


@pytest.mark.parametrize("agrees", [True, False])
@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_a_round_line_as_arrays_is_the_text_of_its_paths_either_way(
    data: st.DataObject, agrees: bool
) -> None:
    """LineMoves' and PointsMemo's text through orjson (floats in the range) and through repr
    (AGREES off) is the line its Paths give, which the tests of round_text hold to json.dumps."""
    n = data.draw(st.integers(1, 8))
    floats = st.one_of(TAKEN, ANY.filter(lambda x: x == x and abs(x) != float("inf")))
    pick = data.draw(st.sampled_from([TAKEN, floats]))
    some = data.draw(st.sets(st.integers(0, n - 1), min_size=1))
    movers = np.arange(n) if data.draw(st.booleans()) else np.array(sorted(some))  # every, some
    ends = data.draw(hnp.arrays(np.float64, (len(movers), 2), elements=pick))
    traveled = np.abs(data.draw(hnp.arrays(np.float64, len(movers), elements=pick)))
    positions = data.draw(hnp.arrays(np.float64, (n, 2), elements=pick))
    of_arrays = round_entry(7, list(range(n)), LineMoves(movers, ends, traveled), None, positions)
    made = of_arrays.moves  # as Paths: robot -> path and robot -> distance covered
    paths, covered = {m.robot: m.path for m in made}, {m.robot: m.traveled for m in made}
    of_paths = round_entry(7, list(range(n)), paths, covered, positions)
    old = float_text.AGREES
    try:
        float_text.AGREES = agrees  # type: ignore[misc]
        memo = PointsMemo()
        assert round_text(of_arrays, memo) == round_text(of_paths) == round_text(of_arrays, memo)
    finally:
        float_text.AGREES = old  # type: ignore[misc]
