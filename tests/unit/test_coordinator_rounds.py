"""The coordinator's round state machine against a fake world on a fake clock (no Zenoh)."""

from __future__ import annotations

import ast
import inspect
from collections import deque
from collections.abc import Sequence

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fatswarm.coordinator import rounds
from fatswarm.coordinator.protocol import RoundStart
from fatswarm.coordinator.rounds import (
    Action,
    Announce,
    Ask,
    CoordinatorCore,
    CoreMisuse,
    Finished,
    Note,
    Phase,
    RoundTimes,
)
from fatswarm.coordinator.schedule import make_scheduler
from fatswarm.world.outcome import ExitCode, Status, exit_code_for
from fatswarm.world.protocol import Begin, Commit, ControlReply, Hello, MoveHeld

Request = Hello | Begin | Commit
TIMES = RoundTimes(move_timeout_s=5.0, start_timeout_s=120.0, resume_grace_s=2.0, pace_s=0.0,
                   retry_s=0.25)


class FakeWorld:
    """Answers Hello, Begin and Commit as the world does; the run ends after `end_after` commits.

    `fail(kind, how)` makes the next request of that kind fail: "refuse" (ok=False), "none" (no
    answer) or "lost" (applied, but the answer never arrives). `restart()` loses the open round.
    """

    def __init__(self, n: int, end_after: int = 3, end_status: Status = Status.FORMED,
                 committed: int = 0, collisions: int = 0) -> None:
        self.n, self.end_after, self.end_status = n, end_after, end_status
        self.committed, self.collisions = committed, collisions
        self.status = Status.RUNNING if committed < end_after else end_status
        self.open_round = 0
        self.active: tuple[int, ...] = ()
        self.held: set[int] = set()
        self.faults: list[tuple[str, str]] = []
        self.requests: list[Request] = []
        self.applied: list[tuple[Commit, tuple[int, ...]]] = []  # and the world's timed out

    def fail(self, kind: str, how: str) -> None:
        self.faults.append((kind, how))

    def restart(self) -> None:
        self.open_round, self.active, self.held = 0, (), set()

    def hold(self, robot: int) -> MoveHeld | None:
        """An agent's move: held (its notice returned) if the robot is active in the open round."""
        if self.open_round and robot in self.active and robot not in self.held:
            self.held.add(robot)
            return MoveHeld(round=self.open_round, robot=robot)
        return None

    def reply(self, ok: bool, reason: str = "") -> ControlReply:
        return ControlReply(ok=ok, reason=reason, n=self.n, committed=self.committed,
                            open_round=self.open_round, status=str(self.status),
                            collisions=self.collisions,
                            held=tuple(sorted(self.held)) if self.open_round else ())

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
            if req.round != self.committed + 1:
                return self.reply(False, f"next round is {self.committed + 1}")
            if (self.open_round, self.active) != (req.round, req.active):
                self.open_round, self.active, self.held = req.round, req.active, set()
            return self.reply(True)
        if req.round == self.committed and not self.open_round:
            return self.reply(True)  # the answer to a commit was lost: it is durable
        if req.round != self.open_round:
            return self.reply(False, f"round {req.round} is not open")
        self.applied.append((req, tuple(r for r in self.active if r not in self.held)))
        self.committed, self.open_round, self.active, self.held = req.round, 0, (), set()
        if self.committed >= self.end_after:
            self.status = self.end_status
        return self.reply(True)


