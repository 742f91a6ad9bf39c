"""The world's state machine under an async model: `WorldCore`'s looks, moves and control
requests, with robots on their own clocks (world/asynchrony.py) instead of rounds of physics.

A protocol round is one instant of virtual time at which some robots Look (the coordinator, as
the adversary and the clock, names them and the instant in its Begin); their moves come back as
in a round, and the Commit hands the world each one's delays (compute, then wait). Between those
instants the world runs every move on its own: it commits each ended cycle as one record line
and goes on, event by event, to the next instant at which a Look is due, which its reply names.
The lock step drives this very core, so a networked async run and a lock-step one agree.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

from fatswarm.domain.adversary import ASYNC_NAMES, make_async
from fatswarm.domain.draws import cut_fraction
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Path, transform
from fatswarm.domain.seam import Configured
from fatswarm.world.asynchrony import AsyncWorld, CycleDone
from fatswarm.world.core import Committed, Journal, WorldCore, WorldSetup, cut_path
from fatswarm.world.physics import RoundOutcome
from fatswarm.world.progress import MOVE_TOLERANCE
from fatswarm.world.protocol import Begin, Commit, ControlReply
from fatswarm.world.record import RunRecord


class AsyncResumeError(ValueError):
    """An async run's record to resume: not supported (its moves in flight are not recorded)."""


def is_async(setup: WorldSetup) -> bool:
    """Whether `setup` runs an async model."""
    return setup.scheduler in ASYNC_NAMES


def make_world(
    setup: WorldSetup,
    journal: Journal | None = None,
    history: RunRecord | None = None,
    algorithm: Configured | None = None,
    epoch: int = 0,
) -> WorldCore:
    """The world core for `setup`: `AsyncWorldCore` under an async model, else `WorldCore`."""
    if is_async(setup):
        return AsyncWorldCore(setup, journal, history, algorithm, epoch)
    return WorldCore(setup, journal, history, algorithm, epoch)


