"""The coordinator's round state machine against a fake world on a fake clock (no Zenoh)."""

from __future__ import annotations

import ast
import inspect
import itertools
from collections import deque
from collections.abc import Sequence
from dataclasses import replace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.coordinator import rounds
from fatswarm.coordinator.rounds import (
    Action,
    Ask,
    CoordinatorCore,
    CoreMisuse,
    Finished,
    Note,
    Phase,
    RoundTimes,
)
from fatswarm.coordinator.schedule import Scheduler, make_scheduler
from fatswarm.domain.outcome import ExitCode, Status, exit_code_for
from fatswarm.world.protocol import Begin, Commit, ControlReply, Hello, MovesHeld

Request = Hello | Begin | Commit
TIMES = RoundTimes(
    move_timeout_s=5.0, start_timeout_s=120.0, resume_grace_s=2.0, pace_s=0.0, retry_s=0.25
)


class FakeWorld:
    """Answers Hello, Begin and Commit as the world does; the run ends after `end_after` commits.

    A Commit with `then_active` commits and, if the run goes on, opens the next round with that
    set. `notice()` is the world's one `MovesHeld` a round, due once every active robot whose agent
    is alive has moved (again only if a late move joins them).

    `fail(kind, how)` makes the next request of that kind fail: "refuse" (ok=False), "none" (no
    answer) or "lost" (applied, but the answer never arrives). `restart()` loses the open round.
    """

    def __init__(
        self,
        n: int,
        end_after: int = 3,
        end_status: Status = Status.FORMED,
        committed: int = 0,
        collisions: int = 0,
    ) -> None:
        self.n, self.end_after, self.end_status = n, end_after, end_status
        self.committed, self.collisions = committed, collisions
        self.status = Status.RUNNING if committed < end_after else end_status
        self.open_round = 0
        self.active: tuple[int, ...] = ()
        self.held: set[int] = set()
        self.alive: set[int] = set()  # robots whose agent the world knows to be up
        self.noticed: MovesHeld | None = None
        self.epoch = 1  # the world process (MovesHeld.epoch)
        self.faults: list[tuple[str, str]] = []
        self.requests: list[Request] = []
        self.opened: list[tuple[int, tuple[int, ...]]] = []  # every round opened anew, with its set
        self.applied: list[tuple[Commit, tuple[int, ...]]] = []  # and the world's timed out

    def fail(self, kind: str, how: str) -> None:
        self.faults.append((kind, how))

    def restart(self) -> None:
        self.open_round, self.active, self.held, self.noticed = 0, (), set(), None
        self.epoch += 1  # another world process

    def set_alive(self, robot: int, up: bool) -> None:
        if 0 <= robot < self.n:
            (self.alive.add if up else self.alive.discard)(robot)

    def hold(self, robot: int) -> bool:
        """An agent's move: held if the robot is active in the open round and has not moved."""
        if self.open_round and robot in self.active and robot not in self.held:
            self.held.add(robot)
            return True
        return False

    def notice(self) -> MovesHeld | None:
        """The moves notice due now, if any (never the same one twice)."""
        if not self.open_round or any(r in self.alive - self.held for r in self.active):
            return None
        notice = MovesHeld(self.open_round, tuple(sorted(self.held)), self.epoch)
        if notice == self.noticed:
            return None
        self.noticed = notice
        return notice

    def reply(self, ok: bool, reason: str = "") -> ControlReply:
        return ControlReply(
            ok=ok,
            reason=reason,
            n=self.n,
            committed=self.committed,
            open_round=self.open_round,
            status=self.status,
            collisions=self.collisions,
            held=tuple(sorted(self.held)) if self.open_round else (),
            epoch=self.epoch,
        )

    def answer(self, req: Request) -> ControlReply | None:
        self.requests.append(req)
        kind = type(req).__name__.lower()
        how = next((h for k, h in self.faults if k == kind), None)
        if how is not None:
            self.faults.remove((kind, how))
        if how == "refuse":
            return self.reply(False, f"{kind} refused")
        if how == "none":
            return None
        reply = self._apply(req)
        return None if how == "lost" else reply

    def _apply(self, req: Request) -> ControlReply:
        if isinstance(req, Hello):
            return self.reply(True)
        if self.status != Status.RUNNING:
            return self.reply(False, f"the run has ended ({self.status})")
        if isinstance(req, Begin):
            return self._begin(req)
        if req.round == self.committed and not self.open_round:
            return self.reply(True)  # the answer to a commit was lost: it is durable
        if req.round != self.open_round:
            return self.reply(False, f"round {req.round} is not open")
        missed = tuple(r for r in self.active if r not in self.held)
        self.applied.append((req, missed))
        self.committed, self.open_round, self.active, self.held = req.round, 0, (), set()
        if self.committed >= self.end_after:
            self.status = self.end_status
        then = req.then
        if then is not None and self.status == Status.RUNNING:
            return replace(self._begin(then), timed_out=missed)
        return replace(self.reply(True), timed_out=missed)

    def _begin(self, req: Begin) -> ControlReply:
        if req.round != self.committed + 1:
            return self.reply(False, f"next round is {self.committed + 1}")
        if (self.open_round, self.active) != (req.round, req.active):
            self.open_round, self.active, self.held = req.round, req.active, set()
            self.noticed = None
            self.opened.append((req.round, req.active))
        return self.reply(True)


class Recording:
    """A scheduler that remembers which rounds it was asked for, in order, and what it said."""

    def __init__(self, inner: Scheduler) -> None:
        self.inner, self.name = inner, inner.name
        self.asked: list[int] = []
        self.said: dict[int, tuple[int, ...]] = {}

    def active(self, round_no: int, live: Sequence[int]) -> list[int]:
        out = self.inner.active(round_no, live)
        self.asked.append(round_no)
        self.said[round_no] = tuple(out)
        return out