class Drive:
    """A core, a fake world and a fake clock; live agents move at once unless `silent`."""

    def __init__(self, world: FakeWorld, scheduler: str = "fsync", seed: int = 7,
                 times: RoundTimes = TIMES, resume_live: Sequence[int] | None = None) -> None:
        self.world, self.times, self.now = world, times, 0.0
        self.core = CoordinatorCore(lambda n: make_scheduler(scheduler, n, seed), times,
                                    resume_live)
        self.auto_move = True
        self.silent: set[int] = set()
        self.announced: list[tuple[float, RoundStart]] = []
        self.finished: Finished | None = None

    def perform(self, actions: list[Action]) -> None:
        todo = deque(actions)
        while todo:
            action = todo.popleft()
            if isinstance(action, Ask):
                assert not todo, "an Ask is the last action of a list"
                todo.extend(self.core.on_reply(self.world.answer(action.request), self.now))
            elif isinstance(action, Announce):
                self.announced.append((self.now, action.start))
                live = self.core.live
                for robot in action.start.active if self.auto_move else ():
                    if robot in live and robot not in self.silent:
                        todo.extend(self._held(robot))
            else:
                assert self.finished is None
                self.finished = action

    def start(self, *alive: int) -> Drive:
        self.perform(self.core.start(self.now))
        self.alive(*alive)
        return self

    def alive(self, *robots: int, up: bool = True) -> None:
        for robot in robots:
            self.perform(self.core.on_alive(robot, up, self.now))

    def move(self, robot: int) -> None:
        self.perform(self._held(robot))

    def _held(self, robot: int) -> list[Action]:
        notice = self.world.hold(robot)
        return [] if notice is None else self.core.on_held(notice, self.now)

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


def test_the_core_imports_no_zenoh_clock_threads_or_logging() -> None:
    tree = ast.parse(inspect.getsource(rounds))
    imported = {alias.name.split(".")[0] for node in ast.walk(tree)
                if isinstance(node, ast.Import) for alias in node.names}
    imported |= {(node.module or "").split(".")[0] for node in ast.walk(tree)
                 if isinstance(node, ast.ImportFrom)}
    assert not imported & {"zenoh", "time", "threading", "logging", "asyncio", "random", "socket"}


# --- a whole run ------------------------------------------------------------------------------


def test_a_full_fsync_run_ends_formed_after_the_worlds_last_commit() -> None:
    drive = Drive(FakeWorld(4, end_after=3)).start(0, 1, 2, 3)
    assert drive.finished == Finished(Status.FORMED, 0)
    assert [type(r).__name__ for r in drive.world.requests] == ["Hello"] + ["Begin", "Commit"] * 3
    assert drive.begins() == [Begin(round=k, active=(0, 1, 2, 3)) for k in (1, 2, 3)]
    assert drive.commits() == [Commit(round=k, timed_out=()) for k in (1, 2, 3)]
    assert [s for _, s in drive.announced] == [
        RoundStart(round=k, active=(0, 1, 2, 3), timeout_ms=5000) for k in (1, 2, 3)]
    assert drive.now == 0.0  # nobody waited: every move came at once
    assert drive.core.phase is Phase.DONE and drive.core.next_deadline() is None
    assert drive.core.finished == drive.finished


def test_finished_carries_the_worlds_status_and_collisions() -> None:
    stalled = Drive(FakeWorld(2, end_after=2, end_status=Status.STALLED, collisions=3)).start(0, 1)
    assert stalled.finished == Finished(Status.STALLED, 3)
    formed = Drive(FakeWorld(2, end_after=1, collisions=2)).start(0, 1)
    assert formed.finished == Finished(Status.FORMED, 2)
    assert exit_code_for(formed.finished.status, formed.finished.collisions) == (
        ExitCode.FORMED_WITH_COLLISIONS)


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


# --- moves and timeouts -----------------------------------------------------------------------


def test_a_robot_that_never_moves_is_timed_out_at_exactly_move_timeout() -> None:
    drive = Drive(FakeWorld(3))
    drive.silent = {2}
    drive.now = 10.0
    drive.start(0, 1, 2)
    assert drive.core.phase is Phase.COLLECT and drive.core.held == {0, 1}
    assert drive.core.next_deadline() == 15.0
    drive.tick(15.0 - 1e-9)
    assert drive.commits() == []
    drive.tick(15.0)
    assert drive.commits()[0] == Commit(round=1, timed_out=(2,))


