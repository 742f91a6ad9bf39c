"""The asynchronous world: robots Look, Compute, Move and Wait each on its own clock, in virtual
time, and moves that start at different times run through the same continuous collision
detection as a round's.

Time is virtual, in robot radii travelled at unit speed. A Look sees every robot where it is at
that instant, those in the middle of a move included. Between two events (a Look, the start or
the end of a move) the set of movers is fixed, so the world applies each such window as a round
of `world.physics.apply_round`: every mover covers its path for the window's length, from where
it is, and a mover that would overlap another stops at contact. A stopped mover's move ends with
the window (the adversary's wait may be longer than it chose: the wait is any finite delay).
A Look that asks to stay ends its cycle at once. Each ended cycle is one `CycleDone`: the run
record keeps one line per cycle, in the order they end (docs/record.md).

No I/O, clock or global random state: the delays come from the caller (the adversary,
fatswarm/domain/adversary.py), so the same core serves lock step and a networked run.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Final

import numpy as np

from fatswarm.domain.path import Path, Point, Points, path_length, remainder, truncate
from fatswarm.domain.tolerance import snap
from fatswarm.world.physics import Collision, apply_round

ENDED: Final = 1e-9
"""A move with less than this left (robot radii) has ended: far below any planned move, far above
the rounding of virtual times of a few thousand."""


class Phase(enum.Enum):
    """Where a robot is in its cycle."""

    WAITING = "waiting"  # until its next Look
    COMPUTING = "computing"  # Looked; its move starts at `at`
    MOVING = "moving"


# The phases read off their Enum class once: under CPython 3.11 a member read off its class costs
# about 20 times a global (the metaclass's __getattr__ hook), and the clock reads them per robot
_WAITING, _COMPUTING, _MOVING = Phase.WAITING, Phase.COMPUTING, Phase.MOVING


@dataclass(slots=True)
class _Robot:
    """One robot's cycle in progress (the core's own mutable bookkeeping)."""

    at: float  # WAITING: its next Look; COMPUTING: its move's start
    phase: Phase = _WAITING
    cycle: int = 0  # cycles begun (its Looks)
    look: float = 0.0
    start: float = 0.0
    origin: Point = (0.0, 0.0)  # where the move starts (where it Looked: it stays while computing)
    path: Path = field(default_factory=Path)  # the whole move, world frame
    rest: Path = field(default_factory=Path)  # what is left of it, from where the robot is
    left: float = 0.0
    traveled: float = 0.0
    wait: float = 0.0
    cut: bool = False
    stopped: bool = False
    collisions: list[Collision] = field(default_factory=list)


@dataclass(frozen=True, slots=True)
class CycleDone:
    """One robot's ended cycle: its Look, the start and end of its move (virtual times; a cycle
    that asked to stay has start = end = look and an empty path), the world-frame path from
    `origin`, the arc length covered, every robot's position at `end`, the contacts that stopped
    it (`t`: arc length along its path) and whether the non-rigid adversary cut it."""

    robot: int
    cycle: int
    look: float
    start: float
    end: float
    origin: Point
    path: Path
    traveled: float
    positions: Points
    collisions: tuple[Collision, ...]
    cut: bool


class AsyncWorld:
    """The positions of n unit discs in virtual time and every robot's cycle.

    Drive it event by event: `next_time`, `advance` to it, `end_moves`, `start_moves`, then begin
    the cycle of each due robot (`looking`, `begin_cycle`) and `submit` its path with its delays
    (the world core serves the Looks themselves from `positions`).
    """

    def __init__(
        self, positions: Points, first_looks: Sequence[float], *, points: bool = False
    ) -> None:
        """`first_looks`: each robot's first Look time; math.inf for one the adversary sets
        later (`set_look`). `points`: point robots (no contact: `apply_round`)."""
        self.points = points
        self.positions: Points = snap(np.array(positions, dtype=np.float64))
        self.n = len(self.positions)
        if len(first_looks) != self.n:
            raise ValueError(f"{len(first_looks)} first Looks for {self.n} robots")
        self.now = 0.0
        self.crashed: set[int] = set()
        self._robots = [_Robot(at=float(t)) for t in first_looks]

    def next_time(self) -> float:
        """The next event: a Look, the start or the natural end of a move (never before now)."""
        times = []
        for r, robot in enumerate(self._robots):
            if r in self.crashed and robot.phase is not _MOVING:
                continue
            times.append(self.now + robot.left if robot.phase is _MOVING else robot.at)
        return max(self.now, min(times)) if times else self.now

    def phase(self, robot: int) -> Phase:
        return self._robots[robot].phase

    def moving(self) -> list[int]:
        return [r for r, robot in enumerate(self._robots) if robot.phase is _MOVING]

    def advance(self, t: float) -> None:
        """Move every mover on to virtual time `t` (one window of physics; contacts stop)."""
        dt = t - self.now
        if dt < 0:
            raise ValueError(f"time runs forward: {t} is before {self.now}")
        movers = self.moving()
        if dt > 0 and movers:
            here = {r: (float(self.positions[r, 0]), float(self.positions[r, 1])) for r in movers}
            window = {r: truncate(here[r], self._robots[r].rest, dt) for r in movers}
            outcome = apply_round(self.positions, window, points=self.points)
            for r in movers:
                robot = self._robots[r]
                covered = float(outcome.traveled.get(r, 0.0))
                for c in outcome.collisions:
                    if c.robot == r:
                        robot.collisions.append(
                            Collision(r, c.other, robot.traveled + c.t, c.point)
                        )
                        robot.stopped = True
                robot.traveled += covered
                robot.rest = remainder(here[r], robot.rest, covered)
            self.positions = np.asarray(outcome.positions, dtype=np.float64)
            for r in movers:  # what is left, measured from where the robot is (on the grid)
                robot = self._robots[r]
                there = (float(self.positions[r, 0]), float(self.positions[r, 1]))
                robot.left = path_length(there, robot.rest) if robot.rest else 0.0
        self.now = max(self.now, t)

    def end_moves(self) -> list[CycleDone]:
        """The moves that ended by now (their whole path, or stopped by contact), robots in
        order; each robot then waits its cycle's wait before its next Look."""
        done = []
        for r, robot in enumerate(self._robots):
            if robot.phase is _MOVING and (robot.left <= ENDED or robot.stopped):
                robot.phase, robot.at = _WAITING, self.now + robot.wait
                done.append(self._done(r, self.now))
        return done

    def start_moves(self) -> None:
        """The computed moves whose start has come begin (robots in order)."""
        for robot in self._robots:
            if robot.phase is _COMPUTING and robot.at <= self.now:
                robot.phase, robot.start = _MOVING, self.now  # from where it Looked

    def looking(self) -> list[int]:
        """The live robots whose Look is due now, in order."""
        return [
            r
            for r, robot in enumerate(self._robots)
            if robot.phase is _WAITING and robot.at <= self.now and r not in self.crashed
        ]

    def set_look(self, robot: int, t: float) -> None:
        """Robot `robot`'s first Look comes at `t` (the adversary's choice); only for a robot
        waiting with no Look time yet. Raises ValueError otherwise, or for a time in the past."""
        state = self._robots[robot]
        if state.phase is not _WAITING or math.isfinite(state.at):
            raise ValueError(f"robot {robot} already has its next Look at {state.at}")
        if not math.isfinite(t) or t < self.now:
            raise ValueError(f"robot {robot}'s Look at {t} is not a time from now ({self.now}) on")
        state.at = float(t)

    def looks(self) -> tuple[list[tuple[int, float]], list[int]]:
        """(each live waiting robot's next Look time, the live waiting robots without one)."""
        known, unset = [], []
        for r, state in enumerate(self._robots):
            if state.phase is _WAITING and r not in self.crashed:
                if math.isfinite(state.at):
                    known.append((r, state.at))
                else:
                    unset.append(r)
        return known, unset

    def begin_cycle(self, robot: int) -> None:
        """Robot `robot` Looks now: its next cycle begins (it must be due)."""
        state = self._robots[robot]
        state.cycle += 1
        state.look = self.now

    def cycle_of(self, robot: int) -> int:
        """Robot `robot`'s cycles begun (the one in progress counted)."""
        return self._robots[robot].cycle

    def submit(
        self, robot: int, path: Path, compute: float, wait: float, *, cut: bool = False
    ) -> CycleDone | None:
        """Robot `robot`'s move (world frame, from where it is) after its Look now, starting after
        `compute`, then `wait` before its next Look. A path of length zero ends the cycle at once
        (returned); the next Look then comes after compute + wait."""
        state = self._robots[robot]
        origin = (float(self.positions[robot, 0]), float(self.positions[robot, 1]))
        length = path_length(origin, path) if path else 0.0
        state.origin, state.path, state.rest, state.left = origin, path, path, length
        state.traveled, state.wait, state.cut, state.stopped = 0.0, wait, cut, False
        state.collisions = []
        if length <= ENDED:
            state.start = self.now
            state.phase, state.at = _WAITING, self.now + compute + wait
            return self._done(robot, self.now)
        state.phase, state.at = _COMPUTING, self.now + compute
        return None

    def crash(self, robot: int) -> None:
        """Robot `robot` crashes instead of Looking (it is waiting): it never Looks again and
        stays where it is, a still obstacle."""
        if self._robots[robot].phase is not _WAITING:
            raise ValueError(f"robot {robot} crashes only between cycles")
        self.crashed.add(robot)

    def _done(self, r: int, end: float) -> CycleDone:
        robot = self._robots[r]
        return CycleDone(
            robot=r,
            cycle=robot.cycle,
            look=robot.look,
            start=robot.start,
            end=end,
            origin=robot.origin,
            path=robot.path,
            traveled=robot.traveled,
            positions=self.positions.copy(),
            collisions=tuple(robot.collisions),
            cut=robot.cut,
        )


__all__ = ["ENDED", "AsyncWorld", "CycleDone", "Phase"]
