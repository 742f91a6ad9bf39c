"""Refused messages counted by kind and said at most once per kind every few seconds."""

from __future__ import annotations

from collections import Counter

from fatswarm.world.rejections import SAY_EVERY_S, Rejections, tally


def test_the_first_of_a_kind_is_said_at_once_and_the_rest_with_their_count_later() -> None:
    r = Rejections()
    assert r.count("move-garbage", "on k: bad", 100.0) == "rejected (move-garbage): on k: bad"
    said = [r.count("move-garbage", f"on k: bad {i}", 100.0 + i * 0.001) for i in range(5_000)]
    assert said == [None] * 5_000  # within SAY_EVERY_S of the first: counted, not said
    assert r.due(100.0 + SAY_EVERY_S / 2) == []
    assert r.due(100.0 + SAY_EVERY_S) == [
        "rejected (move-garbage): on k: bad 4999 [5,000 since it was last said, 5,001 in all]"
    ]
    assert r.due(200.0) == []  # nothing new: nothing said
    assert r.totals == Counter({"move-garbage": 5_001})


def test_each_kind_keeps_its_own_pace() -> None:
    r = Rejections(every_s=5.0)
    assert r.count("look-garbage", "a", 0.0) is not None
    assert r.count("move-wrong-robot", "b", 1.0) is not None  # another kind: said at once
    assert r.count("look-garbage", "c", 4.0) is None
    assert r.count("look-garbage", "d", 5.0) == (
        "rejected (look-garbage): d [2 since it was last said, 3 in all]"
    )
    assert r.count("move-wrong-robot", "e", 5.5) is None
    assert r.flush(5.5) == ["rejected (move-wrong-robot): e [1 since it was last said, 2 in all]"]
    assert r.flush(5.5) == []


def test_a_flood_of_a_hundred_thousand_costs_a_line_per_kind_per_period() -> None:
    r, lines = Rejections(every_s=5.0), 0
    kinds = ("look-garbage", "move-garbage", "move-wrong-round")
    for i in range(100_000):  # 10,000 a second for 10 s
        lines += r.count(kinds[i % 3], "x", i / 10_000) is not None
    lines += len(r.flush(10.0))
    assert lines == 3 * 3  # at 0 s, at 5 s, and the rest at the end
    assert sum(r.totals.values()) == 100_000


def test_tally_names_the_kinds_most_first() -> None:
    assert tally({"b": 2, "a": 2, "c": 1_500, "d": 0}) == "c 1,500, a 2, b 2"
