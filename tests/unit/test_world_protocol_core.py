"""The world handling its protocol, without Zenoh: looks, moves, commits, durability, resume."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path as FsPath

import numpy as np
import pytest

from fatswarm.domain.path import STAY, Line, Path, mirror
from fatswarm.world.core import WorldCore
from fatswarm.world.faults import crash_after
from fatswarm.world.journal import open_world, perform
from fatswarm.world.protocol import (
    Begin,
    Commit,
    ControlReply,
    Hello,
    LookRequest,
    MovesHeld,
    MoveSubmitted,
    Snapshot,
    move_key,
    snapshot_key,
)
from fatswarm.world.record import RecordWriter
from fatswarm.world.record_read import read_record
from fatswarm.world.service import control_bytes, look_bytes, move_bytes
from fatswarm.world.setup import WorldSetup

SWARM = "t"
START = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]])


def _setup(max_rounds: int | None = 50) -> WorldSetup:
    return WorldSetup(SWARM, 3, 1, "ssync", START, max_rounds, params={"a": 4.0})


OPENED: dict[int, tuple[WorldCore, RecordWriter]] = {}


def _keep(opened: tuple[WorldCore, RecordWriter]) -> WorldCore:
    """The core of a world opened on a state file; its record is closed after the test."""
    OPENED[id(opened[0])] = opened
    return opened[0]


def _close(world: WorldCore) -> None:
    """Do what the core still asks (record lines) and close its record, as the world's shell."""
    core, journal = OPENED.pop(id(world))
    perform(core.take_effects(), journal)
    journal.close()


def _world(tmp_path: FsPath) -> WorldCore:
    w = _keep(open_world(str(tmp_path / "state.jsonl"), _setup, SWARM, None))
    return w


@pytest.fixture(autouse=True)
def _close_journals() -> Iterator[None]:
    yield
    while OPENED:
        _close(next(iter(OPENED.values()))[0])


def _ctl(world: WorldCore, data: bytes) -> ControlReply:
    reply = control_bytes(world, data)[0]
    perform(world.take_effects(), OPENED[id(world)][1])  # durable before the reply, as the shell
    return reply


def _move(world: WorldCore, key_robot: int, robot: int, round_no: int, path: Path) -> bool:
    """Send `path` (world axes) as robot `robot` would: in its private frame (a mirror or none)."""
    mine = mirror(path) if world.looks.frame(robot, round_no).mirror else path
    return move_bytes(
        world, move_key(SWARM, key_robot), MoveSubmitted(robot, round_no, mine).encode()
    )


def test_snapshot_only_for_active_robots_relative_and_without_ids(tmp_path: FsPath) -> None:
    w = _world(tmp_path)
    assert look_bytes(w, snapshot_key(SWARM, 0)) is None  # no round open
    assert _ctl(w, Begin(1, (1,)).encode()).ok
    assert look_bytes(w, snapshot_key(SWARM, 0)) is None  # not active
    data = look_bytes(w, snapshot_key(SWARM, 1))
    assert data is not None
    snap = Snapshot.decode(data)
    assert snap.round == 1 and snap.n == 3
    got = sorted(map(tuple, snap.view.tolist()))
    assert got == [(-10.0, 0.0), (-10.0, 10.0)]  # others minus the asker: never its own position


def test_moves_are_taken_once_from_active_robots_that_looked(tmp_path: FsPath) -> None:
    w = _world(tmp_path)
    _ctl(w, Begin(1, (0, 1)).encode())
    step = Path((Line((1.0, 0.0)),))
    assert _move(w, 0, 0, 1, step) is False  # has not looked yet
    look_bytes(w, snapshot_key(SWARM, 0))
    look_bytes(w, snapshot_key(SWARM, 1))
    assert _move(w, 0, 1, 1, step) is False  # names someone else
    assert _move(w, 2, 2, 1, step) is False  # not active
    assert _move(w, 0, 0, 2, step) is False  # not the open round
    assert move_bytes(w, move_key(SWARM, 0), b"\x00garbage") is False
    assert _move(w, 0, 0, 1, step) is True
    assert _move(w, 0, 0, 1, STAY) is False  # a second move for the round
    assert set(w.rejected) == {
        "move-without-look",
        "move-wrong-robot",
        "move-not-active",
        "move-wrong-round",
        "move-garbage",
        "move-duplicate",
    }
    reply = _ctl(w, Commit(1).encode())
    assert reply.ok and reply.committed == 1
    assert w.positions[0].tolist() == [1.0, 0.0]  # translated by the robot's own position
    assert w.positions[1].tolist() == [10.0, 0.0]  # looked, never moved: stays
    assert w.timeouts == [0, 1, 0]
    assert _move(w, 0, 0, 1, step) is False  # a replay of an old round


