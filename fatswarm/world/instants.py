"""The world's model for the async models: robots on their own clocks (world/asynchrony.py)
instead of rounds of physics.

A protocol round is one instant of virtual time at which some robots Look (the coordinator, as
the adversary and the clock, names them and the instant in its Begin); their moves come back as
in a round, and the Commit hands the world each one's delays (compute, then wait). Between those
instants the world runs every move on its own: it commits each ended cycle as one record line
and goes on, event by event, to the next instant at which a Look is due, which its reply names.
The lock step drives this very model, so a networked async run and a lock-step one agree.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from fatswarm.domain.adversary import ASYNC_NAMES, make_async
from fatswarm.domain.draws import cut_fraction
from fatswarm.domain.outcome import Status
from fatswarm.domain.path import Path, transform
from fatswarm.world.asynchrony import AsyncWorld, CycleDone
from fatswarm.world.effects import Committed
from fatswarm.world.faults import cut_path
from fatswarm.world.model import Answer, Books
from fatswarm.world.progress import MOVE_TOLERANCE
from fatswarm.world.protocol import Begin, Commit
from fatswarm.world.record import RunRecord, round_entry
from fatswarm.world.setup import WorldSetup

_RUNNING = Status.RUNNING  # (read off its Enum class once: ~20 times a global's cost a read)


class AsyncResumeError(ValueError):
    """An async run's record handed to the world core to book line by line: its lines are ended
    cycles, and the moves in flight between them are in no line, so the core cannot rebuild its
    clock from them. A record is resumed by running the run again from its start and checking
    each line against the record's (`deploy.engine.lockstep.replay_async`)."""


def is_async(setup: WorldSetup) -> bool:
    """Whether `setup` runs an async model."""
    return setup.scheduler in ASYNC_NAMES


def async_setup(setup: WorldSetup, history: RunRecord | None) -> WorldSetup:
    """`setup` with the async model's fairness bound among its header fields; raises
    AsyncResumeError for a history with lines (replayed from the start instead: the class)."""
    if history is not None and (history.rounds or history.result is not None):
        raise AsyncResumeError(
            f"a {setup.scheduler} record is resumed by replaying its run from the start, "
            "not line by line"
        )
    model = make_async(setup.scheduler, setup.n, setup.seed)
    return dataclasses.replace(setup, extra={"fairness_time": model.bound(), **setup.extra})


