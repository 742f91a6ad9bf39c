"""The coordinator's round protocol as a sans-IO state machine: events and `now` in, actions out.

No Zenoh, no clock, no threads: a shell (`service.py`) or an in-process driver performs the
actions, feeds back the world's replies and calls `on_tick` at `next_deadline()`.
"""

from __future__ import annotations

import enum
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from fatswarm.coordinator.schedule import Scheduler
from fatswarm.domain.outcome import Status
from fatswarm.domain.quick import quick_init
from fatswarm.world.protocol import Begin, Commit, ControlReply, Hello, MovesHeld

MAX_NOTES = 256  # notes nobody takes are dropped oldest first (a driver may ignore them)


@quick_init
@dataclass(frozen=True, slots=True)
class Ask:
    """Send this control request to the world; feed its reply (or None) to `on_reply`."""

    request: Hello | Begin | Commit


@dataclass(frozen=True, slots=True)
class Finished:
    """The run is over: `status` as the world said (RUNNING if the core was stopped first)."""

    status: Status
    collisions: int  # robots stopped at contact so far, from the world's last reply (else 0)
    gave_up: str = ""  # why the core gave up (the world gave no usable answer for give_up_s)


Action = Ask | Finished


@dataclass(frozen=True, slots=True)
class Note:
    """Something worth a log line; the shell logs it, a driver may drop it."""

    text: str
    warning: bool = False


@dataclass(frozen=True, slots=True)
class RoundTimes:
    """The coordinator's timing, in seconds."""

    move_timeout_s: float = 5.0  # an active robot that has not moved by then stays put
    start_timeout_s: float = 120.0  # wait this long for all n agents before round 1
    resume_grace_s: float = 2.0  # a restarted coordinator waits this long for all n agents
    pace_s: float = 0.0  # least time from one Begin to the next (0: full speed)
    retry_s: float = 0.25  # wait before asking the world again when it did not answer
    give_up_s: float = 120.0  # no usable answer from the world for this long: give up (a world
    # restarted on a long async record replays it before it answers: minutes for the longest)


class Phase(enum.Enum):
    """Where the core stands. A request is out (awaiting `on_reply`) in HELLO, BEGIN and COMMIT."""

    IDLE = "idle"  # not started
    HELLO = "hello"  # Hello is out: where does the run stand?
    RETRY = "retry"  # no usable answer: Hello again at the deadline
    GATHER = "gather"  # waiting for agents: all n until the deadline, then (no deadline) anyone
    REJOIN = "rejoin"  # before a new plan: waiting (to the deadline) for agents that went away
    BEGIN = "begin"  # Begin is out
    COLLECT = "collect"  # the round is open: waiting for the live active robots' moves
    COMMIT = "commit"  # Commit is out (carrying the next round's Begin when it may open at once)
    PACE = "pace"  # the next round begins at the deadline (pace_s after the last Begin)
    DONE = "done"  # finished


class CoreMisuse(RuntimeError):
    """The caller broke the core's contract (a bug of the shell or driver, not of a peer)."""


_WAITING = (Phase.RETRY, Phase.GATHER, Phase.REJOIN, Phase.COLLECT, Phase.PACE)  # with a deadline
# The phases and the status a round's path compares with, read off their Enum classes once: under
# CPython 3.11 a member read off its class costs about 20 times a global (400 ns against 17 on a
# loaded machine, measured), and each round compared about ten
_DONE, _HELLO, _BEGIN, _COLLECT, _COMMIT = (
    Phase.DONE,
    Phase.HELLO,
    Phase.BEGIN,
    Phase.COLLECT,
    Phase.COMMIT,
)
_RUNNING = Status.RUNNING
_NONE: frozenset[int] = frozenset()


