"""The asynchronous adversary: how long each robot computes and waits, in virtual time.

Under the async models a robot cycles Look, Compute, Move, Wait on its own clock. Time is virtual
and counted in robot radii travelled at unit speed: a move of length L lasts L. The adversary picks
each cycle's compute delay (Look to the start of the move) and wait (end of the move to the next
Look); the world does the rest (world/asynchrony.py). Every draw is a pure function of (seed,
robot, cycle), so lock step, a networked run and a resumed run see the same adversary.
"""

from __future__ import annotations

import enum
import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

from fatswarm.domain.draws import DELAY_STREAM, keyed_fraction

RANDOM_MAX: Final = 2.0
"""Random delays: compute delay and wait are each uniform on [0, RANDOM_MAX): up to the time a
robot takes to travel its own diameter."""
STALE_STEP: Final = 2.0
"""Slowest robot last: the robot of rank k (0 fastest) computes for k * STALE_STEP."""
STALE_WAIT: Final = 1.0
"""Slowest robot last: every robot waits this long after a move before its next Look (a robot
that keeps asking to stay thus still lets time pass)."""


class Delays(enum.Enum):
    """The adversary's delay policies; the model's scheduler name says which."""

    RANDOM = "async"
    SLOWEST_LAST = "async-slowest"


ASYNC_NAMES: Final = tuple(policy.value for policy in Delays)


class NotRoundBasedError(RuntimeError):
    """An async model handed to something that runs rounds (a bug of the caller)."""


@dataclass(frozen=True, slots=True)
class Cycle:
    """One cycle's delays: compute (the Look to the start of its move) and wait (the end of the
    move, or the Look when it asks to stay, to the next Look)."""

    compute: float
    wait: float


@dataclass(frozen=True, slots=True)
class AsyncModel:
    """An async model: the policy and the seed of its draws. It takes a scheduler's place in a
    run's configuration (`name` is the scheduler name) but has no rounds to activate."""

    policy: Delays
    seed: int
    n: int

    @property
    def name(self) -> str:
        return self.policy.value

    def active(self, round_no: int, live: Sequence[int]) -> list[int]:
        """Not defined: async robots are not activated in rounds (world/asynchrony.py)."""
        del round_no, live
        raise NotRoundBasedError(f"the {self.name} model has no rounds; run it with run_async")

    def first_look(self, robot: int) -> float:
        """The virtual time of robot `robot`'s first Look."""
        if self.policy is Delays.SLOWEST_LAST:
            return 0.0  # everyone sees the start; the slowest moves last, on that snapshot
        return RANDOM_MAX * keyed_fraction(DELAY_STREAM, self.seed, robot, 0, 2)

    def cycle(self, robot: int, cycle: int) -> Cycle:
        """The delays of robot `robot`'s cycle `cycle` (1 for the cycle of its first Look)."""
        if self.policy is Delays.SLOWEST_LAST:
            return Cycle(STALE_STEP * self.rank(robot), STALE_WAIT)
        return Cycle(
            RANDOM_MAX * keyed_fraction(DELAY_STREAM, self.seed, robot, cycle, 0),
            RANDOM_MAX * keyed_fraction(DELAY_STREAM, self.seed, robot, cycle, 1),
        )

    def rank(self, robot: int) -> int:
        """Robot `robot`'s place from fastest (0) to slowest (n - 1), drawn from the seed."""
        return _ranks(self.seed, self.n)[robot]

    def bound(self) -> float:
        """The fairness bound: a live robot's next Look comes at most this long after the end of
        its move (or after its Look when it asked to stay)."""
        if self.policy is Delays.SLOWEST_LAST:
            return STALE_STEP * (self.n - 1) + STALE_WAIT
        return 2 * RANDOM_MAX


@functools.lru_cache(maxsize=8)
def _ranks(seed: int, n: int) -> tuple[int, ...]:
    """Every robot's rank (`AsyncModel.rank`), drawn once per run rather than once per cycle."""
    keys = [keyed_fraction(DELAY_STREAM, seed, r, 0, 3) for r in range(n)]
    order = sorted(range(n), key=lambda r: (keys[r], r))
    ranks = [0] * n
    for place, robot in enumerate(order):
        ranks[robot] = place
    return tuple(ranks)


def make_async(name: str, n: int, seed: int) -> AsyncModel:
    """The async model of scheduler name `name` ('async' or 'async-slowest')."""
    return AsyncModel(Delays(name), seed, n)


__all__ = ["ASYNC_NAMES", "AsyncModel", "Cycle", "Delays", "NotRoundBasedError", "make_async"]
