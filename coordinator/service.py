"""The coordinator process: runs semi-synchronous rounds over the live agents until the run ends.

Each round: ask the scheduler for the active set among live agents, open the round at the world,
announce it to the agents, wait until the world holds every live active robot's move (or a timeout),
then tell the world to commit. The world's reply says whether the run has ended.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from fatswarm.agent.protocol import alive_any_key, robot_of_alive_key
from fatswarm.coordinator.protocol import RoundStart, alive_key, round_key
from fatswarm.coordinator.schedule import Scheduler
from fatswarm.world.protocol import (
    Begin,
    Commit,
    ControlReply,
    Hello,
    MoveHeld,
    ProtocolError,
    control_key,
    moves_held_key,
)

log = logging.getLogger("fatswarm.coordinator")

EXIT_FORMED = 0
EXIT_NOT_FORMED = 1
RESUME_GRACE_S = 2.0  # a restarted coordinator waits this long for every agent's token
CONTROL_TIMEOUT_S = 10.0  # the world answers in milliseconds; a commit includes one fsync


@dataclass(frozen=True, slots=True)
class CoordinatorConfig:
    """How the coordinator runs rounds."""

    swarm: str
    move_timeout_s: float = 5.0  # an active robot that has not moved by then stays put
    start_timeout_s: float = 120.0  # wait this long for all n agents before round 1
    pace_s: float = 0.0  # least time per round: lets people (and tests) watch a run unfold
    resume_live: Sequence[int] | None = None  # live set assumed when replaying the scheduler


class Coordinator:
    """The coordinator's Zenoh shell; `run` returns 0 when formed, 1 otherwise."""

    def __init__(
        self,
        cfg: CoordinatorConfig,
        make_scheduler: Callable[[int], Scheduler],
        stop: threading.Event,
    ) -> None:
        self.cfg = cfg
        self.make_scheduler = make_scheduler
        self.scheduler: Scheduler | None = None
        self.n = 0
        self.stop = stop
        self.events: queue.Queue[tuple[str, Any]] = queue.Queue()
        self.live: set[int] = set()
        self.held: set[int] = set()
        self.round = 0
        self.planned: dict[int, tuple[int, ...]] = {}  # round -> active set (kept for retries)
        self.rejected = 0

    # -- event intake (callbacks only enqueue) --------------------------------------------------

    def _on_alive(self, sample: Any) -> None:
        import zenoh

        self.events.put(("alive", (str(sample.key_expr), sample.kind == zenoh.SampleKind.PUT)))

    def _on_held(self, sample: Any) -> None:
        self.events.put(("held", sample.payload.to_bytes()))

    def _drain(self, timeout: float) -> None:
        """Apply queued events, waiting up to `timeout` for the first one."""
        try:
            kind, item = self.events.get(timeout=max(0.0, timeout))
        except queue.Empty:
            return
        while True:
            if kind == "alive":
                key, alive = item
                robot = robot_of_alive_key(key)
                if robot is not None and (robot < self.n or not self.n):
                    if alive:
                        self.live.add(robot)
                    elif robot in self.live:
                        self.live.discard(robot)
                        log.info("agent %d is gone", robot)
            elif kind == "held":
                try:
                    notice = MoveHeld.decode(item)
                except ProtocolError as exc:
                    self.rejected += 1
                    log.warning("rejected move notice: %s [total %d]", exc, self.rejected)
                else:
                    if notice.round == self.round:
                        self.held.add(notice.robot)
            try:
                kind, item = self.events.get_nowait()
            except queue.Empty:
                return

    # -- requests to the world ------------------------------------------------------------------

    def _ask(self, session: Any, request: bytes) -> ControlReply | None:
        """One control request; None if the world did not answer (down or restarting)."""
        import zenoh

        try:
            replies = list(
                session.get(control_key(self.cfg.swarm), payload=request, timeout=CONTROL_TIMEOUT_S)
            )
        except zenoh.ZError as exc:  # the session is reconnecting to its router
            log.warning("control request failed: %s", exc)
            return None
        for reply in replies:
            if reply.ok is None:
                continue
            try:
                return ControlReply.decode(reply.ok.payload.to_bytes())
            except ProtocolError as exc:
                log.warning("world sent a bad control reply: %s", exc)
        return None

    def _hello(self, session: Any) -> ControlReply | None:
        """Wait until the world answers; None if stopped first."""
        while not self.stop.is_set():
            reply = self._ask(session, Hello().encode())
            if reply is not None:
                return reply
            self._drain(0.25)
        return None

    # -- the round loop -------------------------------------------------------------------------

    def run(self, session: Any) -> int:
        """Run rounds on an open Zenoh session until the run ends, then close it."""
        import zenoh

        with session:
            _token = session.liveliness().declare_token(alive_key(self.cfg.swarm))
            session.liveliness().declare_subscriber(
                alive_any_key(self.cfg.swarm), self._on_alive, history=True
            )
            session.declare_subscriber(moves_held_key(self.cfg.swarm), self._on_held)
            announce = session.declare_publisher(
                round_key(self.cfg.swarm),
                congestion_control=zenoh.CongestionControl.BLOCK,
                express=True,
            )
            return self._loop(session, announce)

    def _loop(self, session: Any, announce: Any) -> int:
        first = self._hello(session)
        if first is None:
            return EXIT_NOT_FORMED
        self.n = first.n  # the world owns the run's parameters
        self.live = {r for r in self.live if r < self.n}
        self.scheduler = self.make_scheduler(self.n)
        if first.committed:
            self._replay_scheduler(first.committed)
        self._wait_for_agents(first.committed)
        reply: ControlReply | None = first
        while reply is not None and reply.status == "running" and not self.stop.is_set():
            started = time.monotonic()
            done = self._one_round(session, announce, reply.committed + 1)
            if self.cfg.pace_s > 0:
                self.stop.wait(max(0.0, started + self.cfg.pace_s - time.monotonic()))
            # a commit's reply says where the run stands; after a refusal or a failure, ask
            reply = done if done is not None and done.ok else self._hello(session)
        status = reply.status if reply is not None else "running"
        if status == "running":
            return EXIT_NOT_FORMED
        log.info("run ended: %s after round %d", status, self.round)
        return EXIT_FORMED if status == "formed" else EXIT_NOT_FORMED

    def _replay_scheduler(self, committed: int) -> None:
        """A restarted coordinator advances a seeded scheduler past the rounds already run."""
        live = sorted(self.cfg.resume_live or range(self.n))
        assert self.scheduler is not None
        for r in range(1, committed + 1):
            self.scheduler.active(r, live)
        log.info("resuming after round %d", committed)

    def _wait_for_agents(self, committed: int) -> None:
        """Wait for all n agents: up to the start timeout before round 1, briefly on resuming."""
        wait_s = self.cfg.start_timeout_s if committed == 0 else RESUME_GRACE_S
        deadline = time.monotonic() + wait_s
        while len(self.live) < self.n and not self.stop.is_set():
            if time.monotonic() > deadline:
                log.warning("only %d of %d agents after %.1f s; going on with them",
                            len(self.live), self.n, wait_s)
                break
            self._drain(0.1)
        while not self.live and not self.stop.is_set():
            self._drain(0.1)

    def _one_round(self, session: Any, announce: Any, round_no: int) -> ControlReply | None:
        """Run round `round_no` to its commit; the world's last reply (None: no answer)."""
        import zenoh

        self._drain(0.0)
        while not self.live and not self.stop.is_set():
            self._drain(0.1)
        if self.stop.is_set():
            return None
        if round_no not in self.planned:
            assert self.scheduler is not None
            self.planned = {round_no: tuple(self.scheduler.active(round_no, sorted(self.live)))}
        active = self.planned[round_no]
        self.round, self.held = round_no, set()
        t0 = time.perf_counter()
        begun = self._ask(session, Begin(round=round_no, active=active).encode())
        if begun is None or not begun.ok:
            log.warning("world refused round %d: %s", round_no, begun and begun.reason)
            self._drain(0.2)
            return begun
        timeout_ms = int(self.cfg.move_timeout_s * 1000)
        try:
            announce.put(RoundStart(round=round_no, active=active, timeout_ms=timeout_ms).encode())
        except zenoh.ZError as exc:  # nobody hears it: the robots stay put this round
            log.warning("round %d announcement failed: %s", round_no, exc)
        t1 = time.perf_counter()
        deadline = time.monotonic() + self.cfg.move_timeout_s
        while not self.stop.is_set():
            waiting = [r for r in active if r in self.live and r not in self.held]
            if not waiting or time.monotonic() >= deadline:
                break
            self._drain(deadline - time.monotonic())
        timed_out = tuple(r for r in active if r not in self.held)
        if timed_out:
            log.info("round %d: no move from %s", round_no, list(timed_out))
        t2 = time.perf_counter()
        done = self._ask(session, Commit(round=round_no, timed_out=timed_out).encode())
        t3 = time.perf_counter()
        log.debug("round %d: begin %.2f ms, moves %.2f ms, commit %.2f ms", round_no,
                  1e3 * (t1 - t0), 1e3 * (t2 - t1), 1e3 * (t3 - t2))
        if done is None or not done.ok:
            # The world restarted and lost the open round: the loop opens it again.
            log.warning("commit of round %d failed: %s", round_no, done and done.reason)
        return done