class Drive:
    """A core, a fake world and a fake clock.

    The world holds every agent's Look: when a request opens a round (or opens it again), each
    active robot whose agent is up moves at once, unless it is `silent` or `auto_move` is off. The
    world's moves notices reach the core as events, after the actions of the reply in hand.
    """

    def __init__(
        self,
        world: FakeWorld,
        scheduler: str = "fsync",
        seed: int = 7,
        times: RoundTimes = TIMES,
        resume_live: Sequence[int] | None = None,
    ) -> None:
        self.world, self.times, self.now = world, times, 0.0
        self.schedulers: list[Recording] = []
        self.core = CoordinatorCore(
            lambda n: self._recording(make_scheduler(scheduler, n, seed)), times, resume_live
        )
        self.auto_move = True
        self.agents: set[int] = set()  # robots whose agent is up
        self.silent: set[int] = set()
        self.notices: deque[MovesHeld] = deque()  # sent by the world, not yet seen by the core
        self.opened: list[tuple[float, int, tuple[int, ...]]] = []  # when the world opened what
        self.collecting_since: dict[int, float] = {}  # round -> when a reply last opened it
        self.finished: Finished | None = None

    def _recording(self, scheduler: Scheduler) -> Recording:
        self.schedulers.append(Recording(scheduler))
        return self.schedulers[-1]

    @property
    def scheduler(self) -> Recording:
        (only,) = self.schedulers
        return only

    def perform(self, actions: list[Action]) -> None:
        todo = deque(actions)
        while todo or self.notices:
            if not todo:
                todo.extend(self.core.on_held(self.notices.popleft(), self.now))
                continue
            action = todo.popleft()
            if isinstance(action, Ask):
                assert not todo, "an Ask is the last action of a list"
                todo.extend(self.core.on_reply(self._ask(action.request), self.now))
            else:
                assert self.finished is None
                self.finished = action

    def _ask(self, request: Request) -> ControlReply | None:
        world = self.world
        opened = len(world.opened)
        reply = world.answer(request)
        if reply is not None and reply.ok and reply.open_round and not isinstance(request, Hello):
            self.collecting_since[reply.open_round] = self.now
        if len(world.opened) > opened:  # the held Looks are answered: the agents act
            self.opened.append((self.now, world.open_round, world.active))
            for robot in world.active if self.auto_move else ():
                if robot in self.agents and robot not in self.silent:
                    self._world_move(robot)
        return reply

    def _world_move(self, robot: int) -> None:
        if self.world.hold(robot):
            self._world_notice()

    def _world_notice(self) -> None:
        notice = self.world.notice()
        if notice is not None:
            self.notices.append(notice)

    def start(self, *alive: int) -> Drive:
        self.perform(self.core.start(self.now))
        self.alive(*alive)
        return self

    def alive(self, *robots: int, up: bool = True, world_first: bool = False) -> None:
        """Agents' tokens appear (or go away): the core and the world hear of it, in that order
        unless `world_first`."""
        for robot in robots:
            (self.agents.add if up else self.agents.discard)(robot)
            if world_first:
                self.world.set_alive(robot, up)
                self._world_notice()
                self.perform([])
            self.perform(self.core.on_alive(robot, up, self.now))
            if not world_first:
                self.world.set_alive(robot, up)
                self._world_notice()
                self.perform([])

    def move(self, robot: int) -> None:
        self._world_move(robot)
        self.perform([])

    def tick(self, now: float) -> None:
        self.now = max(self.now, now)
        self.perform(self.core.on_tick(self.now))
        deadline = self.core.next_deadline()
        assert deadline is None or deadline > self.now, "a deadline that has passed stays"

    def wait(self, dt: float) -> None:
        """Let `dt` seconds pass, ticking the core at each of its deadlines on the way."""
        until = self.now + dt
        while (d := self.core.next_deadline()) is not None and d <= until:
            self.tick(d)
        self.now = until

    def run(self, steps: int = 1000) -> Finished:
        """Tick at each deadline until the run ends."""
        for _ in range(steps):
            if self.finished is not None:
                return self.finished
            deadline = self.core.next_deadline()
            assert deadline is not None, f"stuck in {self.core.phase} with nothing to wait for"
            self.tick(deadline)
        raise AssertionError("the run did not end")

    def begins(self) -> list[Begin]:
        return [r for r in self.world.requests if isinstance(r, Begin)]

    def commits(self) -> list[Commit]:
        return [r for r in self.world.requests if isinstance(r, Commit)]

    def kinds(self) -> list[str]:
        return [type(r).__name__ for r in self.world.requests]


def test_the_core_imports_no_zenoh_clock_threads_or_logging() -> None:
    tree = ast.parse(inspect.getsource(rounds))
    imported = {
        alias.name.split(".")[0]
        for node in ast.walk(tree)
        if isinstance(node, ast.Import)
        for alias in node.names
    }
    imported |= {
        (node.module or "").split(".")[0]
        for node in ast.walk(tree)
        if isinstance(node, ast.ImportFrom)
    }
    assert not imported & {"zenoh", "time", "threading", "logging", "asyncio", "random", "socket"}


# --- a whole run ------------------------------------------------------------------------------

ALL4 = (0, 1, 2, 3)


def test_a_full_fsync_run_ends_formed_after_the_worlds_last_commit() -> None:
    drive = Drive(FakeWorld(4, end_after=3)).start(*ALL4)
    assert drive.finished == Finished(Status.FORMED, 0)
    assert drive.world.requests == [
        Hello(),
        Begin(round=1, active=ALL4),
        *(Commit(round=k, timed_out=(), then_active=ALL4) for k in (1, 2, 3)),
    ]
    assert drive.world.opened == [(1, ALL4), (2, ALL4), (3, ALL4)]  # the last commit opens none
    assert [(at, r) for at, r, _ in drive.opened] == [(0.0, 1), (0.0, 2), (0.0, 3)]
    assert drive.now == 0.0  # nobody waited: every move came at once
    assert drive.core.phase is Phase.DONE and drive.core.next_deadline() is None
    assert drive.core.finished == drive.finished