class CoordinatorCore:
    """Runs semi-synchronous rounds: Hello, gather agents, then Begin, collect moves, Commit.

    A Commit carries the next round's Begin when nothing (a pace) holds that round back, so a round
    costs one request. The agents learn they are active from the world, which answers their held
    Looks when it opens a round: the coordinator never talks to them.

    An agent that goes away is given the move timeout to come back before the scheduler plans a
    round without it: a router restart takes every agent's token away for a moment, and a round
    planned over the few agents back first would no longer be the lock-step run's.

    At most one request is out at a time, and an `Ask` is always the last action of a list.
    """

    def __init__(
        self,
        make_scheduler: Callable[[int], Scheduler],
        times: RoundTimes,
        resume_live: Sequence[int] | None = None,
    ) -> None:
        self.times = times
        self._make_scheduler = make_scheduler
        self._resume_live = tuple(resume_live) if resume_live is not None else None
        self._scheduler: Scheduler | None = None
        self._n: int | None = None
        self._phase = Phase.IDLE
        self._deadline: float | None = None  # of the phases in _WAITING; None in GATHER: anyone
        self._gather_s = 0.0
        self._live: set[int] = set()
        self._live_order: tuple[int, ...] | None = None  # `_live` sorted, until it changes
        self._planned_live: frozenset[int] = frozenset()  # live when the scheduler last planned
        self._gone_at: dict[int, float] = {}  # robots of `_planned_live` gone since, and when
        self._held: set[int] = set()
        self._round = 0  # the round being opened, open or next (0 before the first Hello reply)
        self._planned: tuple[int, tuple[int, ...]] | None = None  # round, active: kept for retries
        self._next: tuple[int, tuple[int, ...]] | None = None  # planned ahead, carried by a Commit
        self._chained = False  # the Commit out carries the next round's Begin
        self._asked_at = 0.0  # when the request out was asked
        self._active_set: frozenset[int] = frozenset()  # of the planned round
        self._waiting: set[int] = set()  # COLLECT: live active robots without a held move
        self._began_at: float | None = None  # when the last Begin was asked (pace)
        self._collisions = 0
        self._epoch = 0  # the world process that answered last (MovesHeld.epoch)
        self._finished: Finished | None = None
        self._notes: deque[Note] = deque(maxlen=MAX_NOTES)
        self._unanswered_since: float | None = None  # the first retry since a usable answer

    # -- read-only views ------------------------------------------------------------------------

    @property
    def phase(self) -> Phase:
        return self._phase

    @property
    def finished(self) -> Finished | None:
        return self._finished

    @property
    def n(self) -> int | None:
        """The run's number of robots, once the world said it."""
        return self._n

    @property
    def round(self) -> int:
        return self._round

    @property
    def active(self) -> tuple[int, ...]:
        """The active set of `round` once planned, else ()."""
        if self._planned is not None and self._planned[0] == self._round:
            return self._planned[1]
        return ()

    @property
    def active_set(self) -> frozenset[int]:
        """`active` as a set (() -> empty)."""
        return self._active_set if self.active else frozenset()

    @property
    def live(self) -> frozenset[int]:
        return frozenset(self._live)

    @property
    def held(self) -> frozenset[int]:
        """Active robots of `round` whose move the world said it holds.

        Kept when the round is opened again at a world that still has it open (a Begin with the
        same set keeps what the world holds); cleared when the world says it lost the round.
        """
        return frozenset(self._held)

    def next_deadline(self) -> float | None:
        """When `on_tick` must be called next; None while only events (or a reply) move it on."""
        return self._deadline if self._phase in _WAITING else None

    def pop_notes(self) -> list[Note]:
        """The notes since the last call, oldest first."""
        if not self._notes:
            return []
        notes = list(self._notes)
        self._notes.clear()
        return notes

    # -- events in, actions out -----------------------------------------------------------------

    def start(self, now: float) -> list[Action]:
        """Ask the world where the run stands."""
        del now
        if self._phase is not Phase.IDLE:
            raise CoreMisuse("start() called twice")
        return self._ask_hello()

    def stop(self) -> Finished:
        """End now (the shell was told to stop): RUNNING unless the run had already ended."""
        if self._finished is None:
            self._finish(Status.RUNNING)
        assert self._finished is not None
        return self._finished

    def on_reply(self, reply: ControlReply | None, now: float) -> list[Action]:
        """The world's reply to the request out; None: no answer or a bad one (down, restarting)."""
        phase = self._phase
        if phase is _DONE:
            return []
        if reply is not None:
            self._collisions = reply.collisions
            self._epoch = reply.epoch
            if reply.ok:
                self._unanswered_since = None
        if phase is _COMMIT:  # (a round's request: first)
            return self._on_committed(reply, now)
        if phase is _HELLO:
            return self._on_hello(reply, now)
        if phase is _BEGIN:
            return self._on_begun(reply, now)
        raise CoreMisuse(f"a reply with no request out (phase {self._phase.value})")

    def on_alive(self, robot: int, alive: bool, now: float) -> list[Action]:
        """An agent's liveliness token appeared (alive) or went away."""
        if robot < 0 or (self._n is not None and robot >= self._n):
            return []
        if alive:
            if robot not in self._live:
                self._live.add(robot)
                self._live_order = None
            self._gone_at.pop(robot, None)
            if robot in self._active_set and robot not in self._held:
                self._waiting.add(robot)  # (only read in COLLECT, where it is kept up to date)
        elif robot in self._live:
            self._live.discard(robot)
            self._live_order = None
            self._waiting.discard(robot)
            if robot in self._planned_live:
                self._gone_at[robot] = now
            self._note(f"agent {robot} is gone")
        if self._phase is Phase.GATHER:
            return self._gathered(now)
        if self._phase is Phase.REJOIN:
            return self._open(now)
        if self._phase is Phase.COLLECT:  # a robot that died is not waited for
            return self._collected(now)
        return []

    def on_world(self, alive: bool, now: float) -> list[Action]:
        """The world's liveliness token appeared or went away. When it appears (a world just
        started, or restarted and lost the round it held open), the coordinator asks it where it
        stands at once, rather than at its retry or move deadline."""
        del now
        if alive and self._phase in (Phase.RETRY, Phase.COLLECT):
            return self._ask_hello()
        return []

    def on_held(self, notice: MovesHeld, now: float) -> list[Action]:
        """The world holds these robots' moves; notices of other rounds (or robots), or of another
        world process than the one that answered last (one since restarted), are ignored."""
        if notice.round == self._round and notice.epoch == self._epoch:
            planned, robots = self._planned, notice.robots
            active = planned[1] if planned is not None and planned[0] == self._round else ()
            if active and (robots is active or robots == active):
                # every active robot: the set as it is (a lock step's notice carries the very
                # tuple planned); what was held is among them, and nobody is waited for
                self._held = set(self._active_set)  # kept while the world keeps the round open
                self._waiting.clear()
            else:
                held = self.active_set.intersection(robots)
                self._held |= held  # kept while the world keeps the round open
                self._waiting -= held
        if self._phase is _COLLECT:
            return self._collected(now)
        return []

    def on_tick(self, now: float) -> list[Action]:
        """Act on a deadline that has passed; nothing otherwise (calling it again is harmless)."""
        if self._phase is Phase.GATHER:
            return self._gathered(now)
        if self._phase is Phase.REJOIN:
            return self._open(now)
        if self._phase is Phase.COLLECT:
            return self._collected(now)
        if self._deadline is None or now < self._deadline:
            return []
        if self._phase is Phase.RETRY:
            return self._ask_hello()
        if self._phase is Phase.PACE:
            return self._open(now)
        return []

    # -- transitions ----------------------------------------------------------------------------

    def _note(self, text: str, warning: bool = False) -> None:
        self._notes.append(Note(text, warning))

    def _ask_hello(self) -> list[Action]:
        self._phase, self._deadline = Phase.HELLO, None
        return [Ask(Hello())]

    def _retry(self, now: float) -> list[Action]:
        """Ask the world again after retry_s; give up once it has given no usable answer for
        give_up_s (a world gone for good: never retried forever)."""
        if self._unanswered_since is None:
            self._unanswered_since = now
        elif now - self._unanswered_since >= self.times.give_up_s:
            self._phase, self._deadline = Phase.DONE, None
            self._finished = Finished(
                Status.RUNNING,
                self._collisions,
                gave_up=f"the world gave no usable answer for {self.times.give_up_s:g} s "
                f"(round {self._round}); giving up",
            )
            return [self._finished]
        self._phase, self._deadline = Phase.RETRY, now + self.times.retry_s
        return []

    def _finish(self, status: Status) -> list[Action]:
        self._phase, self._deadline = Phase.DONE, None
        self._finished = Finished(status, self._collisions)
        return [self._finished]

    def _on_hello(self, reply: ControlReply | None, now: float) -> list[Action]:
        if reply is None or not reply.ok:
            return self._retry(now)
        if self._n is None:
            return self._first_hello(reply, now)
        if reply.n != self._n:
            self._note(
                f"the world now says n = {reply.n}; this coordinator keeps n = {self._n}",
                warning=True,
            )
        if reply.status != Status.RUNNING:
            return self._finish(Status(reply.status))
        if reply.open_round != self._round:
            self._held = set()  # the world restarted: it lost the moves it held
        # Open the round after the world's last committed one: the same round again if it lost
        # it, or the next one if only the reply to a commit was lost.
        return self._next_round(reply.committed + 1, now)

    def _first_hello(self, reply: ControlReply, now: float) -> list[Action]:
        self._n = reply.n  # the world owns the run's parameters
        self._live = {r for r in self._live if r < self._n}
        self._live_order = None
        self._scheduler = self._make_scheduler(self._n)
        if reply.status != Status.RUNNING:
            return self._finish(Status(reply.status))  # nothing to wait for
        if reply.committed:
            self._catch_up(reply.committed)
        self._round = reply.committed + 1
        times = self.times
        self._gather_s = times.resume_grace_s if reply.committed else times.start_timeout_s
        self._phase, self._deadline = Phase.GATHER, now + self._gather_s
        return self._gathered(now)

    def _catch_up(self, committed: int) -> None:
        """A restarted coordinator advances a seeded scheduler past the rounds already run."""
        assert self._scheduler is not None and self._n is not None
        replay_live = sorted(self._resume_live or range(self._n))
        for r in range(1, committed + 1):
            self._scheduler.active(r, replay_live)
        self._note(f"resuming after round {committed}")

    def _gathered(self, now: float) -> list[Action]:
        """GATHER: all n agents (or the deadline passed, then anyone) -> open the round."""
        if self._deadline is not None:
            if len(self._live) == self._n:
                return self._begin(now)
            if now < self._deadline:
                return []
            self._deadline = None
            self._note(
                f"only {len(self._live)} of {self._n} agents after {self._gather_s:.1f} s; "
                "going on with them",
                warning=True,
            )
        return self._begin(now) if self._live else []

    def _next_round(self, round_no: int, now: float) -> list[Action]:
        self._round = round_no
        if self.times.pace_s > 0 and self._began_at is not None:
            due = self._began_at + self.times.pace_s
            if now < due:
                self._phase, self._deadline = Phase.PACE, due
                return []
        return self._open(now)

    def _open(self, now: float) -> list[Action]:
        away = self.rejoining(now)
        if away:  # planned without them, the round would not be the one they were gone from
            if self._phase is not Phase.REJOIN:
                self._note(f"waiting for agents {sorted(away)} to come back (round {self._round})")
            self._phase = Phase.REJOIN
            self._deadline = min(self._gone_at[r] for r in away) + self.times.move_timeout_s
            return []
        if self._phase is Phase.REJOIN and self._gone_at:
            self._note(
                f"agents {sorted(self._gone_at)} did not come back within the move timeout; "
                "going on without them",
                warning=True,
            )
            self._gone_at.clear()  # (all of them past their move timeout: none is waited for)
        if not self._live:  # never a round with no live agent: wait for one
            self._phase, self._deadline = Phase.GATHER, None
            return []
        return self._begin(now)

    def rejoining(self, now: float) -> frozenset[int]:
        """Agents live when the scheduler last planned, gone since, whose move timeout (counted
        from when they went) has not run out: no round is planned without them meanwhile."""
        if not self._gone_at:
            return _NONE
        wait_s = self.times.move_timeout_s
        return frozenset(
            r
            for r, gone in self._gone_at.items()
            if r in self._planned_live and now < gone + wait_s
        )

    def _plan(self, round_no: int) -> tuple[int, ...]:
        """Round `round_no`'s active set: the scheduler is asked once per round, in order."""
        if self._next is not None and self._next[0] == round_no:
            return self._next[1]
        assert self._scheduler is not None
        live = self._plan_over_live()
        active = tuple(self._scheduler.active(round_no, live))
        planned = self._planned
        if planned is not None and active == planned[1]:
            active = planned[1]  # the same set again: the very tuple (compared by `is` after)
        self._next = (round_no, active)
        return active

    def _plan_over_live(self) -> tuple[int, ...]:
        """Note a new plan over the live agents (`_plan` calls it): the agents gone before it are
        no longer waited for. The live agents, sorted."""
        if self._live_order is None:  # (else the same agents as at the last plan)
            self._live_order = tuple(sorted(self._live))
            self._planned_live = frozenset(self._live_order)
        self._gone_at.clear()
        return self._live_order

    def _take_plan(self) -> None:
        """Make `round`'s planned active set the current one (a new round: nothing held yet)."""
        if self._planned is None or self._planned[0] != self._round:
            active = self._plan(self._round)
            if self._planned is None or active is not self._planned[1]:  # (`_plan`: else equal)
                self._active_set = frozenset(active)
            self._planned, self._next = (self._round, active), None
            self._held = set()

    def _begin(self, now: float) -> list[Action]:
        self._take_plan()
        self._began_at = self._asked_at = now
        self._phase, self._deadline = Phase.BEGIN, None
        return [Ask(Begin(round=self._round, active=self.active))]

    def _on_begun(self, reply: ControlReply | None, now: float) -> list[Action]:
        if reply is None or not reply.ok:
            why = "no answer" if reply is None else reply.reason
            self._note(f"world refused round {self._round}: {why}", warning=True)
            return self._retry(now)  # then Hello, and on from where the world stands
        # What the world holds is what counts: moves of a round it kept (this coordinator restarted,
        # or retried), none of a round it opened anew (it restarted while the core paced).
        held = reply.held
        self._held = (
            set(self.active_set.intersection(held))
            if held and reply.open_round == self._round
            else set()
        )
        self._phase, self._deadline = _COLLECT, now + self.times.move_timeout_s
        active, live = self._active_set, self._live
        # (every active robot live, as a lock step's: a copy of the set, no new hashing; every
        # robot of the run live: so is every active one, robots of this run that were live)
        everyone = len(live) == self._n or live.issuperset(active)
        self._waiting = set(active) if everyone else live.intersection(active)
        if self._held:
            self._waiting -= self._held
        if self._waiting and now < self._deadline:  # (`_collected` would wait: saved a call)
            return []
        return self._collected(now)

    def _collected(self, now: float) -> list[Action]:
        """COLLECT: every live active robot's move held, or the deadline -> Commit."""
        assert self._deadline is not None
        if self._waiting and now < self._deadline:
            return []
        planned, held, round_no = self._planned, self._held, self._round
        active = planned[1] if planned is not None and planned[0] == round_no else ()
        timed_out = (
            ()
            if len(held) == len(self._active_set) or held.issuperset(active)  # (held: of active)
            else tuple(r for r in active if r not in held)
        )
        self._phase, self._deadline = _COMMIT, None
        began = self._began_at
        paced = began is not None and now < began + self.times.pace_s
        self._chained = (
            bool(self._live) and not paced and not (self._gone_at and self.rejoining(now))
        )
        then = self._plan(round_no + 1) if self._chained else ()
        self._asked_at = now
        return [Ask(Commit(round=round_no, timed_out=timed_out, then_active=then))]

    def _on_committed(self, reply: ControlReply | None, now: float) -> list[Action]:
        if reply is None or not reply.ok:
            # The world restarted and lost the open round (or the reply was lost): ask where it
            # stands, and open the round it has not committed again.
            why = "no answer" if reply is None else reply.reason
            self._note(f"commit of round {self._round} failed: {why}", warning=True)
            return self._ask_hello()
        if reply.timed_out:  # the world's record, not what this core heard (one notice a round)
            self._note(f"round {self._round}: no move from {list(reply.timed_out)}")
        if reply.status != _RUNNING:
            return self._finish(Status(reply.status))
        if self._chained and reply.open_round == reply.committed + 1 == self._round + 1:
            self._round += 1  # the world opened the next round with the commit
            self._take_plan()
            self._began_at = self._asked_at
            return self._on_begun(reply, now)
        return self._next_round(reply.committed + 1, now)


__all__ = [
    "Action",
    "Ask",
    "CoordinatorCore",
    "CoreMisuse",
    "Finished",
    "Note",
    "Phase",
    "RoundTimes",
]
