"""Progress of a run: rounds, epochs, moves, distance, collisions and when (and how) it ends.

Pure bookkeeping fed one committed round at a time, shared by the lockstep runner and the networked
world so both decide `formed`, `stalled` and `max_rounds` the same way.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterable, Mapping, Sequence, Set
from dataclasses import dataclass, field
from typing import Any, Final

import numpy as np

from fatswarm.domain.figures import FigureValue, RunFolder
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Points, float64_array
from fatswarm.domain.quick import quick_new

# A robot "moved" (the configuration changed) when its centre shifted by more than this. Far above
# float noise at coordinates ~1e3 (~1e-13), far below any planned move (>= ~1e-6, the algorithm's
# "at a point" tolerance); a path fully blocked at its start leaves the configuration unchanged.
MOVE_TOLERANCE: Final = 1e-9
FEW_SHIFTS: Final = 4  # up to this many robots, `configuration_changed` reads shifts in Python


@dataclass(frozen=True, slots=True)
class Progress:
    """A snapshot of the run's figures; `status` is None while the run goes on.

    `epochs` counts completed epochs: an epoch ends when every robot has been active at least
    once since the previous epoch ended (under fsync, epochs == rounds).
    """

    status: Status | None
    rounds: int
    epochs: int
    moves: int
    total_distance: float
    collisions: int
    moves_by_robot: tuple[int, ...]
    crashed: tuple[int, ...] = ()  # the robots that count as crashed now, sorted
    # the figures that follow from the positions (fatswarm.domain.figures), each summarised over
    # the rounds so far as declared (min_gap: its minimum), by name; None before any round
    derived: Mapping[str, FigureValue] = field(default_factory=dict)


class ProgressTracker:
    """Observes committed rounds of an n-robot run and decides when it ends.

    A crashed robot (`crash`) counts as active and staying in every round.

    formed:  the algorithm's goal holds for the configuration and every robot has been active
             since the configuration last changed, each time asking for an empty path (an async
             line whose Look came before the last change, `stale`, counts for neither);
    stalled: every robot has been active since the last change, the configuration is unchanged
             and it is not formed (someone wants to move but cannot, or nobody wants to move);
    max_rounds: `max_rounds` rounds were committed without either of the above.
    """

    def __init__(
        self, n: int, goal: Callable[[Points], bool], max_rounds: int | None = None
    ) -> None:
        if n < 1:
            raise ValueError(f"a run needs at least one robot, got n={n}")
        if max_rounds is not None and max_rounds < 1:
            raise ValueError(f"max_rounds must be >= 1, got {max_rounds}")
        self.n = n
        self.goal = goal
        self.max_rounds = max_rounds
        self._rounds = 0
        self._epochs = 0
        # moves by robot: `_everyone` rounds in which every robot moved once, plus `_moves`, those
        # of the other rounds (`_some`: some such round was counted, so `_moves` may not be 0s)
        self._moves = [0] * n
        self._everyone = 0
        self._some = False
        self._robots = frozenset(range(n))
        self._every_robot = range(n)  # `observe`'s movers when every robot moved, each once
        # the last active tuple given whose robots were each of 0..n-1, and its set (not changed):
        # a round's active robots are often the last round's (every robot, under fsync)
        self._active_known: tuple[tuple[int, ...], Set[int]] = ((), frozenset())
        self._distance = 0.0
        self._collisions = 0
        self._epoch_seen: set[int] = set()
        self._seen_since_change: set[int] = set()
        self._wanting_since_change: set[int] = set()
        self._status: Status | None = None
        self._crashed: set[int] = set()
        self._derived = RunFolder()

    def crash(self, robots: Iterable[int]) -> None:
        """These robots count as crashed: still obstacles, no longer waited for (seen as staying
        in every round), until `recover` says otherwise."""
        self._crashed |= {int(r) for r in robots}

    def recover(self, robots: Iterable[int]) -> None:
        """These robots are back: waited for again."""
        self._crashed -= {int(r) for r in robots}

    @property
    def crashed(self) -> frozenset[int]:
        return frozenset(self._crashed)

    @property
    def status(self) -> Status | None:
        """How the run ended (formed, stalled, max_rounds), or None while it goes on."""
        return self._status

    @property
    def done(self) -> bool:
        return self._status is not None

    def observe(
        self,
        active: Iterable[int],
        movers: Collection[int],
        before: Points,
        after: Points,
        traveled: Mapping[int, float] | Sequence[float] | None = None,
        collisions: int = 0,
        changed: bool | None = None,
        line: Mapping[str, Any] | None = None,
        stale: bool = False,
    ) -> Status | None:
        """Account one committed round; returns the status (None while the run goes on).

        `movers`: the active robots that asked for a non-empty path; `before`/`after`: (n, 2)
        positions around the round; `traveled`: arc length each mover covered (by robot, or in
        the order of `movers`: the distance adds them in that order). `changed`: whether
        the configuration changed, if the caller knows better than `before`/`after` (an async
        cycle whose move ended at the instant of the previous line moved all the same).
        `line`: the round line's other fields (`RoundEntry.extra`): its `failed` robots stayed
        without asking to (a run cannot be formed while one fails), and the figures derived
        from the line (failures) count them. `stale`:
        the robots of this line Looked before the last change (an async cycle booked after a move
        that ended while it computed or moved): they saw the old configuration, so they count
        neither as having seen this one nor as wanting to move in it.
        """
        if self._status is not None:
            raise RuntimeError(f"the run already ended ({self._status}); no more rounds")
        n, robots = self.n, self._robots  # (each equal to one of 0..n-1: as its int, in a set)
        known = self._active_known
        active_set: Set[int]
        if active is known[0] or (type(active) is tuple and active == known[0]):  # as last round's
            active_set, active_ok = known[1], True
        else:
            active_set = set(active)
            active_ok = robots.issuperset(active_set)
            if active_ok and type(active) is tuple:
                self._active_known = (active, active_set)  # (never changed: unions make new)
        if type(movers) is range and movers == self._every_robot:  # every robot, each once
            mover_set: Set[int] = robots
            everyone = each_once = active_ok
        else:
            mover_set = set(movers)
            each_once = active_ok and robots.issuperset(mover_set)
            everyone = each_once and len(mover_set) == len(movers) == n  # every robot, once
        if not each_once:  # some robot is not an int of 0..n-1: as its int, or refused
            active_set = set(map(int, active))
            if _outside(active_set, n) or _outside(movers, n):
                bad = [r for r in active_set | mover_set if not 0 <= r < n]
                raise ValueError(f"robots {sorted(bad)} are not in 0..{n - 1}")
        if self._crashed:  # a crashed robot stays, as if active and asking to stay
            active_set = active_set | self._crashed
        self._count(active_set, movers, everyone, traveled, collisions)
        before_arr, after_arr = float64_array(before), float64_array(after)
        self._derived.add(after_arr, self._rounds, line)
        if changed if changed is not None else configuration_changed(before_arr, after_arr):
            # The robots active this round looked at the old configuration: start counting afresh.
            if self._seen_since_change:
                self._seen_since_change = set()
            if self._wanting_since_change:
                self._wanting_since_change = set()
        else:
            failed = line.get("failed") if line else None
            if not stale:
                self._seen_since_change |= active_set
                self._wanting_since_change |= mover_set
                if failed:
                    self._wanting_since_change |= {int(r) for r in failed}
            if len(self._seen_since_change) == n:
                formed = not self._wanting_since_change and bool(self.goal(after_arr))
                self._status = Status.FORMED if formed else Status.STALLED
        if self._status is None and self.max_rounds is not None and self._rounds >= self.max_rounds:
            self._status = Status.MAX_ROUNDS
        return self._status

    def _count(
        self,
        active: Set[int],
        movers: Collection[int],
        everyone: bool,
        traveled: Mapping[int, float] | Sequence[float] | None,
        collisions: int,
    ) -> None:
        """The round's figures: rounds, moves, distance, collisions and epochs (`everyone`: the
        movers are every robot, each once)."""
        self._rounds += 1
        if everyone:
            self._everyone += 1
        else:
            self._some = True
            moves = self._moves
            for robot in movers:
                moves[robot] += 1
        if traveled:
            each = traveled.values() if isinstance(traveled, Mapping) else traveled
            self._distance += float(sum(each))
        self._collisions += collisions
        if len(active) == self.n:  # every robot active (each of 0..n-1): the epoch ends
            self._epochs += 1
            if self._epoch_seen:
                self._epoch_seen = set()
            return
        self._epoch_seen |= active
        if len(self._epoch_seen) == self.n:
            self._epochs += 1
            self._epoch_seen = set()

    def snapshot(self) -> Progress:
        """The figures so far."""
        everyone, n = self._everyone, self.n
        if not self._some:  # (every round counted was one where every robot moved)
            by_robot, moves = (everyone,) * n, everyone * n
        else:
            by_robot = tuple(map(everyone.__add__, self._moves) if everyone else self._moves)
            moves = sum(by_robot)
        return _new_progress(
            status=self._status,
            rounds=self._rounds,
            epochs=self._epochs,
            moves=moves,
            total_distance=self._distance,
            collisions=self._collisions,
            moves_by_robot=by_robot,
            crashed=tuple(sorted(self._crashed)) if self._crashed else (),
            derived=self._derived.snapshot(),
        )


_new_progress: Final = quick_new(Progress)  # (built every round: no __init__ of 9 setattrs)


def _outside(robots: Collection[int], n: int) -> bool:
    """Whether some of `robots` are not robots of an n-robot run (not in 0..n-1)."""
    return bool(robots) and (min(robots) < 0 or max(robots) >= n)


def configuration_changed(before: Points, after: Points) -> bool:
    """True when some robot's centre moved by more than MOVE_TOLERANCE."""
    if before.shape != after.shape:
        raise ValueError(f"positions changed shape: {before.shape} -> {after.shape}")
    if before.size == 0:
        return False
    delta = after - before
    if delta.size <= 2 * FEW_SHIFTS:  # the shifts as Python floats (fewer numpy calls)
        shifts = list(map(abs, delta.ravel().tolist()))
        total = sum(shifts)  # (of non-negatives: NaN or infinite just when one is, or it grew so)
        if total - total == 0.0:  # every one finite: the largest says it, unless it is near
            most = max(shifts)
            if most > MOVE_TOLERANCE:
                return True
            if most <= 0.5 * MOVE_TOLERANCE:  # hypot(dx, dy) <= sqrt(2) * most < the tolerance
                return False
    if np.abs(delta).max() > MOVE_TOLERANCE:  # hypot(dx, dy) >= |dx|, |dy|: some shift is above
        return True
    shift = np.hypot(delta[:, 0], delta[:, 1])  # (NaN, or every |dx|, |dy| within: measured)
    return bool(shift.max() > MOVE_TOLERANCE)


__all__ = [
    "MOVE_TOLERANCE",
    "Progress",
    "ProgressTracker",
    "configuration_changed",
]