def test_finished_carries_the_worlds_status_and_collisions() -> None:
    stalled = Drive(FakeWorld(2, end_after=2, end_status=Status.STALLED, collisions=3)).start(0, 1)
    assert stalled.finished == Finished(Status.STALLED, 3)
    formed = Drive(FakeWorld(2, end_after=1, collisions=2)).start(0, 1)
    assert formed.finished == Finished(Status.FORMED, 2)
    assert exit_code_for(formed.finished.status, formed.finished.collisions) == (
        ExitCode.FORMED_WITH_COLLISIONS
    )


def test_a_run_that_already_ended_finishes_at_the_first_hello_without_waiting_for_agents() -> None:
    drive = Drive(FakeWorld(3, end_after=5, committed=5, collisions=1)).start()
    assert drive.finished == Finished(Status.FORMED, 1)
    assert drive.world.requests == [Hello()]


def test_a_stopped_core_finishes_running_and_then_does_nothing() -> None:
    drive = Drive(FakeWorld(3)).start(0)  # waits for robots 1 and 2
    assert drive.core.stop() == Finished(Status.RUNNING, 0)
    assert exit_code_for(Status.RUNNING, 0) == ExitCode.NOT_FORMED
    assert drive.core.on_alive(1, True, 1.0) == [] and drive.core.on_tick(500.0) == []
    assert drive.core.stop() == Finished(Status.RUNNING, 0)


# --- chained commits --------------------------------------------------------------------------


def test_a_chained_commit_opens_the_next_round_with_one_request() -> None:
    world = FakeWorld(3, end_after=9)
    drive = Drive(world, scheduler="ssync", seed=5)
    drive.auto_move = False
    drive.start(0, 1, 2)
    first = drive.core.active
    for robot in first:
        drive.move(robot)
    (commit,) = drive.commits()
    assert commit.round == 1 and commit.then_active == drive.scheduler.said[2]
    assert world.requests == [Hello(), Begin(1, first), commit]  # no Begin for round 2
    assert world.committed == 1 and world.opened == [(1, first), (2, commit.then_active)]
    assert drive.core.phase is Phase.COLLECT and drive.core.round == 2
    assert drive.core.active == commit.then_active and drive.core.held == set()
    assert drive.core.next_deadline() == TIMES.move_timeout_s


def test_every_round_after_the_first_costs_one_request_and_asks_the_scheduler_once() -> None:
    drive = Drive(FakeWorld(5, end_after=8), scheduler="ssync", seed=3).start(*range(5))
    assert drive.finished == Finished(Status.FORMED, 0)
    assert drive.kinds() == ["Hello", "Begin"] + ["Commit"] * 8
    assert drive.scheduler.asked == list(range(1, 10))  # round 9 planned, never opened
    assert drive.world.opened == [(k, drive.scheduler.said[k]) for k in range(1, 9)]


def test_with_a_pace_the_commit_is_not_chained_and_a_begin_follows_at_the_pace_deadline() -> None:
    drive = Drive(FakeWorld(2, end_after=3), times=RoundTimes(pace_s=1.0)).start(0, 1)
    assert drive.world.requests == [Hello(), Begin(1, (0, 1)), Commit(1, (), then_active=())]
    assert drive.core.phase is Phase.PACE and drive.core.next_deadline() == 1.0
    drive.tick(0.5)
    assert len(drive.world.requests) == 3
    drive.tick(1.0)
    assert drive.world.requests[3:] == [Begin(2, (0, 1)), Commit(2, (), then_active=())]
    assert drive.core.next_deadline() == 2.0
    assert drive.scheduler.asked == [1, 2]  # the next round is planned when it begins


def test_a_round_longer_than_the_pace_is_chained_to_the_next() -> None:
    drive = Drive(FakeWorld(2, end_after=3), times=RoundTimes(pace_s=1.0))
    drive.silent = {1}
    drive.start(0, 1)
    drive.tick(5.0)  # round 1 timed out after 5 s > pace
    assert [b.round for b in drive.begins()] == [1]
    assert drive.commits()[0].then_active == (0, 1)
    assert drive.opened == [(0.0, 1, (0, 1)), (5.0, 2, (0, 1))]


def test_the_pace_counts_from_the_commit_that_opened_the_round() -> None:
    drive = Drive(FakeWorld(2, end_after=5), times=RoundTimes(pace_s=1.0))
    drive.silent = {1}
    drive.start(0, 1)
    drive.silent = set()
    drive.tick(5.0)  # round 1 timed out; its commit opens round 2 at 5.0, where both move at once
    assert drive.commits()[1] == Commit(2, (), then_active=())  # 5.0 < 5.0 + pace
    assert drive.core.phase is Phase.PACE and drive.core.next_deadline() == 6.0
    drive.tick(6.0)
    assert drive.begins()[1] == Begin(3, (0, 1))


def test_a_lost_reply_to_a_chained_commit_recovers_to_the_same_round_and_set() -> None:
    world = FakeWorld(4, end_after=6)
    world.fail("commit", "lost")  # round 1 is committed and round 2 opened; the reply is lost
    drive = Drive(world, scheduler="ssync", seed=9).start(*range(4))
    lost = drive.commits()[0]
    assert world.requests[:5] == [
        Hello(),
        Begin(1, drive.scheduler.said[1]),
        lost,
        Hello(),
        Begin(2, lost.then_active),
    ]
    # the world kept the moves it held for round 2: its commit came at once, with nobody missing
    assert world.applied[1] == (drive.commits()[1], ())
    assert drive.commits()[1] == Commit(2, (), then_active=drive.scheduler.said[3])
    assert drive.scheduler.asked == list(range(1, 8))  # each round once, in order
    assert drive.finished == Finished(Status.FORMED, 0) and drive.now == 0.0