class Instants:
    """Async robots: `committed` counts instants; the record counts ended cycles."""

    def __init__(self, books: Books) -> None:
        self.books = books
        self.clock = AsyncWorld(
            books.positions, [math.inf] * books.setup.n, points=books.looks.points
        )
        self._last = books.positions.copy()
        self._delays: dict[int, tuple[float, float]] = {}
        # robot -> (when, colour): a luminous robot's colour shows at the end of its Compute
        self._showing: dict[int, tuple[float, int]] = {}
        self._relit = False  # a colour changed since the last cycle line
        self._failing: dict[int, str] = {}  # robot -> why its compute raised, until its cycle ends
        # robot -> the time the crash adversary crashed it, until the next cycle line says so
        self._crashes: dict[int, float] = {}
        # the end of the last cycle line that changed the configuration: a cycle whose Look came
        # before it planned on the old one (its line is booked when its move ends, after it)
        self._changed_at = -math.inf

    def reply_fields(self) -> dict[str, Any]:
        known, unset = self.clock.looks()
        w = self.books
        cycles = tuple((r, self.clock.cycle_of(r)) for r in w.active) if w.open_round else ()
        return {
            "now": self.clock.now,
            "looks": tuple(known),
            "unset": tuple(unset),
            "cycles": cycles,
        }

    def result_fields(self) -> dict[str, Any]:
        return {"time": self.clock.now}

    def time(self) -> float | None:
        return self.clock.now

    def begin(self, req: Begin) -> Answer:
        """Open the instant `req.at` for the robots due then, once the world has got there."""
        w = self.books
        if req.round != w.committed + 1:
            return f"next round is {w.committed + 1}, not {req.round}", False
        if w.open_round == req.round and w.active == req.active:
            return None, False  # a coordinator retrying: keep what is held
        if w.open_round:
            return f"round {w.open_round} is open", False
        if req.at is None:
            return "an async world opens instants: Begin needs `at`", False
        refused = self._set_looks(req)
        if refused is not None:
            return refused, False
        changed = self._settle()
        due = tuple(self.clock.looking())
        if w.status != _RUNNING or not due or due != req.active or self.clock.now != req.at:
            return None, changed  # not opened: the reply says what is due, and when
        self._open(req.round, due)
        return None, True

    def _set_looks(self, req: Begin) -> str | None:
        """Set the first Looks `req` gives; why not, if a robot or a time is refused."""
        for robot, t in req.looks:
            if not 0 <= robot < self.books.setup.n:
                return f"robot {robot} is not of this run"
            try:
                self.clock.set_look(robot, t)
            except ValueError as exc:
                return str(exc)
        return None

    def _open(self, round_no: int, due: tuple[int, ...]) -> None:
        """Open the instant for the robots `due`: those the crash adversary crashes now stay."""
        w = self.books
        crashing = {r for r in due if w.crash_plan.get(r) == self.clock.cycle_of(r) + 1}
        for robot in sorted(crashing):
            self.clock.crash(robot)
            w.tracker.crash([robot])
            self._crashes[robot] = self.clock.now
        w.stuck = w.stuck | frozenset(crashing)
        for robot in due:
            if robot not in crashing:
                self.clock.begin_cycle(robot)
        w.open_round, w.active = round_no, due
        w.active_set = frozenset(due)
        # a crashed robot is held as staying: nobody waits for its agent
        w.looked, w.held, w.noticed = set(), {r: Path() for r in crashing}, None
        w.failed = {}
        w.missing = {r for r in due if w.alive[r] and r not in crashing}

    def commit(self, req: Commit) -> Answer:
        w = self.books
        if req.round == w.committed and not w.open_round:
            return None, False  # the reply to a commit was lost: it is done
        if req.round != w.open_round:
            return f"round {req.round} is not open", False
        delays = {int(r): (float(c), float(wait)) for r, c, wait in req.delays}
        missing = [r for r in w.active if r not in w.stuck and r not in delays]
        if missing:
            return f"no delays for robots {missing}", False
        self._delays = delays
        self.commit_open_round()
        return None, True

    def commit_open_round(self) -> None:
        """Hand the instant's moves to the clock, each with its delays (a robot with no move
        stays), commit the cycles that end at once, and go on to the next instant."""
        w = self.books
        round_no, here = w.open_round, w.positions
        delays, self._delays = self._delays, {}
        colours, w.held_colours = w.held_colours, {}
        moved = []
        for robot in w.active:
            if robot in w.stuck:
                continue
            compute, wait = delays.get(robot, (0.0, 0.0))
            if robot in colours:
                self._showing[robot] = (self.clock.now + compute, colours[robot])
                # a change to come counts now: a staying robot's cycle line comes before it shows
                self._relit |= colours[robot] != w.looks.colour(robot)
            path = w.held.get(robot, Path())
            origin = (float(here[robot, 0]), float(here[robot, 1]))
            world = transform(path, origin, False) if path else Path()
            cut = False
            if world and w.setup.non_rigid is not None:
                cycle = self.clock.cycle_of(robot)
                short = cut_path(
                    origin, world, w.setup.non_rigid, cut_fraction(w.setup.seed, cycle, robot)
                )
                world, cut = short, short is not world
            if world:
                moved.append(robot)
            if robot not in w.held:
                w.timeouts[robot] += 1
            if robot in w.failed:  # its cycle line says why it stayed
                self._failing[robot] = w.failed[robot]
            done = self.clock.submit(robot, world, compute, wait, cut=cut)
            if done is not None and self._cycle(done, timed_out=robot not in w.held):
                break
        w.committed, w.moved = round_no, tuple(moved)
        w.open_round, w.looked, w.held, w.missing, w.failed = 0, set(), {}, set(), {}
        w.views_changed()
        if w.status == _RUNNING:
            self._settle()

    def _settle(self) -> bool:
        """Run the clock on until some Look is due (or the adversary has yet to say when the
        first ones are), committing the cycles that end on the way; True if any did."""
        w = self.books
        clock, changed = self.clock, False
        while w.status == _RUNNING:
            clock.start_moves()
            self._show_due()
            if clock.looking():
                break
            t = clock.next_time()
            if not math.isfinite(t):
                break
            clock.advance(t)
            self._show_due()
            w.positions = clock.positions
            for done in clock.end_moves():
                changed = True
                if self._cycle(done):
                    break
        w.positions = clock.positions
        return changed

    def _show_due(self) -> None:
        """The colours whose Compute has ended by now show (a Look at that very time sees them,
        unless it is of the instant at which that Compute began: docs/model.md, rule 7)."""
        due = {r: c for r, (t, c) in self._showing.items() if t <= self.clock.now}
        if due:
            self._relit |= self.books.looks.show(due, skip=self.books.stuck)
            for robot in due:
                del self._showing[robot]

    def _cycle(self, done: CycleDone, timed_out: bool = False) -> bool:
        """Record and account one ended cycle (`timed_out`: no move came for it in time, so the
        robot stayed); True once the run has ended."""
        w = self.books
        self._show_due()
        k = w.tracker.snapshot().rounds + 1
        w.last_active[done.robot] = k  # observers count cycles, as the record (not instants)
        paths = {done.robot: done.path} if done.path else {}
        traveled = {done.robot: done.traveled} if done.path else {}
        failed = self._failing.pop(done.robot, None)
        crashes, self._crashes = self._crashes, {}
        entry = round_entry(
            k,
            (done.robot,),
            paths,
            traveled,
            done.positions,
            done.collisions,
            times={
                "look": done.look,
                "start": done.start,
                "end": done.end,
                "origin": [done.origin[0], done.origin[1]],
                # only when some crashed since the line before: records without stay as they were
                **({"crash_at": {str(r): crashes[r] for r in sorted(crashes)}} if crashes else {}),
            },
            robots=(
                ("cut", [done.robot] if done.cut else []),
                ("timed_out", [done.robot] if timed_out else []),
                ("crash", sorted(crashes)),
            ),
            model=w.looks.round_fields([done.robot]),
            failed=None if failed is None else {done.robot: failed},
        )
        # its move changed the configuration even when the line before is of the same instant
        moved = done.traveled > MOVE_TOLERANCE or self._relit or None
        self._relit = False
        stale = done.look < self._changed_at
        try:  # the cycle is the record's even when the goal raises while it is booked
            w.tracker.observe(
                [done.robot],
                traveled.keys(),
                self._last,
                done.positions,
                traveled,
                len(done.collisions),
                changed=moved,
                line=entry.extra,
                stale=stale,
            )
        finally:
            w.emit(Committed(entry, w.tracker.snapshot()))
        self._last = done.positions
        if moved:
            self._changed_at = done.end
        w.positions = done.positions
        w.collisions_total += len(done.collisions)
        w.last_length[done.robot] = done.traveled
        w.stopped = tuple(sorted({c.robot for c in done.collisions}))
        if w.tracker.status is None:
            return False
        w.finish()
        return True


__all__ = ["AsyncResumeError", "Instants", "async_setup", "is_async"]