def test_a_robot_that_dies_mid_round_is_not_waited_for() -> None:
    drive = Drive(FakeWorld(3))
    drive.silent = {1}
    drive.start(0, 1, 2)
    drive.now = 1.0
    drive.alive(1, up=False)
    assert drive.commits()[0] == Commit(round=1, timed_out=(1,))
    assert drive.begins()[1] == Begin(round=2, active=(0, 2))  # fsync over the live robots
    assert drive.now == 1.0


def test_a_retried_round_keeps_its_set_and_does_not_wait_for_a_robot_that_died() -> None:
    world = FakeWorld(2, end_after=1)
    world.fail("begin", "refuse")
    drive = Drive(world).start(0, 1)
    drive.alive(0, up=False)
    drive.tick(0.25)
    assert drive.begins() == [Begin(round=1, active=(0, 1))] * 2
    assert drive.commits() == [Commit(round=1, timed_out=(0,))]
    assert drive.now == 0.25


def test_move_notices_of_another_round_or_robot_are_ignored() -> None:
    drive = Drive(FakeWorld(3, end_after=5))
    drive.auto_move = False
    drive.start(0, 1)
    drive.tick(120.0)  # robot 2 never came: round 1 with 0 and 1
    assert drive.core.round == 1 and drive.core.active == (0, 1)
    for notice in (MoveHeld(round=2, robot=0), MoveHeld(round=1, robot=2)):
        assert drive.core.on_held(notice, drive.now) == []
    assert drive.core.held == set()
    drive.move(0)
    drive.move(1)
    assert drive.commits() == [Commit(round=1, timed_out=())]


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
    assert drive.announced[0][0] == 30.0


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
    drive.now = 0.01
    drive.move(2)
    assert world.applied[0] == (Commit(round=3, timed_out=()), ())  # no wait for a deadline


def test_a_world_that_restarts_mid_round_is_asked_at_once_and_the_round_opened_again() -> None:
    world = FakeWorld(3, end_after=5)
    drive = Drive(world)
    drive.silent = {2}  # robot 2's move is on its way when the world dies
    drive.start(0, 1, 2)
    assert drive.core.phase is Phase.COLLECT and drive.core.held == {0, 1}
    world.restart()  # it lost the open round and the moves it held
    drive.now = 0.2
    drive.silent = set()
    drive.perform(drive.core.on_world(True, drive.now))
    assert world.requests[2:4] == [Hello(), Begin(round=1, active=(0, 1, 2))]
    assert world.applied[0] == (Commit(round=1, timed_out=()), ())  # all three moved again


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
    assert drive.begins()[1:] == clean.begins()  # the scheduler drew each round once


def test_a_refused_commit_asks_hello_and_opens_the_lost_round_again_with_the_same_set() -> None:
    world = FakeWorld(6, end_after=3)
    drive = Drive(world, scheduler="ssync")
    drive.auto_move = False
    drive.start(*range(6))
    opened = drive.begins()[0]
    drive.move(opened.active[0])
    world.restart()  # the world restarts and loses the open round with its held move
    drive.wait(5.0)  # the deadline: Commit, refused; Hello; Begin round 1 again at once
    tail = world.requests[2:]
    assert tail[:3] == [Commit(round=1, timed_out=opened.active[1:]), Hello(), opened]
    assert drive.core.phase is Phase.COLLECT and drive.core.held == set()
    assert drive.core.next_deadline() == 10.0


def test_a_round_the_world_still_holds_open_keeps_its_held_moves_when_opened_again() -> None:
    world = FakeWorld(3, end_after=1)
    world.fail("commit", "none")  # the request is lost: the world keeps round 1 and its moves
    drive = Drive(world).start(0, 1, 2)
    assert world.requests == [Hello(), Begin(round=1, active=(0, 1, 2)),
                              Commit(round=1, timed_out=()), Hello(),
                              Begin(round=1, active=(0, 1, 2)), Commit(round=1, timed_out=())]
    assert drive.finished == Finished(Status.FORMED, 0) and drive.now == 0.0


