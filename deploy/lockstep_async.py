"""An async run in one process: the adversary's delays (coordinator/adversary.py), the
asynchronous world (world/asynchrony.py) and every robot's Compute, event by event in virtual time.

Each ended cycle is committed as one record line (`round` = its number among all ended cycles,
in the order they end) with the virtual times of its Look, start and end: docs/record.md. The run
ends as round runs do (`world.progress`): formed once every robot has Looked at the unchanged
configuration and asked to stay, and the goal holds; stalled likewise without the goal; out of
rounds after `max_rounds` cycles.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any, Final

import numpy as np

from fatswarm.agent.frames import compute_in_frame, draw_flip
from fatswarm.agent.path import Path, Points, transform
from fatswarm.agent.protocol import MoveSubmitted
from fatswarm.agent.seam import Configured, checked
from fatswarm.coordinator.adversary import AsyncModel
from fatswarm.world.asynchrony import AsyncWorld, CycleDone
from fatswarm.world.core import Committed, Journal, NullJournal, crash_plan, cut_fraction, cut_path
from fatswarm.world.physics import RoundOutcome
from fatswarm.world.progress import ProgressTracker
from fatswarm.world.protocol import ProtocolError

log = logging.getLogger("fatswarm.lockstep")

SHOWN_FAULTS: Final = 3


class AsyncRun:
    """The state of one async run: world, adversary, progress and record (no I/O but the
    journal). `step` handles one instant of virtual time; `run` steps until the run ends."""

    def __init__(
        self,
        positions: Points,
        setting: Configured,
        model: AsyncModel,
        *,
        seed: int,
        max_rounds: int,
        journal: Journal | None = None,
        compute: Callable[[Points], Path] | None = None,
        non_rigid: float | None = None,
        crash: int | None = None,
        on_cycle: Callable[[Committed, CycleDone], None] | None = None,
    ) -> None:
        n = len(positions)
        self.setting, self.model, self.seed = setting, model, seed
        self.world = AsyncWorld(positions, seed, [model.first_look(r) for r in range(n)])
        self.journal: Journal = NullJournal() if journal is None else journal
        self.compute = checked(setting.compute if compute is None else compute)
        self.flips = [draw_flip(seed, r) for r in range(n)]
        self.non_rigid = non_rigid
        self.crash_plan = {} if crash is None else crash_plan(seed, n, crash)
        self.tracker = ProgressTracker(n, self._goal, max_rounds)
        self.on_cycle = on_cycle
        self.looks = 0
        self.faults = 0
        self._last: Points = self.world.positions.copy()
        self._live_goal: Configured | None = None

    @property
    def status(self) -> str | None:
        return self.tracker.status

    def run(self) -> None:
        """Step until formed, stalled or out of rounds. Every step either lets time pass or
        ends, starts or begins a cycle; more than a step per robot and phase at one instant with
        no cycle ended would be a bug, said rather than looped on."""
        idle, mark = 0, (-1.0, -1, -1)
        while self.tracker.status is None:
            self.step()
            now = (self.world.now, self.world.cycles, self.looks)
            idle = idle + 1 if now == mark else 0
            mark = now
            if idle > 3 * self.world.n + 3:
                raise RuntimeError(f"async run stuck at virtual time {self.world.now}")

    def step(self) -> None:
        """The next instant: movers on to it, ended moves committed, due moves started, due
        robots Look and submit."""
        world = self.world
        world.advance(world.next_time())
        for done in world.end_moves():
            if self._commit(done):
                return
        world.start_moves()
        for robot in world.looking():
            if self.crash_plan.get(robot) == world.cycle_of(robot) + 1:
                world.crash(robot)
                self.tracker.crash([robot])
                continue
            view = world.look(robot)
            self.looks += 1
            cycle = world.cycle_of(robot)
            path, cut = self._path(robot, cycle, view)
            delays = self.model.cycle(robot, cycle)
            stayed = world.submit(robot, path, delays.compute, delays.wait, cut=cut)
            if stayed is not None and self._commit(stayed):
                return

    def _path(self, robot: int, cycle: int, view: Points) -> tuple[Path, bool]:
        """Robot `robot`'s world-frame move from its Look (stay if its compute fails, as an
        agent's would), and whether the non-rigid adversary cut it."""
        world = self.world
        here = (float(world.positions[robot, 0]), float(world.positions[robot, 1]))
        try:
            local = compute_in_frame(view, self.flips[robot], self.compute)
            wire = MoveSubmitted(robot=robot, round=cycle, path=local).encode()
            path = transform(MoveSubmitted.decode(wire).path, here, False)
        except ProtocolError as exc:
            return self._fault(robot, cycle, f"sent a move the world refuses: {exc}"), False
        except Exception as exc:  # a bug in the algorithm: the robot stays put, as networked
            return self._fault(robot, cycle, f"compute raised {type(exc).__name__}: {exc}"), False
        if self.non_rigid is None or not path:
            return path, False
        short = cut_path(here, path, self.non_rigid, cut_fraction(self.seed, cycle, robot))
        return short, short is not path

    def _fault(self, robot: int, cycle: int, problem: str) -> Path:
        self.faults += 1
        if self.faults <= SHOWN_FAULTS:
            log.warning("robot %d, cycle %d: %s; it stays put%s", robot, cycle, problem,
                        "; further faults are only counted" if self.faults == SHOWN_FAULTS else "")
        return Path()

    def _commit(self, done: CycleDone) -> bool:
        """Record and account one ended cycle; True once the run has ended."""
        k = self.tracker.snapshot().rounds + 1
        moves = {done.robot: (done.path, done.traveled)} if done.path else {}
        extra: dict[str, Any] = {"look": done.look, "start": done.start, "end": done.end,
                                 "origin": [done.origin[0], done.origin[1]]}
        if done.cut:
            extra["cut"] = [done.robot]
        self.journal.round(k, (done.robot,), moves, done.positions, done.collisions, **extra)
        traveled = {done.robot: done.traveled} if done.path else {}
        self.tracker.observe([done.robot], traveled.keys(), self._last, done.positions,
                             traveled, len(done.collisions))
        self._last = done.positions
        if self.on_cycle is not None:
            outcome = RoundOutcome(done.positions, traveled, list(done.collisions))
            paths = {done.robot: done.path} if done.path else {}
            self.on_cycle(Committed(k, (done.robot,), paths, outcome), done)
        if self.tracker.status is None:
            return False
        progress = self.tracker.snapshot()
        self.journal.result(
            progress.status or "", progress.rounds, done.positions, epochs=progress.epochs,
            moves=progress.moves, total_distance=progress.total_distance,
            collisions=progress.collisions, time=self.world.now,
        )
        return True

    def _goal(self, positions: Points) -> bool:
        """The algorithm's goal, on the live robots once some have crashed (as world.core)."""
        crashed = self.world.crashed
        if not crashed:
            return self.setting.goal(positions)
        live = [r for r in range(len(positions)) if r not in crashed]
        if self._live_goal is None or self._live_goal.n != len(live):
            try:
                self._live_goal = Configured.of(self.setting.algorithm, len(live),
                                                self.setting.values)
            except ValueError:
                return False
        return self._live_goal.goal(np.asarray(positions)[live])


__all__ = ["AsyncRun"]