def _looked_and_moved(world: WorldCore, *robots: int, path: Path = STAY) -> None:
    for robot in robots:
        assert look_bytes(world, snapshot_key(SWARM, robot)) is not None
        assert _move(world, robot, robot, world.open_round, path)


def _live(world: WorldCore, *robots: int) -> WorldCore:
    for robot in robots:
        world.set_alive(robot, True)
    return world


def test_the_moves_notice_comes_once_when_every_live_active_robot_has_moved(
    tmp_path: FsPath,
) -> None:
    w = _live(_world(tmp_path), 0, 1, 2)
    assert w.moves_notice() is None  # no round open
    assert _ctl(w, Begin(1, (0, 2)).encode()).ok
    assert w.moves_notice() is None  # nobody has moved yet
    _looked_and_moved(w, 2)
    assert w.moves_notice() is None  # robot 0 is live and has not moved
    _looked_and_moved(w, 0)
    assert w.moves_notice() == MovesHeld(1, (0, 2))
    assert w.moves_notice() is None  # not twice
    assert _ctl(w, Commit(1).encode()).ok
    assert w.moves_notice() is None  # the round is committed
    assert _ctl(w, Begin(2, (0, 2)).encode()).ok
    _looked_and_moved(w, 0, 2)
    assert w.moves_notice() == MovesHeld(2, (0, 2))  # the same robots, another round


def test_a_robot_whose_agent_is_not_up_is_not_waited_for(tmp_path: FsPath) -> None:
    w = _live(_world(tmp_path), 0)  # robot 1's agent never came
    assert _ctl(w, Begin(1, (0, 1)).encode()).ok
    _looked_and_moved(w, 0)
    assert w.moves_notice() == MovesHeld(1, (0,))


def test_a_robot_gone_mid_round_is_not_waited_for_and_a_late_move_is_noticed_again(
    tmp_path: FsPath,
) -> None:
    w = _live(_world(tmp_path), 0, 1, 2)
    assert _ctl(w, Begin(1, (0, 1, 2)).encode()).ok
    _looked_and_moved(w, 0, 1)
    look_bytes(w, snapshot_key(SWARM, 2))
    assert w.moves_notice() is None
    assert w.set_alive(2, False)  # its agent goes away before it moves
    assert w.moves_notice() == MovesHeld(1, (0, 1))
    assert _move(w, 2, 2, 1, STAY)  # its move was on its way: it is held, and noticed
    assert w.moves_notice() == MovesHeld(1, (0, 1, 2))
    assert w.moves_notice() is None


def test_a_robot_back_mid_round_is_waited_for_again(tmp_path: FsPath) -> None:
    w = _live(_world(tmp_path), 0, 1)
    assert _ctl(w, Begin(1, (0, 1)).encode()).ok
    _looked_and_moved(w, 0)
    w.set_alive(1, False)
    w.set_alive(1, True)  # back before the notice was asked for
    assert w.moves_notice() is None
    _looked_and_moved(w, 1)
    assert w.moves_notice() == MovesHeld(1, (0, 1))


def test_a_robot_that_moved_then_left_does_not_hold_back_the_notice(tmp_path: FsPath) -> None:
    w = _live(_world(tmp_path), 0, 1)
    assert _ctl(w, Begin(1, (0, 1)).encode()).ok
    _looked_and_moved(w, 0)
    w.set_alive(0, False)
    w.set_alive(0, True)  # it comes back: its move is held already
    _looked_and_moved(w, 1)
    assert w.moves_notice() == MovesHeld(1, (0, 1))


