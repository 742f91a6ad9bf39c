"""Scheduler invariants under arbitrary seeds, sizes and changing live sets."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.coordinator.schedule import make_scheduler

names = st.sampled_from(["fsync", "ssync", "centralized"])


@settings(max_examples=60, deadline=None)
@given(
    name=names,
    n=st.integers(1, 12),
    seed=st.integers(0, 2**32 - 1),
    live_masks=st.lists(st.integers(1, 2**12 - 1), min_size=1, max_size=40),
)
def test_active_set_is_a_sorted_nonempty_subset_of_live(
    name: str, n: int, seed: int, live_masks: list[int]
) -> None:
    sched = make_scheduler(name, n, seed)
    for k, mask in enumerate(live_masks, start=1):
        live = [r for r in range(n) if mask >> r & 1] or [0]
        active = sched.active(k, live)
        assert active and set(active) <= set(live) and active == sorted(set(active))


@settings(max_examples=60, deadline=None)
@given(
    name=st.sampled_from(["ssync", "centralized"]),
    n=st.integers(1, 10),
    seed=st.integers(0, 2**32 - 1),
    fairness=st.integers(1, 25),
)
def test_every_robot_active_within_the_fairness_bound(
    name: str, n: int, seed: int, fairness: int
) -> None:
    sched = make_scheduler(name, n, seed, fairness=fairness)
    bound = max(fairness, n) if name == "centralized" else fairness
    last = dict.fromkeys(range(n), 0)
    for k in range(1, 6 * bound + 2):
        for robot in sched.active(k, list(range(n))):
            last[robot] = k
        assert all(k - seen < bound for seen in last.values())


@settings(max_examples=40, deadline=None)
@given(name=names, n=st.integers(1, 10), seed=st.integers(0, 2**32 - 1))
def test_same_seed_same_sequence(name: str, n: int, seed: int) -> None:
    a = make_scheduler(name, n, seed)
    b = make_scheduler(name, n, seed)
    live = list(range(n))
    assert [a.active(k, live) for k in range(1, 50)] == [b.active(k, live) for k in range(1, 50)]