def test_a_lost_commit_reply_goes_on_from_the_round_the_world_committed() -> None:
    world = FakeWorld(3, end_after=5)
    world.fail("commit", "lost")
    drive = Drive(world).start(0, 1, 2)
    assert world.requests[:5] == [Hello(), Begin(round=1, active=(0, 1, 2)),
                                  Commit(round=1, timed_out=()), Hello(),
                                  Begin(round=2, active=(0, 1, 2))]
    assert drive.finished == Finished(Status.FORMED, 0)


def test_a_world_that_ended_while_the_coordinator_was_asking_finishes_it() -> None:
    world = FakeWorld(2, end_after=1)
    world.fail("commit", "lost")
    drive = Drive(world).start(0, 1)
    assert drive.finished == Finished(Status.FORMED, 0)
    assert world.requests[-1] == Hello()


# --- resuming ---------------------------------------------------------------------------------


def test_a_restarted_coordinator_replays_the_scheduler_to_the_uninterrupted_active_sets() -> None:
    whole = Drive(FakeWorld(6, end_after=9), scheduler="ssync", seed=11).start(*range(6))
    assert whole.finished is not None
    resumed = Drive(FakeWorld(6, end_after=9, committed=4), scheduler="ssync", seed=11)
    resumed.start(*range(6))
    assert resumed.begins() == whole.begins()[4:]
    assert len({b.active for b in whole.begins()}) > 1  # ssync drew different sets


def test_a_restarted_coordinator_waits_only_the_resume_grace_for_its_agents() -> None:
    drive = Drive(FakeWorld(4, end_after=9, committed=2))
    drive.auto_move = False
    drive.start(0)
    assert drive.core.round == 3 and drive.core.next_deadline() == 2.0
    drive.tick(2.0)
    assert drive.begins() == [Begin(round=3, active=(0,))]
    assert drive.core.pop_notes() == [
        Note("resuming after round 2"),
        Note("only 1 of 4 agents after 2.0 s; going on with them", warning=True)]
    assert drive.core.pop_notes() == []


# --- pace and ticks ---------------------------------------------------------------------------


def test_pace_delays_the_next_begin_by_a_deadline_not_a_sleep() -> None:
    times = RoundTimes(pace_s=1.0)
    drive = Drive(FakeWorld(2, end_after=3), times=times).start(0, 1)
    assert len(drive.begins()) == 1 and len(drive.commits()) == 1
    assert drive.core.phase is Phase.PACE and drive.core.next_deadline() == 1.0
    drive.tick(0.5)
    assert len(drive.begins()) == 1
    drive.tick(1.0)
    assert drive.begins()[1] == Begin(round=2, active=(0, 1))
    assert drive.core.next_deadline() == 2.0


def test_a_round_longer_than_the_pace_is_followed_at_once() -> None:
    drive = Drive(FakeWorld(2, end_after=3), times=RoundTimes(pace_s=1.0))
    drive.silent = {1}
    drive.start(0, 1)
    drive.tick(5.0)  # round 1 timed out after 5 s > pace
    assert [b.round for b in drive.begins()] == [1, 2]


def test_on_tick_before_a_deadline_or_twice_does_nothing() -> None:
    drive = Drive(FakeWorld(3, end_after=2))
    drive.silent = {2}
    assert drive.core.on_tick(0.0) == []  # not started
    drive.start(0, 1, 2)
    assert drive.core.on_tick(4.0) == []
    first = drive.core.on_tick(5.0)
    assert first == [Ask(Commit(round=1, timed_out=(2,)))]
    assert drive.core.on_tick(5.0) == [] and drive.core.on_tick(6.0) == []


def test_a_reply_with_no_request_out_or_a_second_start_is_the_callers_bug() -> None:
    drive = Drive(FakeWorld(3)).start(0)
    with pytest.raises(CoreMisuse):
        drive.core.on_reply(None, 1.0)
    with pytest.raises(CoreMisuse):
        drive.core.start(1.0)


# --- under any order of events ----------------------------------------------------------------

