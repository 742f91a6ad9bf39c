"""How the world core is joined to its model of time: rounds of physics (`world.rounds`) or async
robots on their own clocks (`world.instants`).

The core keeps the books (positions, the open round, who looked and moved, agents, the tracker) and
answers looks and moves; a model opens and commits what the coordinator asks, through `Books`.
"""

from __future__ import annotations

from collections.abc import Collection, KeysView, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Path, Points
from fatswarm.domain.quick import quick_init
from fatswarm.world.effects import Effect
from fatswarm.world.looks import Looks
from fatswarm.world.physics import Collision
from fatswarm.world.progress import ProgressTracker
from fatswarm.world.protocol import Begin, Commit
from fatswarm.world.record import LineMoves
from fatswarm.world.setup import WorldSetup


@quick_init
@dataclass(frozen=True, slots=True, kw_only=True)
class RoundBooking:
    """One committed round as the core books it (`Books.account`): live, from the model that
    committed it, or replayed from a record. Positions are (n, 2), world frame."""

    round: int
    active: Sequence[int]
    # the moves applied (non-empty), world frame, from `before`; or the common round's (every
    # path one Line) as arrays, what the round line holds (`LineMoves`: movers, ends, traveled)
    paths: Mapping[int, Path] | LineMoves
    timed_out: Collection[int]  # active robots without a move
    before: Points
    after: Points
    traveled: Mapping[int, float] | None  # the arc length each mover covered (None: LineMoves')
    collisions: Sequence[Collision]
    crashed: Collection[int] = ()  # robots that count as crashed from this round (agents gone)
    recovered: Collection[int] = ()  # crashed robots whose agent is back
    stuck: Collection[int] = ()  # robots the crash adversary crashes in this round, for good
    relit: bool = False  # a colour changed: the configuration changed, though none may have moved
    # the paths' lengths physics measured, where it did; with LineMoves, an array of every one
    # in its order, or None: measured here as physics does (`0.0 + math.hypot`)
    lengths: Mapping[int, float] | NDArray[np.float64] | None = None
    # the round line's other fields (`RoundEntry.extra`): its `failed` robots stayed without
    # asking to, and the run's figures derived from the line (failures) count them
    line: Mapping[str, Any] | None = None


class Books(Protocol):
    """What a model sees and keeps of the world core's state (`world.core.WorldCore`)."""

    setup: WorldSetup
    positions: Points  # (n, 2), world frame
    status: Status
    committed: int  # the last committed round (an async run: instant)
    open_round: int  # 0 while none is open
    active: tuple[int, ...]
    active_set: frozenset[int]
    looked: set[int]
    held: dict[int, Path]  # moves of the open round, world axes, relative to each robot
    held_colours: dict[int, int]  # the colours of the held moves (a luminous algorithm's)
    failed: dict[int, str]  # held robots of the open round whose compute raised: why
    looks: Looks  # what each robot sees, and every robot's colour
    missing: set[int]  # live active robots of the open round without a move
    noticed: tuple[int, tuple[int, ...]] | None  # the last moves notice sent
    alive: list[bool]
    gone_since: list[int | None]
    last_active: list[int]
    last_length: list[float]
    timeouts: list[int]
    moved: tuple[int, ...]
    stopped: tuple[int, ...]
    collisions_total: int
    stuck: frozenset[int]  # robots the crash adversary crashed, for good
    crash_plan: dict[int, int]  # robot -> the round (an async run: cycle) it crashes in
    tracker: ProgressTracker
    last_timed_out: tuple[int, ...]

    def held_robots(self) -> KeysView[int]: ...  # `held`'s keys, no Path made

    def held_lines(self) -> tuple[NDArray[np.intp], Points] | None: ...  # the moves as arrays

    def emit(self, effect: Effect) -> None: ...

    def views_changed(self) -> None: ...

    def account(self, booking: RoundBooking) -> None: ...

    def finish(self) -> None: ...


Answer = tuple[str | None, bool]  # why a model refused a request (None: taken), and whether the
# state changed: the core makes the one reply from it and the state after (`WorldCore.control`)


class Model(Protocol):
    """What the world core asks of its model: open and commit, and the fields it adds."""

    def begin(self, req: Begin) -> Answer:
        """Open what `req` asks; why not (None: taken), and whether the state changed."""
        ...

    def commit(self, req: Commit) -> Answer:
        """Commit what `req` asks; why not (None: taken), and whether the state changed."""
        ...

    def reply_fields(self) -> dict[str, Any]:
        """Fields of every control reply beyond the core's (an async run's clock)."""
        ...

    def result_fields(self) -> dict[str, Any]:
        """Fields of the record's result line beyond the core's (an async run's end time)."""
        ...

    def time(self) -> float | None:
        """The virtual time now (async models), else None."""
        ...


__all__ = ["Answer", "Books", "Model", "RoundBooking"]
