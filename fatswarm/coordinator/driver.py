"""The one loop that drives a coordinator core: its actions out, the world's replies and the swarm's
events in, its deadlines kept, on a clock and a transport the caller plugs in.

The networked coordinator (coordinator/service.py) runs it with the wall clock and Zenoh; the lock
step (deploy/engine/lockstep.py) with a virtual clock and the world core in the same process. No
I/O here: the link does it all.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Generator, Sequence
from dataclasses import dataclass
from typing import Protocol, TypeVar

from fatswarm.coordinator.rounds import Action, CoordinatorCore, Finished, Note
from fatswarm.world.protocol import ControlReply, ControlRequest, MovesHeld


@dataclass(frozen=True, slots=True)
class WorldSeen:
    """The world's liveliness token came (True) or went (False)."""

    alive: bool


@dataclass(frozen=True, slots=True)
class AgentSeen:
    """Robot `robot`'s agent came (True) or went (False)."""

    robot: int
    alive: bool


Event = WorldSeen | AgentSeen | MovesHeld


class Link(Protocol):
    """The coordinator's clock and transport: what `drive` needs of the world around it."""

    def now(self) -> float:
        """The time on this link's clock (seconds; virtual in a lock step)."""
        ...

    def ask(self, request: ControlRequest) -> ControlReply | None:
        """Send a control request to the world; its reply, or None if none came."""
        ...

    def wait(self, deadline: float | None) -> Sequence[Event] | None:
        """The events that come before `deadline` (None: no deadline), at least one unless the
        deadline passes first; None once nothing more can come (stopped)."""
        ...

    def stopped(self) -> bool:
        """Whether to stop now (a signal came): the core is stopped, whatever it waits for."""
        ...

    def note(self, notes: Sequence[Note]) -> None:
        """Say what the core noted (a log, or nothing)."""
        ...


def drive(core: CoordinatorCore, link: Link) -> Finished:
    """Run `core` on `link` until it finishes (or the link stops: the core is stopped then)."""
    return run_out(driving(core, link))


def driving(core: CoordinatorCore, link: Link) -> Generator[None, None, Finished]:
    """`drive`'s loop, one exchange at a time: it yields after each request the world answered
    (all a world changes on) and returns how the core finished. A lock step advances it round by
    round (deploy/engine/lockstep.py); `drive` runs it out."""
    now, stopped, pop_notes = link.now, link.stopped, core.pop_notes  # (looked up once)
    todo: deque[Action] = deque(core.start(now()))
    while not stopped():
        notes = pop_notes()
        if notes:
            link.note(notes)
        if not todo:
            events = link.wait(core.next_deadline())
            if events is None:
                break
            for event in events:
                todo.extend(feed(core, event, now()))
            if not todo:  # (else an Ask is out: the core waits on its reply, and no deadline)
                todo.extend(core.on_tick(now()))
            continue
        action = todo.popleft()
        if isinstance(action, Finished):
            link.note(pop_notes())
            return action
        todo.extend(core.on_reply(link.ask(action.request), now()))
        yield
    finished = core.stop()
    link.note(pop_notes())
    return finished


T = TypeVar("T")


def run_out(steps: Generator[None, None, T]) -> T:
    """Advance `steps` to its end; what it returns."""
    while True:
        try:
            next(steps)
        except StopIteration as done:
            return done.value  # type: ignore[no-any-return]


def feed(core: CoordinatorCore, event: Event, now: float) -> list[Action]:
    """Hand one event to the core; the actions it asks for."""
    if type(event) is MovesHeld:  # (the one event of every round)
        return core.on_held(event, now)
    if isinstance(event, WorldSeen):
        return core.on_world(event.alive, now)
    if isinstance(event, AgentSeen):
        return core.on_alive(event.robot, event.alive, now)
    return core.on_held(event, now)


__all__ = ["AgentSeen", "Event", "Link", "WorldSeen", "drive", "driving", "feed", "run_out"]