def test_a_lost_chained_commit_request_is_sent_again_with_the_same_next_set() -> None:
    world = FakeWorld(4, end_after=6)
    world.fail("commit", "none")  # the world never saw it: round 1 is still open
    drive = Drive(world, scheduler="ssync", seed=9).start(*range(4))
    first, again = drive.commits()[:2]
    assert world.requests[:6] == [
        Hello(),
        Begin(1, drive.scheduler.said[1]),
        first,
        Hello(),
        Begin(1, drive.scheduler.said[1]),
        again,
    ]
    assert first == again and first.then_active == drive.scheduler.said[2]
    assert drive.scheduler.asked == list(range(1, 8))
    assert drive.finished == Finished(Status.FORMED, 0)


def test_a_world_that_opens_no_round_with_the_commit_is_sent_a_begin() -> None:
    # A reply that says the commit went through but no round is open (the commit was already
    # durable, its first reply lost): the core opens the next round itself, with the same set.
    world = FakeWorld(3, end_after=5)
    drive = Drive(world)
    drive.auto_move = False
    drive.start(0, 1, 2)
    world.committed, world.open_round, world.active, world.held = 1, 0, (), set()
    drive.tick(5.0)  # round 1 times out: Commit(1, then) finds it committed already
    assert world.requests[-2:] == [Commit(1, (0, 1, 2), then_active=(0, 1, 2)), Begin(2, (0, 1, 2))]
    assert drive.core.phase is Phase.COLLECT and drive.core.round == 2


def test_no_commit_is_chained_while_no_agent_is_live() -> None:
    drive = Drive(FakeWorld(2, end_after=5))
    drive.silent = {0, 1}
    drive.start(0, 1)
    drive.alive(0, 1, up=False)
    assert drive.commits() == [Commit(round=1, timed_out=(0, 1), then_active=())]
    assert drive.world.opened == [(1, (0, 1))]


# --- moves and timeouts -----------------------------------------------------------------------


def test_a_robot_that_never_moves_is_timed_out_at_exactly_move_timeout() -> None:
    drive = Drive(FakeWorld(3))
    drive.silent = {2}
    drive.now = 10.0
    drive.start(0, 1, 2)
    assert drive.core.phase is Phase.COLLECT and drive.world.held == {0, 1}
    assert drive.core.next_deadline() == 15.0
    drive.tick(15.0 - 1e-9)
    assert drive.commits() == []
    drive.tick(15.0)
    (commit, timed_out), *_ = drive.world.applied
    assert commit.round == 1 and 2 in commit.timed_out and timed_out == (2,)


def test_the_note_of_a_round_ended_at_its_deadline_names_only_the_robots_the_world_missed() -> None:
    drive = Drive(FakeWorld(3))
    drive.silent = {2}
    drive.perform(drive.core.start(drive.now))
    drive.alive(0, 1, 2, world_first=True)  # the world knows robot 2 is up when 0 and 1 move
    drive.core.pop_notes()
    drive.tick(5.0)  # robots 0 and 1 moved, but no notice comes while robot 2 is missing
    assert drive.world.applied[0][1] == (2,)
    assert Note("round 1: no move from [2]") in drive.core.pop_notes()


@pytest.mark.parametrize("world_first", [False, True])
def test_a_robot_that_dies_mid_round_is_not_waited_for_but_the_next_plan_waits_for_it(
    world_first: bool,
) -> None:
    drive = Drive(FakeWorld(3))
    drive.silent = {1}
    drive.start(0, 1, 2)
    assert drive.commits() == []
    drive.now = 1.0
    drive.alive(1, up=False, world_first=world_first)
    # its round is committed at once, without planning the next one over the robots left
    assert drive.commits() == [Commit(round=1, timed_out=(1,), then_active=())]
    assert drive.core.phase is Phase.REJOIN and drive.core.next_deadline() == 6.0
    assert drive.core.rejoining(1.0) == {1} and drive.scheduler.asked == [1]
    drive.tick(6.0)  # the move timeout after it went: the next round goes on without it
    assert drive.world.opened[1] == (2, (0, 2))  # fsync over the live robots
    assert (
        Note(
            "agents [1] did not come back within the move timeout; going on without them",
            warning=True,
        )
        in drive.core.pop_notes()
    )


def test_agents_back_within_the_move_timeout_are_planned_with_as_if_never_gone() -> None:
    # A router restart: every agent's token goes, and they come back one by one.
    clean = Drive(FakeWorld(6, end_after=6), scheduler="ssync", seed=4).start(*range(6))
    world = FakeWorld(6, end_after=6)
    drive = Drive(world, scheduler="ssync", seed=4, times=RoundTimes(pace_s=1.0)).start(*range(6))
    drive.now = 0.5
    drive.alive(*range(6), up=False)  # in the pace of round 1
    assert drive.core.next_deadline() == 1.0  # (the pace's)
    drive.tick(1.0)
    assert drive.core.phase is Phase.REJOIN and drive.core.next_deadline() == 5.5
    drive.now = 2.0
    drive.alive(3)  # the first back does not open round 2 over itself alone
    assert len(drive.begins()) == 1 and drive.core.phase is Phase.REJOIN
    drive.alive(0, 1, 2, 4, 5)  # the last back opens it, planned over all six
    assert drive.begins()[1] == Begin(2, clean.scheduler.said[2])
    drive.run()
    assert [a for _, a in world.opened] == [a for _, a in clean.world.opened]
    assert drive.scheduler.asked == list(range(1, 7))  # each round once (paced: none ahead)


def test_a_retried_round_keeps_its_set_and_waits_for_a_robot_that_died_up_to_the_move_timeout() -> (
    None
):
    world = FakeWorld(2, end_after=1)
    world.fail("begin", "refuse")
    drive = Drive(world).start(0, 1)
    drive.alive(0, up=False)
    drive.tick(0.25)  # Hello: round 1 again, once robot 0 is back or its move timeout ran out
    assert drive.begins() == [Begin(round=1, active=(0, 1))]
    assert drive.core.phase is Phase.REJOIN and drive.core.next_deadline() == 5.0
    drive.tick(5.0)
    assert drive.begins() == [Begin(round=1, active=(0, 1))] * 2
    assert drive.commits() == [Commit(round=1, timed_out=(0,), then_active=(1,))]
    assert drive.now == 5.0