OPS = st.one_of(
    st.tuples(st.just("alive"), st.integers(0, 5), st.booleans()),
    st.tuples(st.just("move"), st.integers(0, 5)),  # the i-th active robot moves
    st.tuples(st.just("kill"), st.integers(0, 5)),  # the i-th active robot dies
    st.tuples(st.just("stray"), st.integers(0, 5), st.sampled_from([-2, -1, 1, 2])),
    st.tuples(st.just("wait"), st.floats(0.0, 1.5)),
    st.tuples(st.just("fault"), st.sampled_from(["hello", "begin", "commit"]),
              st.sampled_from(["refuse", "none", "lost"])),
    st.tuples(st.just("restart")),
)


def _check_commits(
    drive: Drive, seen: list[tuple[float, float, Commit, frozenset[int]]]
) -> None:
    """Every commit the world applied names exactly the active robots it holds no move for, and
    came at the move deadline or once every live active robot had moved, never earlier."""
    world = drive.world
    for commit, timed_out in world.applied:
        assert commit.timed_out == timed_out
    for at, opened, commit, live in seen:
        waited = [r for r in commit.timed_out if r in live]
        assert at >= opened + drive.core.times.move_timeout_s or not waited


@settings(max_examples=300, deadline=None)
@given(
    n=st.integers(1, 5),
    scheduler=st.sampled_from(["fsync", "ssync", "centralized"]),
    pace=st.sampled_from([0.0, 0.7]),
    up=st.sets(st.integers(0, 5)),
    ops=st.lists(OPS, min_size=3, max_size=60),
)
def test_under_any_events_commits_name_exactly_the_active_robots_without_a_held_move(
    n: int, scheduler: str, pace: float, up: set[int], ops: list[tuple[object, ...]]
) -> None:
    times = RoundTimes(move_timeout_s=1.0, start_timeout_s=0.5, resume_grace_s=0.5, pace_s=pace,
                       retry_s=0.25)
    world = FakeWorld(n, end_after=1000)
    drive = Drive(world, scheduler=scheduler, times=times)
    drive.auto_move = False
    seen: list[tuple[float, float, Commit, frozenset[int]]] = []  # when, opened, what, live
    answer = world.answer

    def answer_and_note(req: Request) -> ControlReply | None:
        if isinstance(req, Commit) and req.round == world.open_round:
            seen.append((drive.now, drive.announced[-1][0], req, drive.core.live))
        return answer(req)

    world.answer = answer_and_note  # type: ignore[method-assign]
    drive.start(*sorted(up))
    for op in ops:
        match op:
            case ("alive", int(robot), bool(alive)):
                drive.alive(robot, up=alive)
            case ("move", int(i)):  # an agent acting on the round the core collects
                active = drive.core.active
                if drive.core.phase is Phase.COLLECT and drive.core.round == world.open_round:
                    drive.move(active[i % len(active)])
            case ("kill", int(i)):
                if drive.core.active:
                    drive.alive(drive.core.active[i % len(drive.core.active)], up=False)
            case ("stray", int(robot), int(offset)):
                if drive.core.round + offset >= 1:
                    notice = MoveHeld(round=drive.core.round + offset, robot=robot)
                    drive.perform(drive.core.on_held(notice, drive.now))
            case ("wait", float(dt)):
                drive.wait(dt)
            case ("fault", str(kind), str(how)):
                world.fail(kind, how)
            case ("restart",):
                world.restart()
        for begin in drive.begins():
            assert begin.active and begin.active == tuple(sorted(set(begin.active)))
            assert max(begin.active) < n
        _check_commits(drive, seen)
    # then every agent comes back and moves at once, and the run goes on to its end
    world.faults.clear()
    world.end_after = world.committed + 2
    drive.auto_move = True
    drive.alive(*range(n))
    if drive.core.phase is Phase.COLLECT:
        for robot in drive.core.active:
            drive.move(robot)
    assert drive.run().status == Status.FORMED
    _check_commits(drive, seen)