def test_a_world_restarted_mid_round_waits_for_the_moves_of_the_reopened_round(
    tmp_path: FsPath,
) -> None:
    w = _live(_world(tmp_path), 0, 1)
    assert _ctl(w, Begin(1, (0, 1)).encode()).ok
    _looked_and_moved(w, 0, 1)
    _close(w)
    again = _live(_world(tmp_path), 0, 1)  # the open round and its moves are lost
    assert _ctl(again, Begin(1, (0, 1)).encode()).ok
    assert again.moves_notice() is None
    _looked_and_moved(again, 0, 1)
    assert again.moves_notice() == MovesHeld(1, (0, 1))


def test_may_look_only_while_active_in_the_open_round_and_not_moved(tmp_path: FsPath) -> None:
    w = _live(_world(tmp_path), 0, 1, 2)
    assert not any(w.may_look(r) for r in range(3))  # no round open
    assert _ctl(w, Begin(1, (0, 1)).encode()).ok
    assert [w.may_look(r) for r in range(3)] == [True, True, False]
    assert look_bytes(w, snapshot_key(SWARM, 0)) is not None
    assert w.may_look(0)  # looking is not moving: it may look again
    assert _move(w, 0, 0, 1, STAY)
    assert [w.may_look(r) for r in range(3)] == [False, True, False]
    assert _ctl(w, Commit(1).encode()).ok
    assert not any(w.may_look(r) for r in range(3))
    assert _ctl(w, Begin(2, (0, 2)).encode()).ok
    assert [w.may_look(r) for r in range(3)] == [True, False, True]


def test_lookers_are_the_robots_that_may_look_each(tmp_path: FsPath) -> None:
    w = _live(_world(tmp_path), 0, 1, 2)

    def each(robots: tuple[int, ...]) -> list[int]:
        return [r for r in robots if w.may_look(r)]

    assert w.lookers((0, 1, 2)) == [] == each((0, 1, 2))  # no round open
    assert _ctl(w, Begin(1, (0, 2)).encode()).ok
    for robots in [w.active, (0, 2), (0, 1, 2), (2,), ()]:  # a round just opened
        assert list(w.lookers(robots)) == each(robots)
    assert w.lookers(w.active) is w.active == (0, 2)  # the round's own tuple: nothing to copy
    assert look_bytes(w, snapshot_key(SWARM, 2)) is not None
    assert _move(w, 2, 2, 1, STAY)
    for robots in [w.active, (0, 1, 2), (2, 0)]:  # robot 2 moved: it looks no more
        assert list(w.lookers(robots)) == each(robots) == [r for r in robots if r == 0]


def test_a_look_after_a_round_waits_for_a_later_one_unless_another_world_answered_it(
    tmp_path: FsPath,
) -> None:
    w = _live(_world(tmp_path), 0, 1)
    assert _ctl(w, Begin(1, (0, 1)).encode()).ok
    assert not w.may_look(0, LookRequest(epoch=w.epoch, after=1))  # it moved in round 1 here
    assert w.may_look(0, LookRequest(epoch=w.epoch + 1, after=1))  # a world that lost round 1
    assert w.may_look(0, LookRequest(epoch=w.epoch, after=0))
    assert _ctl(w, Commit(1, then_active=(0,)).encode()).open_round == 2
    assert w.may_look(0, LookRequest(epoch=w.epoch, after=1))


def test_a_commit_with_the_next_active_set_commits_and_opens_the_next_round(
    tmp_path: FsPath,
) -> None:
    w = _live(_world(tmp_path), 0, 1, 2)
    assert _ctl(w, Begin(1, (0, 1)).encode()).ok
    _looked_and_moved(w, 0, path=Path((Line((1.0, 0.0)),)))
    reply, changed = control_bytes(w, Commit(1, (1,), then_active=(1, 2)).encode())
    assert changed and reply.ok and (reply.committed, reply.open_round) == (1, 2)
    assert reply.held == () and reply.status == "running"
    assert reply.timed_out == (1,)  # of the round it committed: robot 1 sent no move
    assert w.positions[0].tolist() == [1.0, 0.0]  # round 1's move applied
    assert (w.open_round, w.active) == (2, (1, 2))
    assert [w.may_look(r) for r in range(3)] == [False, True, True]
    assert _ctl(w, Begin(2, (1, 2)).encode()).ok  # the same Begin again keeps it
    _looked_and_moved(w, 1, 2)
    assert w.moves_notice() == MovesHeld(2, (1, 2))
    last = _ctl(w, Commit(2).encode())
    assert last.committed == 2 and last.timed_out == ()
    _close(w)
    assert [(r.round, r.active) for r in read_record(tmp_path / "state.jsonl").rounds] == [
        (1, (0, 1)),
        (2, (1, 2)),
    ]