def test_move_notices_of_another_round_or_robot_are_ignored() -> None:
    drive = Drive(FakeWorld(3, end_after=5))
    drive.auto_move = False
    drive.start(0, 1)
    drive.tick(120.0)  # robot 2 never came: round 1 with 0 and 1
    assert drive.core.round == 1 and drive.core.active == (0, 1)
    for notice in (
        MovesHeld(round=2, robots=(0, 1), epoch=1),
        MovesHeld(round=1, robots=(2,), epoch=1),
    ):
        assert drive.core.on_held(notice, drive.now) == []
    assert drive.core.held == set()
    drive.move(0)
    assert drive.commits() == []  # robot 1 has not moved: the world sends no notice
    drive.move(1)
    assert drive.commits() == [Commit(round=1, timed_out=(), then_active=(0, 1))]


def test_a_notice_marks_only_the_robots_active_in_the_round() -> None:
    drive = Drive(FakeWorld(3, end_after=5))
    drive.auto_move = False
    drive.start(0, 1)
    drive.tick(120.0)
    drive.perform(drive.core.on_held(MovesHeld(round=1, robots=(0, 2), epoch=1), drive.now))
    assert drive.core.held == {0} and drive.commits() == []  # robot 1 is still waited for
    drive.perform(drive.core.on_held(MovesHeld(round=1, robots=(1,), epoch=1), drive.now))
    assert drive.commits() == [Commit(round=1, timed_out=(), then_active=(0, 1))]


def test_a_notice_that_comes_after_the_commit_changes_nothing() -> None:
    drive = Drive(FakeWorld(3, end_after=5), times=RoundTimes(pace_s=10.0))
    drive.start(0, 1, 2)
    assert drive.core.phase is Phase.PACE and len(drive.world.requests) == 3
    assert drive.core.on_held(MovesHeld(round=1, robots=(0, 1, 2), epoch=1), 1.0) == []
    assert drive.core.on_held(MovesHeld(round=2, robots=(0, 1, 2), epoch=1), 1.0) == []
    assert drive.core.phase is Phase.PACE and len(drive.world.requests) == 3


# --- gathering the agents ---------------------------------------------------------------------


def test_round_one_waits_for_all_agents_up_to_start_timeout_then_goes_on_with_the_live() -> None:
    drive = Drive(FakeWorld(4)).start(0, 1)
    assert drive.core.phase is Phase.GATHER and drive.core.next_deadline() == 120.0
    drive.tick(119.9)
    assert drive.begins() == []
    drive.tick(120.0)
    assert drive.begins()[0] == Begin(round=1, active=(0, 1))


def test_the_last_agent_arriving_opens_round_one_at_once() -> None:
    drive = Drive(FakeWorld(3)).start(0, 1)
    drive.now = 30.0
    drive.alive(2)
    assert drive.begins()[0] == Begin(round=1, active=(0, 1, 2))
    assert drive.opened[0] == (30.0, 1, (0, 1, 2))


def test_no_round_starts_with_nobody_live() -> None:
    drive = Drive(FakeWorld(3)).start()
    drive.tick(120.0)
    drive.tick(500.0)
    assert drive.begins() == [] and drive.core.phase is Phase.GATHER
    assert drive.core.next_deadline() is None  # only an agent can move it on now
    drive.alive(2)
    assert drive.begins()[0] == Begin(round=1, active=(2,))


def test_when_every_agent_dies_the_next_round_waits_for_one() -> None:
    drive = Drive(FakeWorld(2, end_after=5))
    drive.silent = {0, 1}
    drive.start(0, 1)
    drive.alive(0, 1, up=False)
    assert drive.commits() == [Commit(round=1, timed_out=(0, 1))]
    drive.tick(1000.0)
    assert len(drive.begins()) == 1 and drive.core.phase is Phase.GATHER
    drive.alive(1)
    assert drive.begins()[1] == Begin(round=2, active=(1,))


def test_agents_of_other_runs_are_ignored_once_n_is_known() -> None:
    drive = Drive(FakeWorld(2))
    drive.perform(drive.core.on_alive(7, True, 0.0))  # before Hello's reply: n unknown
    drive.start(5, 0, 1)
    assert drive.core.live == {0, 1}
    assert drive.begins()[0] == Begin(round=1, active=(0, 1))


# --- the world restarting ---------------------------------------------------------------------


def test_a_silent_world_is_asked_again_every_retry_interval() -> None:
    world = FakeWorld(2)
    world.fail("hello", "none")
    world.fail("hello", "refuse")
    drive = Drive(world).start(0, 1)
    assert drive.world.requests == [Hello()] and drive.core.next_deadline() == 0.25
    drive.tick(0.25)
    assert drive.world.requests == [Hello(), Hello()] and drive.core.next_deadline() == 0.5
    drive.tick(0.5)
    assert drive.core.n == 2 and drive.begins()[0] == Begin(round=1, active=(0, 1))


def test_a_restarted_coordinator_counts_the_moves_the_world_already_holds() -> None:
    # The first coordinator opened round 3 and the world holds robots 0 and 1's moves; the new
    # one re-opens round 3 (same scheduler, same active set) and waits only for robot 2.
    world = FakeWorld(3, end_after=5, committed=2)
    world.open_round, world.active, world.held = 3, (0, 1, 2), {0, 1}
    drive = Drive(world, resume_live=range(3))
    drive.auto_move = False
    drive.start(0, 1, 2)
    assert drive.core.phase is Phase.COLLECT and drive.core.held == {0, 1}
    assert world.opened == []  # opened again as it was: the world keeps what it holds
    drive.now = 0.01
    drive.move(2)
    assert world.applied[0] == (Commit(round=3, timed_out=(), then_active=(0, 1, 2)), ())


