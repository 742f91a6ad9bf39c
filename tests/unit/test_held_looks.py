"""The world shell's held Looks, with fake queries: the answer to a held Look is the activation."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path as FsPath

import numpy as np
import pytest
import zenoh

from fatswarm.domain.path import STAY, Line, Path
from fatswarm.world.core import WorldCore
from fatswarm.world.journal import open_world
from fatswarm.world.protocol import (
    Begin,
    Commit,
    LookRequest,
    MoveSubmitted,
    Snapshot,
    snapshot_key,
)
from fatswarm.world.service import HOLD_LOOK_S, HeldLooks
from fatswarm.world.setup import WorldSetup

SWARM = "t"
START = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]])
FIRST = LookRequest()


class FakeQuery:
    """A Look query as the shell sees it: its key, what it was answered, how often it was
    dropped. `fail` makes its reply raise as Zenoh does when the asker has gone."""

    def __init__(self, robot: int, fail: bool = False) -> None:
        self.key_expr = snapshot_key(SWARM, robot)
        self.payload = None
        self.fail = fail
        self.replies: list[bytes] = []
        self.errors: list[bytes] = []
        self.drops = 0

    def reply(self, key: str, data: bytes) -> None:
        assert key == self.key_expr and self.drops == 0, "answered after it was let go"
        if self.fail:
            raise zenoh.ZError("the asker is gone")
        self.replies.append(data)

    def reply_err(self, data: bytes) -> None:
        assert self.drops == 0, "answered after it was let go"
        self.errors.append(data)

    def drop(self) -> None:
        self.drops += 1

    @property
    def answered_round(self) -> int | None:
        return Snapshot.decode(self.replies[0]).round if self.replies else None


@pytest.fixture
def world(tmp_path: FsPath) -> Iterator[WorldCore]:
    setup = WorldSetup(SWARM, 3, 1, "ssync", START, 50, params={"a": 4.0})
    core, journal = open_world(str(tmp_path / "state.jsonl"), lambda: setup, SWARM, None, epoch=7)
    for robot in range(3):
        core.set_alive(robot, True)
    yield core
    journal.close()


def _open(core: WorldCore, *active: int) -> None:
    reply, changed = core.control(Begin(core.committed + 1, active))
    assert reply.ok and changed


def test_a_newer_look_replaces_the_held_one_which_is_let_go_unanswered() -> None:
    looks, old, new = HeldLooks(), FakeQuery(0), FakeQuery(0)
    looks.hold(0, old, FIRST, 0.0)
    looks.hold(0, new, FIRST, 1.0)
    assert len(looks) == 1
    assert (old.drops, old.replies, old.errors) == (1, [], [])
    assert new.drops == 0


def test_answer_ready_answers_only_the_robots_that_may_look(world: WorldCore) -> None:
    looks = HeldLooks()
    queries = [FakeQuery(r) for r in range(3)]
    for robot, query in enumerate(queries):
        looks.hold(robot, query, FIRST, 0.0)
    looks.answer_ready(world)  # no round open: nobody is activated
    assert len(looks) == 3 and not any(q.replies or q.drops for q in queries)
    _open(world, 0, 2)
    looks.answer_ready(world)
    assert [q.answered_round for q in queries] == [1, None, 1]
    assert [q.drops for q in queries] == [1, 0, 1] and len(looks) == 1


def test_a_look_after_the_round_its_robot_moved_in_waits_for_the_next_round(
    world: WorldCore,
) -> None:
    _open(world, 0, 1)
    assert world.look(0) is not None
    assert world.move(0, MoveSubmitted(0, 1, STAY))
    looks, again, other_world = HeldLooks(), FakeQuery(0), FakeQuery(1)
    looks.hold(0, again, LookRequest(epoch=7, after=1), 0.0)  # its next Look overtook nothing
    looks.hold(1, other_world, LookRequest(epoch=3, after=1), 0.0)  # a round 1 of another world
    looks.answer_ready(world)
    assert again.drops == 0 and other_world.answered_round == 1
    reply, changed = world.control(Commit(1, then_active=(0, 2)))
    assert reply.ok and changed and world.open_round == 2
    looks.answer_ready(world)
    assert again.answered_round == 2 and len(looks) == 0


def test_expire_lets_go_only_the_looks_held_too_long() -> None:
    looks, old, young = HeldLooks(), FakeQuery(0), FakeQuery(1)
    looks.hold(0, old, FIRST, 0.0)
    looks.hold(1, young, FIRST, 5.0)
    looks.expire(HOLD_LOOK_S)  # not longer than HOLD_LOOK_S yet
    assert len(looks) == 2
    looks.expire(HOLD_LOOK_S + 1.0)
    assert (old.drops, old.replies, young.drops) == (1, [], 0) and len(looks) == 1


def test_every_held_look_is_dropped_exactly_once(world: WorldCore) -> None:
    looks = HeldLooks()
    queries = [FakeQuery(0), FakeQuery(0), FakeQuery(1, fail=True), FakeQuery(2), FakeQuery(2)]
    looks.hold(0, queries[0], FIRST, 0.0)
    looks.hold(0, queries[1], FIRST, 1.0)  # replaces the first
    looks.hold(1, queries[2], FIRST, 0.0)  # its agent has gone: the reply fails
    looks.hold(2, queries[3], FIRST, 0.0)
    _open(world, 0, 1)
    looks.answer_ready(world)  # answers robot 0, tries robot 1
    looks.expire(HOLD_LOOK_S + 0.5)  # lets robot 2's first go
    looks.hold(2, queries[4], FIRST, HOLD_LOOK_S)
    looks.let_go_all()
    assert [q.drops for q in queries] == [1] * 5 and len(looks) == 0
    assert [q.answered_round for q in queries] == [None, 1, None, None, None]


class FakePublisher:
    def __init__(self) -> None:
        self.sent: list[bytes] = []

    def put(self, data: bytes) -> None:
        self.sent.append(data)


def _look_with(robot: int, request: LookRequest) -> FakeQuery:
    query = FakeQuery(robot)
    query.payload = zenoh.ZBytes(request.encode())  # type: ignore[assignment]
    return query


def test_a_look_that_carries_the_robots_move_delivers_it_and_is_held_for_the_next_round(
    world: WorldCore,
) -> None:
    from fatswarm.world.service import _take_look

    looks, notices = HeldLooks(), FakePublisher()
    _open(world, 0, 1)
    for robot in (0, 1):
        first = _look_with(robot, FIRST)
        _take_look(world, first, looks, notices)
        assert first.answered_round == 1
    move = MoveSubmitted(0, 1, STAY).encode()
    # another robot's move in robot 1's Look is refused
    _take_look(world, _look_with(1, LookRequest(world.epoch, 1, move)), looks, notices)
    assert world.held == {} and world.rejected["move-wrong-robot"] == 1
    carrying = _look_with(0, LookRequest(world.epoch, 1, move))
    _take_look(world, carrying, looks, notices)
    assert world.held == {0: STAY} and carrying.replies == [] and len(looks) == 2
    assert notices.sent == []  # robot 1 has not moved yet
    # the agent sends its move again with every Look until one is answered: no news, no word
    _take_look(world, _look_with(0, LookRequest(world.epoch, 1, move)), looks, notices)
    assert world.held == {0: STAY} and sum(world.rejected.values()) == 1
    _take_look(
        world,
        _look_with(1, LookRequest(world.epoch, 1, MoveSubmitted(1, 1, STAY).encode())),
        looks,
        notices,
    )
    assert len(notices.sent) == 1  # every active robot moved: one notice
    assert world.control(Commit(1))[0].ok
    # and a move of a round no longer open, sent again with a Look, is dropped quietly too (these
    # Looks come far quicker than an agent's, which the world takes for two sessions: not a move)
    _take_look(world, _look_with(0, LookRequest(world.epoch, 1, move)), looks, notices)
    assert world.rejected == {"move-wrong-robot": 1, "look-two-sessions": 1}


def test_a_late_move_and_another_move_for_a_round_already_moved_in_are_refused_and_counted(
    world: WorldCore,
) -> None:
    from fatswarm.world.service import _take_look

    looks, notices = HeldLooks(), FakePublisher()
    _open(world, 0, 1)
    for robot in (0, 1):
        _take_look(world, _look_with(robot, FIRST), looks, notices)
    move = MoveSubmitted(0, 1, STAY).encode()
    _take_look(world, _look_with(0, LookRequest(world.epoch, 1, move)), looks, notices)
    other = MoveSubmitted(0, 1, Path((Line((1.0, 0.0)),))).encode()  # a second session's
    _take_look(world, _look_with(0, LookRequest(world.epoch, 1, other)), looks, notices)
    assert world.held == {0: STAY} and world.rejected["move-already-moved"] == 1
    # robot 1 sends nothing in time: the round is committed without it (its move timeout)
    assert world.control(Commit(1))[0].ok
    late = MoveSubmitted(1, 1, STAY).encode()
    looks.taken[1] = (0, b"")  # (a move this world took from robot 1 before)
    _take_look(world, _look_with(1, LookRequest(world.epoch, 1, late)), looks, notices)
    assert world.rejected["move-round-closed"] == 1
    # a move for a round not open yet is refused as before
    ahead = MoveSubmitted(1, 9, STAY).encode()
    _take_look(world, _look_with(1, LookRequest(world.epoch, 1, ahead)), looks, notices)
    assert world.rejected["move-wrong-round"] == 1


def test_looks_of_one_robot_from_two_sessions_are_said_once() -> None:
    looks = HeldLooks()
    # its own agent asks again after LOOK_WAIT_S: never two sessions
    assert not any(looks.hold(0, FakeQuery(0), FIRST, 3.0 * k) for k in range(10))
    # one quick Look (an agent whose Look failed asks again at once): still one session
    assert not looks.hold(0, FakeQuery(0), FIRST, 30.05)
    assert not looks.hold(0, FakeQuery(0), FIRST, 33.05)
    # two sessions: each one's agent asks again as soon as the other takes its place
    said = [looks.hold(0, FakeQuery(0), FIRST, 40.0 + 0.05 * k) for k in range(100)]
    assert said.count(True) == 1 and looks.shared == {0}
    assert not looks.hold(1, FakeQuery(1), FIRST, 50.0)  # the other robots are not