def test_a_commit_that_ends_the_run_opens_no_next_round(tmp_path: FsPath) -> None:
    w = _keep(open_world(str(tmp_path / "s.jsonl"), lambda: _setup(max_rounds=1), SWARM, None))
    assert _ctl(w, Begin(1, (0, 1, 2)).encode()).ok
    reply = _ctl(w, Commit(1, then_active=(0, 1, 2)).encode())
    assert reply.ok and reply.status != "running"
    assert (reply.committed, reply.open_round, w.open_round) == (1, 0, 0)
    assert not any(w.may_look(r) for r in range(3))


def test_a_chained_commit_sent_again_is_refused_and_changes_nothing(tmp_path: FsPath) -> None:
    w = _live(_world(tmp_path), 0, 1)
    assert _ctl(w, Begin(1, (0, 1)).encode()).ok
    chained = Commit(1, then_active=(0, 1)).encode()
    assert _ctl(w, chained).open_round == 2
    _looked_and_moved(w, 0)
    reply, changed = control_bytes(w, chained)
    assert not reply.ok and not changed
    assert (w.committed, w.open_round, set(w.held)) == (1, 2, {0})


def test_control_refuses_out_of_order_rounds_and_is_idempotent(tmp_path: FsPath) -> None:
    w = _world(tmp_path)
    assert not _ctl(w, Begin(2, (0,)).encode()).ok
    assert not _ctl(w, Commit(1).encode()).ok
    assert _ctl(w, Begin(1, (0,)).encode()).ok
    assert _ctl(w, Begin(1, (0,)).encode()).ok  # a coordinator retrying
    assert _ctl(w, Commit(1).encode()).ok
    again = _ctl(w, Commit(1).encode())  # its reply was lost: still fine, nothing re-applied
    assert again.ok and again.committed == 1
    assert not _ctl(w, b"\xff\xfe").ok
    hello = _ctl(w, Hello().encode())
    assert (hello.committed, hello.open_round, hello.status) == (1, 0, "running")


def test_committed_rounds_survive_a_restart_and_a_torn_line(tmp_path: FsPath) -> None:
    w = _world(tmp_path)
    for r in (1, 2):
        _ctl(w, Begin(r, (0,)).encode())
        look_bytes(w, snapshot_key(SWARM, 0))
        _move(w, 0, 0, r, Path((Line((1.0, 0.0)),)))
        _ctl(w, Commit(r).encode())
    _ctl(w, Begin(3, (0,)).encode())  # open but never committed: not durable, not announced
    _close(w)
    state = tmp_path / "state.jsonl"
    with open(state, "a", encoding="utf-8") as f:
        f.write('{"type":"round","rou')  # died mid-write
    again = _world(tmp_path)
    assert again.committed == 2 and again.open_round == 0
    assert again.positions[0].tolist() == [2.0, 0.0]
    assert again.last_active[0] == 2
    assert _ctl(again, Begin(3, (1,)).encode()).ok
    assert _ctl(again, Commit(3).encode()).ok
    _close(again)
    record = read_record(state)
    assert [r.round for r in record.rounds] == [1, 2, 3]


def test_the_run_ends_at_max_rounds_with_a_result_line(tmp_path: FsPath) -> None:
    w = _keep(open_world(str(tmp_path / "s.jsonl"), lambda: _setup(max_rounds=1), SWARM, None))
    _ctl(w, Begin(1, (0, 1, 2)).encode())
    reply = _ctl(w, Commit(1).encode())
    assert reply.status in ("stalled", "max_rounds")
    assert not _ctl(w, Begin(2, (0,)).encode()).ok
    _close(w)
    result = read_record(tmp_path / "s.jsonl").result
    assert result is not None and result.status == reply.status


@pytest.mark.parametrize("alive", [True, False])
def test_liveliness_shows_in_the_state(tmp_path: FsPath, alive: bool) -> None:
    w = _world(tmp_path)
    assert w.set_alive(2, alive) is alive
    assert w.state().agents[2].alive is alive
    assert not w.set_alive(99, True)


