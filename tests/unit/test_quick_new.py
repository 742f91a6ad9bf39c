"""quick_new: a frozen dataclass with slots made from every field by name, through its slots (the
record's round line and the tracker's snapshot are made so every round)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fatswarm.domain.quick import quick_new
from fatswarm.world.progress import Progress, ProgressTracker
from fatswarm.world.record import RoundEntry, round_entry


@dataclasses.dataclass(frozen=True, slots=True)
class _Line:
    round: int
    robots: tuple[int, ...]
    extra: dict[str, int] = dataclasses.field(default_factory=dict)


def test_quick_new_makes_the_object_the_dataclass_makes() -> None:
    new = quick_new(_Line)
    made = new(round=3, robots=(1, 2), extra={"a": 1})
    assert type(made) is _Line and made == _Line(3, (1, 2), {"a": 1})
    assert repr(made) == repr(_Line(3, (1, 2), {"a": 1}))
    with pytest.raises(dataclasses.FrozenInstanceError):
        made.round = 4  # type: ignore[misc]
    with pytest.raises(TypeError):
        new(round=3, robots=())  # every field, none left to a default
    with pytest.raises(TypeError):
        new(3, (), {})  # by name only


def test_the_round_line_and_the_snapshot_are_the_dataclasses_own() -> None:
    pts = np.zeros((2, 2))
    entry = round_entry(4, [0, 1], {}, None, pts, robots=(("cut", [1]),))
    assert entry == RoundEntry(4, (0, 1), entry.moves, pts, (), {"cut": [1]})
    tracker = ProgressTracker(2, lambda _: False)
    tracker.observe((0, 1), [0], pts, pts + 1.0, [0.5])
    got = tracker.snapshot()
    fields = {f.name: getattr(got, f.name) for f in dataclasses.fields(Progress)}
    assert type(got) is Progress and got == Progress(**fields)
    assert got.moves_by_robot == (1, 0) and got.moves == 1 and got.total_distance == 0.5