def test_a_world_that_restarts_mid_round_is_asked_at_once_and_the_round_opened_again() -> None:
    world = FakeWorld(3, end_after=5)
    drive = Drive(world)
    drive.silent = {2}  # robot 2's move is on its way when the world dies
    drive.start(0, 1, 2)
    assert drive.core.phase is Phase.COLLECT and world.held == {0, 1}
    world.restart()  # it lost the open round and the moves it held
    drive.now = 0.2
    drive.silent = set()
    drive.perform(drive.core.on_world(True, drive.now))
    assert world.requests[2:4] == [Hello(), Begin(round=1, active=(0, 1, 2))]
    assert world.applied[0] == (Commit(round=1, timed_out=(), then_active=(0, 1, 2)), ())
    assert drive.opened[:2] == [(0.0, 1, (0, 1, 2)), (0.2, 1, (0, 1, 2))]  # all three moved again


def test_a_notice_of_the_world_before_its_restart_does_not_commit_the_reopened_round() -> None:
    world = FakeWorld(3)
    drive = Drive(world)
    drive.silent = {2}
    drive.perform(drive.core.start(drive.now))
    drive.alive(0, 1, 2, world_first=True)
    stale = MovesHeld(1, (0, 1, 2), world.epoch)  # as if on its way when the world died
    world.restart()
    drive.silent = {0, 1, 2}  # nobody has moved in the new world yet
    drive.perform(drive.core.on_world(True, drive.now))
    assert world.requests[-1] == Begin(round=1, active=(0, 1, 2))  # round 1 opened again
    drive.notices.append(stale)
    drive.perform([])
    assert world.applied == [] and drive.core.phase is Phase.COLLECT
    assert drive.core.held == set()


def test_a_world_that_comes_up_is_asked_at_once_not_at_the_retry_deadline() -> None:
    world = FakeWorld(2)
    world.fail("hello", "none")
    drive = Drive(world).start(0, 1)
    assert drive.core.phase is Phase.RETRY and drive.core.next_deadline() == 0.25
    drive.now = 0.01
    drive.perform(drive.core.on_world(False, drive.now))  # its token going away changes nothing
    assert drive.world.requests == [Hello()]
    drive.perform(drive.core.on_world(True, drive.now))
    assert drive.world.requests[:2] == [Hello(), Hello()]
    assert drive.begins()[0] == Begin(round=1, active=(0, 1))


def test_moves_held_by_a_world_that_then_restarted_are_not_counted_in_the_reopened_round() -> None:
    world = FakeWorld(2, end_after=5)
    world.fail("begin", "lost")  # the world opens round 1 and both move; the reply is lost
    drive = Drive(world).start(0, 1)
    assert drive.core.next_deadline() == 0.25  # Hello again then
    assert drive.core.held == {0, 1}  # from the world's notice
    world.restart()  # it loses the round and the moves
    drive.silent = {1}
    drive.tick(0.25)  # Hello, then round 1 again, where only robot 0 has moved yet
    assert world.requests[2:] == [Hello(), Begin(1, (0, 1))]
    assert drive.core.phase is Phase.COLLECT and drive.core.held == set()
    drive.tick(1.25)  # robot 0's notice never comes: robot 1 is waited for, to the deadline
    assert world.requests[2:] == [Hello(), Begin(1, (0, 1))]
    drive.tick(5.25)
    assert world.applied[0][1] == (1,) and 1 in world.applied[0][0].timed_out


@pytest.mark.parametrize("how", ["refuse", "none", "lost"])
def test_a_failed_begin_is_asked_again_after_hello_with_the_same_round_and_active_set(
    how: str,
) -> None:
    clean = Drive(FakeWorld(6, end_after=4), scheduler="ssync").start(*range(6))
    world = FakeWorld(6, end_after=4)
    world.fail("begin", how)
    drive = Drive(world, scheduler="ssync").start(*range(6))
    assert world.requests == [Hello(), clean.begins()[0]]
    assert drive.core.phase is Phase.RETRY and drive.core.next_deadline() == 0.25
    drive.tick(0.25)
    assert world.requests[2:4] == [Hello(), clean.begins()[0]]
    assert drive.run() == Finished(Status.FORMED, 0)
    assert [a for _, a in world.opened] == [a for _, a in clean.world.opened]
    assert drive.scheduler.asked == clean.scheduler.asked  # the scheduler drew each round once


def test_a_refused_commit_asks_hello_and_opens_the_lost_round_again_with_the_same_set() -> None:
    world = FakeWorld(6, end_after=3)
    drive = Drive(world, scheduler="ssync")
    drive.auto_move = False
    drive.start(*range(6))
    opened = drive.begins()[0]
    assert len(opened.active) > 1
    drive.move(opened.active[0])
    world.restart()  # the world restarts and loses the open round with its held move
    drive.wait(5.0)  # the deadline: Commit, refused; Hello; Begin round 1 again at once
    commit, *tail = world.requests[2:]
    assert isinstance(commit, Commit) and commit.then_active == drive.scheduler.said[2]
    assert commit.round == 1 and set(opened.active[1:]) <= set(commit.timed_out)
    assert tail[:2] == [Hello(), opened]
    assert drive.core.phase is Phase.COLLECT and drive.core.held == set()
    assert drive.core.next_deadline() == 10.0
    drive.wait(5.0)  # round 1 times out again: its commit carries the same next set
    assert world.requests[-1] == commit
    assert drive.scheduler.asked == [1, 2]


def test_a_round_the_world_still_holds_open_keeps_its_held_moves_when_opened_again() -> None:
    world = FakeWorld(3, end_after=1)
    world.fail("commit", "none")  # the request is lost: the world keeps round 1 and its moves
    drive = Drive(world).start(0, 1, 2)
    commit = Commit(round=1, timed_out=(), then_active=(0, 1, 2))
    assert world.requests == [
        Hello(),
        Begin(round=1, active=(0, 1, 2)),
        commit,
        Hello(),
        Begin(round=1, active=(0, 1, 2)),
        commit,
    ]
    assert drive.finished == Finished(Status.FORMED, 0) and drive.now == 0.0