class AsyncWorldCore(WorldCore):
    """`WorldCore` for the async models: `committed` counts instants; the record counts cycles."""

    def __init__(
        self,
        setup: WorldSetup,
        journal: Journal | None = None,
        history: RunRecord | None = None,
        algorithm: Configured | None = None,
        epoch: int = 0,
    ) -> None:
        if history is not None and (history.rounds or history.result is not None):
            raise AsyncResumeError(
                f"a {setup.scheduler} run cannot be resumed (yet): run it again with its seed"
            )
        model = make_async(setup.scheduler, setup.n, setup.seed)
        setup = dataclasses.replace(setup, extra={"fairness_time": model.bound(), **setup.extra})
        super().__init__(setup, journal, history, algorithm, epoch)
        self.clock = AsyncWorld(self.positions, [math.inf] * setup.n)
        self._last = self.positions.copy()
        self._delays: dict[int, tuple[float, float]] = {}
        self.last_cycle: CycleDone | None = None
        self.on_cycle: Callable[[CycleDone], None] | None = None  # e.g. a lock step's progress

    # -- control --------------------------------------------------------------------------------

    def reply(self, ok: bool, reason: str = "") -> ControlReply:
        base = super().reply(ok, reason)
        known, unset = self.clock.looks()
        return dataclasses.replace(base, now=self.clock.now, looks=tuple(known), unset=tuple(unset))

    def _begin(self, req: Begin) -> tuple[ControlReply, bool]:
        """Open the instant `req.at` for the robots due then, once the world has got there."""
        if req.round != self.committed + 1:
            return self.reply(False, f"next round is {self.committed + 1}, not {req.round}"), False
        if self.open_round == req.round and self.active == req.active:
            return self.reply(True), False  # a coordinator retrying: keep what is held
        if self.open_round:
            return self.reply(False, f"round {self.open_round} is open"), False
        if req.at is None:
            return self.reply(False, "an async world opens instants: Begin needs `at`"), False
        for robot, t in req.looks:
            if not 0 <= robot < self.setup.n:
                return self.reply(False, f"robot {robot} is not of this run"), False
            try:
                self.clock.set_look(robot, t)
            except ValueError as exc:
                return self.reply(False, str(exc)), False
        changed = self._settle()
        due = tuple(self.clock.looking())
        if (
            self.status != Status.RUNNING
            or not due
            or due != req.active
            or self.clock.now != req.at
        ):
            return self.reply(True), changed  # not opened: the reply says what is due, and when
        crashing = {r for r in due if self.crash_plan.get(r) == self.clock.cycle_of(r) + 1}
        for robot in sorted(crashing):
            self.clock.crash(robot)
            self.tracker.crash([robot])
        self.stuck = self.stuck | frozenset(crashing)
        for robot in due:
            if robot not in crashing:
                self.clock.begin_cycle(robot)
        self.open_round, self.active = req.round, due
        self._active_set = frozenset(due)
        # a crashed robot is held as staying: nobody waits for its agent
        self.looked, self.held, self._noticed = set(), {r: Path() for r in crashing}, None
        self._missing = {r for r in due if self.alive[r] and r not in crashing}
        return self.reply(True), True

    def _commit(self, req: Commit) -> tuple[ControlReply, bool]:
        if req.round == self.committed and not self.open_round:
            return self.reply(True), False  # the reply to a commit was lost: it is done
        if req.round != self.open_round:
            return self.reply(False, f"round {req.round} is not open"), False
        delays = {int(r): (float(c), float(w)) for r, c, w in req.delays}
        missing = [r for r in self.active if r not in self.stuck and r not in delays]
        if missing:
            return self.reply(False, f"no delays for robots {missing}"), False
        self._delays = delays
        self.commit_open_round()
        return self.reply(True), True

    def commit_open_round(self) -> None:
        """Hand the instant's moves to the clock, each with its delays (a robot with no move
        stays), commit the cycles that end at once, and go on to the next instant."""
        round_no, here = self.open_round, self.positions
        delays, self._delays = self._delays, {}
        moved = []
        for robot in self.active:
            if robot in self.stuck:
                continue
            compute, wait = delays.get(robot, (0.0, 0.0))
            path = self.held.get(robot, Path())
            origin = (float(here[robot, 0]), float(here[robot, 1]))
            world = transform(path, origin, False) if path else Path()
            cut = False
            if world and self.setup.non_rigid is not None:
                cycle = self.clock.cycle_of(robot)
                short = cut_path(
                    origin, world, self.setup.non_rigid, cut_fraction(self.setup.seed, cycle, robot)
                )
                world, cut = short, short is not world
            if world:
                moved.append(robot)
            if robot not in self.held:
                self.timeouts[robot] += 1
            self.last_active[robot] = round_no
            done = self.clock.submit(robot, world, compute, wait, cut=cut)
            if done is not None and self._cycle(done, timed_out=robot not in self.held):
                break
        self.committed, self.moved = round_no, tuple(moved)
        self.open_round, self.looked, self.held, self._missing = 0, set(), {}, set()
        self._agents, self._figures = None, None
        self.last_commit = Committed(round_no, self.active, {}, RoundOutcome(self.positions))
        if self.status == Status.RUNNING:
            self._settle()

    def _settle(self) -> bool:
        """Run the clock on until some Look is due (or the adversary has yet to say when the
        first ones are), committing the cycles that end on the way; True if any did."""
        clock, changed = self.clock, False
        while self.status == Status.RUNNING:
            clock.start_moves()
            if clock.looking():
                break
            t = clock.next_time()
            if not math.isfinite(t):
                break
            clock.advance(t)
            self.positions = clock.positions
            for done in clock.end_moves():
                changed = True
                if self._cycle(done):
                    break
        self.positions = clock.positions
        return changed

    def _cycle(self, done: CycleDone, timed_out: bool = False) -> bool:
        """Record and account one ended cycle (`timed_out`: no move came for it in time, so the
        robot stayed); True once the run has ended."""
        k = self.tracker.snapshot().rounds + 1
        moves = {done.robot: (done.path, done.traveled)} if done.path else {}
        extra: dict[str, Any] = {
            "look": done.look,
            "start": done.start,
            "end": done.end,
            "origin": [done.origin[0], done.origin[1]],
        }
        if done.cut:
            extra["cut"] = [done.robot]
        if timed_out:
            extra["timed_out"] = [done.robot]
        self.journal.round(k, (done.robot,), moves, done.positions, done.collisions, **extra)
        traveled = {done.robot: done.traveled} if done.path else {}
        # its move changed the configuration even when the line before is of the same instant
        moved = done.traveled > MOVE_TOLERANCE or None
        self.tracker.observe(
            [done.robot],
            traveled.keys(),
            self._last,
            done.positions,
            traveled,
            len(done.collisions),
            changed=moved,
        )
        self._last = done.positions
        self.positions = done.positions
        self.collisions_total += len(done.collisions)
        self.last_length[done.robot] = done.traveled
        self.stopped = tuple(sorted({c.robot for c in done.collisions}))
        self.last_cycle = done
        if self.on_cycle is not None:
            self.on_cycle(done)
        if self.tracker.status is None:
            return False
        self._finish()
        return True

    def _finish(self) -> None:
        progress = self.tracker.snapshot()
        status = progress.status or Status.STALLED
        self.journal.result(
            status,
            progress.rounds,
            self.positions,
            epochs=progress.epochs,
            moves=progress.moves,
            total_distance=progress.total_distance,
            collisions=progress.collisions,
            time=self.clock.now,
        )
        self.status = status


__all__ = ["AsyncResumeError", "AsyncWorldCore", "is_async", "make_world"]
