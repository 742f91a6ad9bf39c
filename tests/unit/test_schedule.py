"""Schedulers: fsync, ssync, centralized, scripted; seeding, fairness, live sets, file errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fatswarm.coordinator.schedule import (
    ScheduleError,
    ScheduleFileError,
    default_fairness,
    load_script,
    make_scheduler,
)
from fatswarm.world.record_read import read_record


def run(name: str, n: int, seed: int, rounds: int, **kw: object) -> list[list[int]]:
    sched = make_scheduler(name, n, seed, **kw)  # type: ignore[arg-type]
    return [sched.active(k, list(range(n))) for k in range(1, rounds + 1)]


def test_fsync_activates_every_live_robot() -> None:
    sched = make_scheduler("fsync", 5, 0)
    assert sched.active(1, [4, 0, 2]) == [0, 2, 4]
    assert sched.name == "fsync"


def test_fsync_asked_with_the_same_live_tuple_again_follows_it_and_gives_its_own_list() -> None:
    sched = make_scheduler("fsync", 5, 0)
    live = (0, 2, 4)
    first = sched.active(1, live)
    first.append(1)  # the caller's list: the next answer is not changed by it
    assert sched.active(2, live) == [0, 2, 4]
    assert sched.active(3, (4, 0)) == [0, 4]  # another tuple: its robots
    assert sched.active(4, [3, 1]) == [1, 3]  # a list: read anew each time


@pytest.mark.parametrize("name", ["ssync", "centralized"])
def test_live_sets_given_as_tuples_give_the_same_sequence_as_lists(name: str) -> None:
    tuples = make_scheduler(name, 7, 3)
    live = tuple(range(7))
    assert [tuples.active(k, live) for k in range(1, 61)] == run(name, 7, 3, 60)


@pytest.mark.parametrize("name", ["ssync", "centralized"])
def test_same_seed_gives_same_sequence(name: str) -> None:
    assert run(name, 7, 3, 60) == run(name, 7, 3, 60)


@pytest.mark.parametrize("name", ["ssync", "centralized"])
def test_different_seeds_give_different_sequences(name: str) -> None:
    assert run(name, 7, 3, 60) != run(name, 7, 4, 60)


def test_ssync_can_activate_every_robot_and_single_robots() -> None:
    sizes = {len(s) for s in run("ssync", 3, 1, 400)}
    assert sizes == {1, 2, 3}


def test_centralized_activates_exactly_one_robot() -> None:
    assert all(len(s) == 1 for s in run("centralized", 6, 2, 200))


@pytest.mark.parametrize("name", ["ssync", "centralized"])
def test_fairness_bound_holds(name: str) -> None:
    n, k = 6, 6
    seq = run(name, n, 5, 300, fairness=k)
    for robot in range(n):
        rounds = [i for i, s in enumerate(seq, start=1) if robot in s]
        gaps = [b - a for a, b in zip([0, *rounds], rounds, strict=False)]
        assert max(gaps) <= k


def test_ssync_fairness_one_is_fsync() -> None:
    assert run("ssync", 4, 0, 10, fairness=1) == [[0, 1, 2, 3]] * 10


def test_centralized_stretches_a_too_tight_bound_to_the_live_count() -> None:
    seq = run("centralized", 5, 0, 50, fairness=2)
    for robot in range(5):
        rounds = [i for i, s in enumerate(seq, start=1) if robot in s]
        assert max(b - a for a, b in zip([0, *rounds], rounds, strict=False)) <= 5


@pytest.mark.parametrize("name", ["fsync", "ssync", "centralized"])
def test_only_live_robots_are_activated_when_live_set_changes(name: str) -> None:
    sched = make_scheduler(name, 6, 9)
    lives = [[0, 1, 2, 3, 4, 5], [0, 2, 4], [1], [1, 5], [0, 1, 2, 3, 4, 5]] * 10
    for k, live in enumerate(lives, start=1):
        active = sched.active(k, live)
        assert active and set(active) <= set(live) and active == sorted(active)


def test_rejoining_robot_is_active_within_the_bound() -> None:
    sched = make_scheduler("ssync", 4, 1, fairness=3)
    for k in range(1, 6):
        sched.active(k, [0, 1, 2])
    seen = [sched.active(k, [0, 1, 2, 3]) for k in range(6, 9)]
    assert any(3 in s for s in seen)


def test_empty_live_set_is_refused() -> None:
    with pytest.raises(ScheduleError):
        make_scheduler("fsync", 3, 0).active(1, [])


def test_unknown_name_and_bad_fairness_are_refused() -> None:
    with pytest.raises(ScheduleError, match="unknown scheduler"):
        make_scheduler("asynchronous", 3, 0)
    with pytest.raises(ScheduleError, match="fairness"):
        make_scheduler("ssync", 3, 0, fairness=0)
    with pytest.raises(ScheduleError, match="schedule file"):
        make_scheduler("scripted", 3, 0)


def test_default_fairness_is_twice_n() -> None:
    assert default_fairness(8) == 16
    assert default_fairness(1) == 2


def write(tmp_path: Path, data: object) -> str:
    path = tmp_path / "schedule.json"
    path.write_text(json.dumps(data) if not isinstance(data, str) else data)
    return str(path)


def test_script_replays_rounds_then_repeats(tmp_path: Path) -> None:
    path = write(tmp_path, {"rounds": [[2, 0], [1]]})
    sched = make_scheduler("scripted", 3, 0, schedule_path=path)
    assert [sched.active(k, [0, 1, 2]) for k in range(1, 6)] == [[0, 2], [1], [0, 2], [1], [0, 2]]


def test_script_after_fsync_activates_everyone(tmp_path: Path) -> None:
    path = write(tmp_path, {"rounds": [[1]], "after": "fsync"})
    sched = make_scheduler("scripted", 3, 0, schedule_path=path)
    assert [sched.active(k, [0, 1, 2]) for k in (1, 2, 3)] == [[1], [0, 1, 2], [0, 1, 2]]


def test_script_skips_dead_robots_and_never_returns_empty(tmp_path: Path) -> None:
    path = write(tmp_path, {"rounds": [[0, 2], [1]]})
    sched = make_scheduler("scripted", 3, 0, schedule_path=path)
    assert sched.active(1, [0, 1]) == [0]
    assert sched.active(2, [0, 2]) == [0, 2]


def test_script_from_run_record_replays_its_active_sets() -> None:
    path = Path(__file__).resolve().parents[1] / "data" / "lockstep-n6-seed1.jsonl"
    recorded = [list(entry.active) for entry in read_record(path).rounds]
    sched = load_script(str(path), 6)
    assert [sched.active(k, range(6)) for k in range(1, len(recorded) + 1)] == recorded


def test_a_schedule_file_that_is_a_broken_record_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "run.jsonl"
    lines = [{"type": "header", "version": 1, "n": 2}, {"type": "round", "round": 1}]
    path.write_text("".join(json.dumps(x) + "\n" for x in lines))
    with pytest.raises(ScheduleFileError, match=r"schedule file .*run.jsonl: .*:1: 'a'"):
        load_script(str(path), 2)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("{", "not JSON"),
        ("[[0]]", "must hold an object"),
        ({"rounds": []}, "non-empty list"),
        ({"rounds": [[0], []]}, "round 2 must be a non-empty list"),
        ({"rounds": [[0, 3]]}, "robots are 0..2"),
        ({"rounds": [[0, "1"]]}, "names robot '1'"),
        ({"rounds": [[0]], "after": "stop"}, "'after' must be one of"),
    ],
)
def test_bad_script_file_gives_one_line_error(
    tmp_path: Path, content: object, message: str
) -> None:
    with pytest.raises(ScheduleFileError, match=message) as info:
        make_scheduler("scripted", 3, 0, schedule_path=write(tmp_path, content))
    assert "\n" not in str(info.value)


def test_missing_script_file_is_named(tmp_path: Path) -> None:
    with pytest.raises(ScheduleFileError, match="cannot read schedule file"):
        load_script(str(tmp_path / "nope.json"), 3)