def test_a_lost_commit_reply_goes_on_from_the_round_the_world_committed() -> None:
    world = FakeWorld(3, end_after=5)
    world.fail("commit", "lost")
    drive = Drive(world).start(0, 1, 2)
    assert world.requests[:5] == [
        Hello(),
        Begin(round=1, active=(0, 1, 2)),
        Commit(round=1, timed_out=(), then_active=(0, 1, 2)),
        Hello(),
        Begin(round=2, active=(0, 1, 2)),
    ]
    assert drive.finished == Finished(Status.FORMED, 0)


def test_a_world_that_ended_while_the_coordinator_was_asking_finishes_it() -> None:
    world = FakeWorld(2, end_after=1)
    world.fail("commit", "lost")
    drive = Drive(world).start(0, 1)
    assert drive.finished == Finished(Status.FORMED, 0)
    assert world.requests[-1] == Hello() and world.opened == [(1, (0, 1))]


# --- resuming ---------------------------------------------------------------------------------


def test_a_restarted_coordinator_replays_the_scheduler_to_the_uninterrupted_active_sets() -> None:
    whole = Drive(FakeWorld(6, end_after=9), scheduler="ssync", seed=11).start(*range(6))
    assert whole.finished is not None
    resumed = Drive(FakeWorld(6, end_after=9, committed=4), scheduler="ssync", seed=11)
    resumed.start(*range(6))
    assert resumed.world.opened == whole.world.opened[4:]
    assert len({a for _, a in whole.world.opened}) > 1  # ssync drew different sets


def test_a_restarted_coordinator_waits_only_the_resume_grace_for_its_agents() -> None:
    drive = Drive(FakeWorld(4, end_after=9, committed=2))
    drive.auto_move = False
    drive.start(0)
    assert drive.core.round == 3 and drive.core.next_deadline() == 2.0
    drive.tick(2.0)
    assert drive.begins() == [Begin(round=3, active=(0,))]
    assert drive.core.pop_notes() == [
        Note("resuming after round 2"),
        Note("only 1 of 4 agents after 2.0 s; going on with them", warning=True),
    ]
    assert drive.core.pop_notes() == []


# --- ticks ------------------------------------------------------------------------------------


def test_on_tick_before_a_deadline_or_twice_does_nothing() -> None:
    drive = Drive(FakeWorld(3, end_after=2))
    drive.silent = {2}
    assert drive.core.on_tick(0.0) == []  # not started
    drive.start(0, 1, 2)
    assert drive.core.on_tick(4.0) == []
    (first,) = drive.core.on_tick(5.0)
    assert isinstance(first, Ask) and isinstance(first.request, Commit)
    assert (first.request.round, first.request.then_active) == (1, (0, 1, 2))
    assert drive.core.on_tick(5.0) == [] and drive.core.on_tick(6.0) == []


def test_a_reply_with_no_request_out_or_a_second_start_is_the_callers_bug() -> None:
    drive = Drive(FakeWorld(3)).start(0)
    with pytest.raises(CoreMisuse):
        drive.core.on_reply(None, 1.0)
    with pytest.raises(CoreMisuse):
        drive.core.start(1.0)


# --- under any order of events ----------------------------------------------------------------

OPS = st.one_of(
    st.tuples(st.just("alive"), st.integers(0, 5), st.booleans(), st.booleans()),
    st.tuples(st.just("move"), st.integers(0, 5)),  # the i-th robot of the world's round moves
    st.tuples(st.just("moves")),  # every robot of the world's round whose agent is up moves
    st.tuples(st.just("quick"), st.integers(0, 5), st.booleans()),  # moves as it is answered
    st.tuples(st.just("kill"), st.integers(0, 5), st.booleans()),  # the i-th active robot dies
    st.tuples(st.just("stray"), st.integers(0, 5), st.sampled_from([-2, -1, 0, 1, 2])),
    st.tuples(st.just("wait"), st.floats(0.0, 1.5)),
    st.tuples(
        st.just("fault"),
        st.sampled_from(["hello", "begin", "commit"]),
        st.sampled_from(["refuse", "none", "lost"]),
    ),
    st.tuples(st.just("restart")),
)

Seen = tuple[float, float, Commit, frozenset[int], bool]  # when, round opened, what, live, rejoin


def _check_commits(drive: Drive, seen: list[Seen]) -> None:
    """Every commit the world applied names every active robot it holds no move for (and maybe
    more: the core hears of moves only in the world's one notice a round), and it came at the move
    deadline or once every live active robot had moved, never earlier; with no pace, a commit
    while some agent is live opens the next round."""
    applied = {id(commit): timed_out for commit, timed_out in drive.world.applied}
    for commit, timed_out in drive.world.applied:
        assert set(timed_out) <= set(commit.timed_out)
    for at, opened, commit, live, rejoining in seen:
        if drive.core.times.pace_s == 0 and live and not rejoining:  # nothing holds it back
            assert commit.then_active
        if at < opened + drive.core.times.move_timeout_s and id(commit) in applied:
            assert not set(commit.timed_out) & live


def _check_plans(drive: Drive) -> None:
    """The scheduler is asked once per round, in order, and every set opened is its answer."""
    for scheduler in drive.schedulers:
        assert scheduler.asked == list(range(1, len(scheduler.asked) + 1))
    said = drive.schedulers[-1].said if drive.schedulers else {}
    for req in drive.world.requests:
        plan = (
            (req.round, req.active)
            if isinstance(req, Begin)
            else (
                (req.round + 1, req.then_active)
                if isinstance(req, Commit) and req.then_active
                else None
            )
        )
        if plan is not None:
            assert plan[1] and plan[1] == tuple(sorted(set(plan[1])))
            assert max(plan[1]) < drive.world.n
            assert said[plan[0]] == plan[1]


