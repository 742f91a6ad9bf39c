"""The coordinator under an async model: the adversary and the virtual clock, as a sans-IO state
machine on `CoordinatorCore`'s protocol.

Each protocol round is an instant of virtual time: the coordinator opens it for the robots whose
Look is due then (`Begin.at`, read off the world's last reply), gives robots their first Look
times (`Begin.looks`), and with the Commit hands the world the adversary's delays for each cycle
begun (`Commit.delays`). The world runs the moves in between and says, in each reply, who Looks
next and when; a Begin it cannot open yet (a move ended first) is answered with the new plan and
asked again at once. Hello, agents, timeouts and restarts are `CoordinatorCore`'s.

The core keeps nothing the world does not: each instant is planned from the world's last reply,
and each cycle's delays are drawn for the cycle the world says the robot began (`cycles` of the
reply that opened it; the draws are pure functions of seed, robot and cycle). So a coordinator
restarted mid-run asks the world where it stands and goes on as the one before it would have.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Final

from fatswarm.coordinator.rounds import (
    Action,
    Ask,
    CoordinatorCore,
    CoreMisuse,
    Phase,
    RoundTimes,
)
from fatswarm.coordinator.schedule import Scheduler
from fatswarm.domain.adversary import ASYNC_NAMES, AsyncModel
from fatswarm.world.protocol import Begin, Commit, ControlReply

_BEGIN: Final = Phase.BEGIN  # (read off its Enum class once: ~20 times a global's cost a read)
MAX_REPLANS: Final = 1_000_000  # Begins the world may answer "not yet" in a row (each a move's
# end): far above any run; past it the world and the coordinator disagree (a bug), said plainly


class AsyncCoordinatorCore(CoordinatorCore):
    """`CoordinatorCore` driving an async model's instants instead of a scheduler's rounds."""

    def __init__(
        self,
        make_model: Callable[[int], Scheduler],
        times: RoundTimes,
        resume_live: Sequence[int] | None = None,
    ) -> None:
        super().__init__(make_model, times, resume_live)
        self._last: ControlReply | None = None
        self._at: float | None = None
        self._first: tuple[tuple[int, float], ...] = ()
        self._cycles: dict[int, int] = {}  # the open instant's robots: the cycle each began
        self._replans = 0

    def on_reply(self, reply: ControlReply | None, now: float) -> list[Action]:
        if reply is not None and reply.ok:
            self._last = reply
        if (
            self.phase is _BEGIN
            and reply is not None
            and reply.ok
            and reply.open_round != self.round
            and reply.status == "running"
            and reply.committed + 1 == self.round
        ):
            return self._replan(now)  # not opened: the world got to another instant first
        return super().on_reply(reply, now)

    def _catch_up(self, committed: int) -> None:
        """Nothing to advance: the adversary's draws are keyed by the world's cycle counts."""
        self._note(f"resuming after instant {committed}")

    @property
    def model(self) -> AsyncModel:
        """The adversary (made for the world's n at the first Hello)."""
        if not isinstance(self._scheduler, AsyncModel):
            raise CoreMisuse(f"an async coordinator needs an async model, not {self._scheduler}")
        return self._scheduler

    def _plan(self, round_no: int) -> tuple[int, ...]:
        """The instant `round_no`: the robots whose Look comes first, and when (first Looks for
        robots the world has none for)."""
        del round_no
        self._plan_over_live()
        last = self._last
        if last is None:
            return ()
        first = tuple((r, self.model.first_look(r)) for r in last.unset)
        times = [*last.looks, *first]
        if not times:
            return ()
        at = min(t for _, t in times)
        self._at, self._first = at, first
        return tuple(sorted(r for r, t in times if t == at))

    def _take_plan(self) -> None:
        self._planned = None  # every Begin is planned from the world's latest word
        self._next = None
        super()._take_plan()

    def _begin(self, now: float) -> list[Action]:
        self._take_plan()
        if not self.active:
            return self._retry(now)  # nothing to plan from yet: ask the world again
        self._began_at = self._asked_at = now
        self._phase, self._deadline = _BEGIN, None
        return [Ask(Begin(round=self.round, active=self.active, at=self._at, looks=self._first))]

    def _replan(self, now: float) -> list[Action]:
        self._replans += 1
        if self._replans > MAX_REPLANS:
            self._note(
                f"the world did not open instant {self.round} after {MAX_REPLANS} plans",
                warning=True,
            )
            return self._retry(now)
        return self._begin(now)

    def _on_begun(self, reply: ControlReply | None, now: float) -> list[Action]:
        if reply is not None and reply.ok and reply.open_round == self.round:
            self._replans = 0
            self._cycles = dict(reply.cycles)
        return super()._on_begun(reply, now)

    def _collected(self, now: float) -> list[Action]:
        actions = super()._collected(now)
        if not (
            actions and isinstance(actions[-1], Ask) and isinstance(actions[-1].request, Commit)
        ):
            return actions
        self._chained = False  # the next instant depends on what this one commits
        delays = []
        for robot in self.active:
            cycle = self.model.cycle(robot, self._cycles.get(robot, 1))  # (a crashed one's unused)
            delays.append((robot, cycle.compute, cycle.wait))
        commit = Commit(
            round=self.round, timed_out=actions[-1].request.timed_out, delays=tuple(delays)
        )
        return [*actions[:-1], Ask(commit)]


def coordinator_core(
    name: str,
    make_scheduler: Callable[[int], Scheduler],
    times: RoundTimes,
    resume_live: Sequence[int] | None = None,
) -> CoordinatorCore:
    """The coordinator core for scheduler `name`: `AsyncCoordinatorCore` for an async model."""
    if name in ASYNC_NAMES:
        return AsyncCoordinatorCore(make_scheduler, times, resume_live)
    return CoordinatorCore(make_scheduler, times, resume_live)


__all__ = ["AsyncCoordinatorCore", "coordinator_core"]