def _opened(path: FsPath) -> WorldCore:
    """The world of the state file `path` (resumed if it holds rounds), closed after the test."""
    w = _keep(open_world(str(path), lambda: _setup(max_rounds=200), SWARM, None))
    return w


def _rounds(w: WorldCore, count: int, active: tuple[int, ...] = (0, 1)) -> None:
    """`count` rounds in which `active` look and stay."""
    for _ in range(count):
        r = w.committed + 1
        assert _ctl(w, Begin(r, active).encode()).ok
        for robot in active:
            look_bytes(w, snapshot_key(SWARM, robot))
            _move(w, robot, robot, r, STAY)
        _ctl(w, Commit(r).encode())


def test_a_robot_whose_agent_stays_gone_counts_as_crashed_and_is_not_waited_for(
    tmp_path: FsPath,
) -> None:
    w = _opened(tmp_path / "s.jsonl")
    for robot in (0, 1, 2):
        w.set_alive(robot, True)
    w.set_alive(2, False)  # gone after round 0, for good
    limit = crash_after(3)
    _rounds(w, limit - 1)
    assert w.status == "running" and not w.tracker.crashed  # waited for: the run goes on
    _rounds(w, 1)
    assert w.tracker.crashed == {2}
    # robots 0 and 1 stay, robot 2 counts as staying: everyone has been seen since the last change
    assert w.status == "stalled"  # START is no uniform circle
    _close(w)
    rounds = read_record(tmp_path / "s.jsonl").rounds
    assert [r.round for r in rounds if "crashed" in r.extra] == [limit]
    assert rounds[limit - 1].extra["crashed"] == [2]
    again = _opened(tmp_path / "s.jsonl")
    assert again.tracker.crashed == {2} and again.status == "stalled"  # replayed from the record


def test_a_crashed_robot_whose_agent_comes_back_is_waited_for_again(tmp_path: FsPath) -> None:
    w = _opened(tmp_path / "s.jsonl")
    w.set_alive(0, True)
    w.set_alive(1, True)  # robot 2 never comes: gone since round 0
    _rounds(w, crash_after(3) - 1, active=(0,))  # robot 1 never active: nobody is stalled yet
    _rounds(w, 1, active=(0,))
    assert w.tracker.crashed == {2}
    w.set_alive(2, True)
    _rounds(w, 1, active=(0,))
    assert not w.tracker.crashed
    _close(w)
    assert read_record(tmp_path / "s.jsonl").rounds[-1].extra["recovered"] == [2]


def test_a_world_that_never_hears_of_agents_does_not_crash_them_on_resume(
    tmp_path: FsPath,
) -> None:
    w = _opened(tmp_path / "s.jsonl")
    for robot in (0, 1, 2):
        w.set_alive(robot, True)
    _rounds(w, crash_after(3) + 2, active=(0,))
    _close(w)
    # its agents' tokens have not come yet: they are not gone since round 0
    again = _opened(tmp_path / "s.jsonl")
    _rounds(again, 1, active=(0,))
    assert not again.tracker.crashed


def test_a_round_opened_again_with_another_set_is_noticed_again(tmp_path: FsPath) -> None:
    w = _live(_world(tmp_path), 0, 1)
    assert _ctl(w, Begin(1, (0, 1)).encode()).ok
    _looked_and_moved(w, 0, 1)
    assert w.moves_notice() == MovesHeld(1, (0, 1))  # to a coordinator that dies before its commit
    w.set_alive(2, True)
    assert _ctl(w, Begin(1, (0, 1, 2)).encode()).ok and not w.held  # the next coordinator's plan
    _looked_and_moved(w, 0, 1)
    w.set_alive(2, False)  # robot 2's agent goes away before it moves
    assert w.moves_notice() == MovesHeld(1, (0, 1))


def test_a_chained_commit_naming_robots_not_of_the_run_is_refused_whole(tmp_path: FsPath) -> None:
    w = _live(_world(tmp_path), 0, 1)
    assert _ctl(w, Begin(1, (0, 1)).encode()).ok
    reply = _ctl(w, Commit(1, then_active=(0, 99)).encode())
    assert not reply.ok and w.committed == 0 and w.open_round == 1  # nothing half done