def _check_collecting(drive: Drive) -> None:
    """The core counts only robots active in its round as held, and does not wait on a round in
    which the world has said every live active robot has moved."""
    core, notice = drive.core, drive.world.noticed
    if core.phase is not Phase.COLLECT:
        return
    assert core.held <= core.active_set
    if notice is not None and notice.round == core.round:
        assert core.round != drive.world.open_round or (core.live & core.active_set) - set(
            notice.robots
        ), "a round with every live active robot's move held is not committed"


def _check_pace(drive: Drive) -> None:
    """The world opens no round (nor opens one again) sooner than `pace_s` after the last."""
    times = [at for at, _, _ in drive.opened]
    assert all(b >= a + drive.core.times.pace_s for a, b in itertools.pairwise(times))


def _any_events(
    n: int,
    scheduler: str,
    pace: float,
    up: set[int],
    quick: set[int],
    ops: list[tuple[object, ...]],
) -> None:
    times = RoundTimes(
        move_timeout_s=1.0, start_timeout_s=0.5, resume_grace_s=0.5, pace_s=pace, retry_s=0.25
    )
    world = FakeWorld(n, end_after=1000)
    drive = Drive(world, scheduler=scheduler, times=times)
    drive.silent = set(range(6)) - quick  # the others move as soon as their Look is answered
    seen: list[Seen] = []
    answer = world.answer

    def answer_and_note(req: Request) -> ControlReply | None:
        if isinstance(req, Commit) and req.round == world.open_round:
            rejoining = bool(drive.core.rejoining(drive.now))
            seen.append(
                (drive.now, drive.collecting_since[req.round], req, drive.core.live, rejoining)
            )
        return answer(req)

    world.answer = answer_and_note  # type: ignore[method-assign]
    drive.start(*sorted(up))
    for op in ops:
        match op:
            case ("quick", int(robot), bool(fast)):
                (drive.silent.discard if fast else drive.silent.add)(robot)
            case ("alive", int(robot), bool(alive), bool(world_first)):
                drive.alive(robot, up=alive, world_first=world_first)
            case ("move", int(i)):  # an agent whose Look the world answered moves
                if world.open_round:
                    drive.move(world.active[i % len(world.active)])
            case ("moves",):
                for robot in world.active:
                    if robot in drive.agents:
                        drive.move(robot)
            case ("kill", int(i), bool(world_first)):
                if drive.core.active:
                    robot = drive.core.active[i % len(drive.core.active)]
                    drive.alive(robot, up=False, world_first=world_first)
            case ("stray", int(robot), int(offset)):  # never a notice the world could send
                if drive.core.round + offset >= 1 and (offset or robot not in drive.core.active):
                    notice = MovesHeld(
                        round=drive.core.round + offset, robots=(robot,), epoch=drive.world.epoch
                    )
                    drive.perform(drive.core.on_held(notice, drive.now))
            case ("wait", float(dt)):
                drive.wait(dt)
            case ("fault", str(kind), str(how)):
                world.fail(kind, how)
            case ("restart",):
                world.restart()
        _check_plans(drive)
        _check_commits(drive, seen)
        _check_collecting(drive)
        _check_pace(drive)
    # then every agent comes back and moves at once, and the run goes on to its end
    world.faults.clear()
    world.end_after = world.committed + 2
    drive.silent = set()
    drive.alive(*range(n))
    for robot in world.active:
        drive.move(robot)
    assert drive.run().status == Status.FORMED
    _check_plans(drive)
    _check_commits(drive, seen)


# With its fixed examples this property fails on cores broken in any of these ways (each tried
# on a copy of coordinator/rounds.py): a notice of another round counted; a commit before every
# live active robot has moved, or only at the deadline; a dead robot still waited for; the
# scheduler asked again for a round already planned; held moves kept into a new round; a chained
# reply taken without making its plan current; a commit chained while the pace holds the next
# round back, or never chained; the pace not counted from a chained opening. These need an
# exact order of events and are pinned by named tests: a notice's robots not intersected with the
# active set; held moves kept when the world lost the round; the reply's `held` ignored; a chain
# assumed whatever the commit's reply says.
@settings(max_examples=300, deadline=None)
@given(
    n=st.integers(1, 5),
    scheduler=st.sampled_from(["fsync", "ssync", "centralized"]),
    pace=st.sampled_from([0.0, 0.7]),
    up=st.sets(st.integers(0, 5)),
    quick=st.sets(st.integers(0, 5)),
    ops=st.lists(OPS, min_size=3, max_size=60),
)
def test_under_any_events_rounds_follow_the_schedule_and_commits_wait_for_the_live_robots(
    n: int,
    scheduler: str,
    pace: float,
    up: set[int],
    quick: set[int],
    ops: list[tuple[object, ...]],
) -> None:
    _any_events(n, scheduler, pace, up, quick, ops)


def test_a_round_the_world_lost_while_the_core_paced_waits_for_its_live_robots_again() -> None:
    world = FakeWorld(2, end_after=5)
    drive = Drive(world, times=RoundTimes(pace_s=1.0)).start(0, 1)
    world.fail("commit", "none")  # round 2's commit is lost: the world keeps round 2 and its moves
    drive.tick(1.0)  # Begin 2, both move, Commit lost, Hello: round 2 still open -> pace to 2.0
    assert drive.core.phase is Phase.PACE and drive.core.held == {0, 1}
    drive.now = 1.5
    world.restart()  # the world restarts and loses round 2 (on_world does nothing in PACE)
    drive.silent = {1}
    drive.tick(2.0)  # Begin 2 again: the world opens it anew, holding no move
    assert world.requests[-1] == Begin(2, (0, 1))
    # the ignore: mypy keeps drive.core.phase narrowed to PACE by the assert above, though tick()
    # moved the core on
    assert drive.core.phase is Phase.COLLECT and drive.core.held == set()  # type: ignore[comparison-overlap]
    assert drive.core.next_deadline() == 7.0
