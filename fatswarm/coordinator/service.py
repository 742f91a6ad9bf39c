"""The coordinator process: a Zenoh shell around the round state machine of `rounds.py`.

Callbacks only enqueue. One loop feeds the queued events to the core, calls it at its deadlines,
and performs what it asks: control requests to the world (which activates the agents).
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import zenoh

from fatswarm.coordinator.async_rounds import coordinator_core
from fatswarm.coordinator.driver import AgentSeen, Event, WorldSeen, drive
from fatswarm.coordinator.protocol import alive_key
from fatswarm.coordinator.rounds import Finished, Note, RoundTimes
from fatswarm.coordinator.schedule import Scheduler
from fatswarm.domain.outcome import ExitCode, Status, exit_code_for
from fatswarm.domain.wire import ProtocolError
from fatswarm.world.inbox import Inbox
from fatswarm.world.protocol import (
    MAX_NOTICE_BYTES,
    Begin,
    Commit,
    ControlReply,
    ControlRequest,
    MovesHeld,
    agent_alive_any_key,
    control_key,
    moves_held_key,
    robot_of_alive_key,
)
from fatswarm.world.protocol import alive_key as world_alive_key
from fatswarm.world.rejections import Rejections

log = logging.getLogger("fatswarm.coordinator")

CONTROL_TIMEOUT_S = 10.0  # the world answers in milliseconds; a commit includes one fsync
STOP_POLL_S = 0.1  # the loop looks at the stop flag at least this often while it waits
_TIMES = RoundTimes()  # the defaults


@dataclass(frozen=True, slots=True)
class CoordinatorConfig:
    """How the coordinator runs rounds."""

    swarm: str
    move_timeout_s: float = _TIMES.move_timeout_s  # an active robot silent by then stays put
    start_timeout_s: float = _TIMES.start_timeout_s  # wait this long for all n agents at first
    pace_s: float = _TIMES.pace_s  # least time per round: lets people (and tests) watch a run
    resume_live: Sequence[int] | None = None  # live set assumed when replaying the scheduler
    resume_grace_s: float = _TIMES.resume_grace_s  # a restarted coordinator waits this long
    retry_s: float = _TIMES.retry_s  # before asking a silent world again
    scheduler: str = ""  # its name: an async model gets the async core (coordinator/async_rounds)
    give_up_s: float = _TIMES.give_up_s  # no usable answer from the world this long: exit 5

    @property
    def times(self) -> RoundTimes:
        """The timing part, as the core takes it."""
        return RoundTimes(
            move_timeout_s=self.move_timeout_s,
            start_timeout_s=self.start_timeout_s,
            resume_grace_s=self.resume_grace_s,
            pace_s=self.pace_s,
            retry_s=self.retry_s,
            give_up_s=self.give_up_s,
        )


class Coordinator:
    """The coordinator's Zenoh shell; `run` returns the exit code (0 formed, see world.outcome)."""

    def __init__(
        self,
        cfg: CoordinatorConfig,
        make_scheduler: Callable[[int], Scheduler],
        stop: threading.Event,
    ) -> None:
        self.cfg = cfg
        self.stop = stop
        self.core = coordinator_core(cfg.scheduler, make_scheduler, cfg.times, cfg.resume_live)
        self.events: Inbox[tuple[str, Any]] = Inbox()
        self.rejected = Rejections()  # garbage notices: counted, said at most every few s
        self._began = 0.0  # perf_counter mark of the round's opening (debug timings)
        self._session: Any = None  # the open Zenoh session, while it runs
        # the control request out, cancelled when the world's token goes: a world killed while
        # it held the request would otherwise cost the whole CONTROL_TIMEOUT_S (seen: 10 s)
        self._asking: Any = None
        self._asking_lock = threading.Lock()

    # -- event intake (callbacks only enqueue) --------------------------------------------------

    def _on_alive(self, sample: Any) -> None:
        alive = sample.kind == zenoh.SampleKind.PUT
        self.events.offer("alive", ("alive", (str(sample.key_expr), alive)))

    def _on_world(self, sample: Any) -> None:
        alive = sample.kind == zenoh.SampleKind.PUT
        if not alive:
            with self._asking_lock:
                if self._asking is not None:
                    self._asking.cancel()  # its answer will not come: ask again at once
        self.events.offer("world", ("world", alive))

    def _on_held(self, sample: Any) -> None:
        size = len(sample.payload)
        if size > MAX_NOTICE_BYTES:
            self.events.too_big("held")
            return
        self.events.offer("held", ("held", sample.payload.to_bytes()), size)

    # -- the loop -------------------------------------------------------------------------------

    def run(self, session: Any) -> int:
        """Run rounds on an open Zenoh session until the run ends, then close it."""
        with session:
            _token = session.liveliness().declare_token(alive_key(self.cfg.swarm))
            session.liveliness().declare_subscriber(
                agent_alive_any_key(self.cfg.swarm), self._on_alive, history=True
            )
            session.declare_subscriber(moves_held_key(self.cfg.swarm), self._on_held)
            session.liveliness().declare_subscriber(
                world_alive_key(self.cfg.swarm), self._on_world, history=True
            )
            return self._loop(session)

    def _loop(self, session: Any) -> int:
        self._session = session
        return self._end(drive(self.core, self))

    def _end(self, finished: Finished) -> int:
        if finished.gave_up:
            log.error("%s", finished.gave_up)
            return ExitCode.NO_PEER
        if finished.status != Status.RUNNING:
            log.info("run ended: %s after round %d", finished.status, self.core.round)
        return exit_code_for(finished.status, finished.collisions)

    # -- the link `drive` runs on: the wall clock, Zenoh, the log --------------------------------

    def now(self) -> float:
        return time.monotonic()

    def stopped(self) -> bool:
        return self.stop.is_set()

    def note(self, notes: Sequence[Note]) -> None:
        for note in notes:
            log.log(logging.WARNING if note.warning else logging.INFO, "%s", note.text)

    def wait(self, deadline: float | None) -> list[Event] | None:
        """The events that come before `deadline` (at most STOP_POLL_S from now), decoded; None
        once stopped."""
        if self.stop.is_set():
            return None
        wait_s = STOP_POLL_S
        if deadline is not None:
            wait_s = min(wait_s, max(0.0, deadline - time.monotonic()))
        events: list[Event] = []
        try:
            item = self.events.get(timeout=wait_s)
        except queue.Empty:
            return events
        while True:
            event = self._decode(*item)
            if event is not None:
                events.append(event)
            try:
                item = self.events.get_nowait()
            except queue.Empty:
                return events

    def _decode(self, kind: str, item: Any) -> Event | None:
        if kind == "world":
            return WorldSeen(bool(item))
        if kind == "alive":
            key, alive = item
            robot = robot_of_alive_key(key)
            return None if robot is None else AgentSeen(robot, alive)
        try:
            return MovesHeld.decode(item)
        except ProtocolError as exc:
            line = self.rejected.count("notice-garbage", str(exc), time.monotonic())
            if line is not None:
                log.warning("%s", line)
            return None

    # -- actions --------------------------------------------------------------------------------

    def ask(self, request: ControlRequest) -> ControlReply | None:
        """One control request; None if the world did not answer (down or restarting)."""
        asked = time.perf_counter()
        reply = self._get(self._session, request.encode())
        if isinstance(request, Commit) and log.isEnabledFor(logging.DEBUG):
            log.debug(
                "round %d: moves %.2f ms, commit %.2f ms",
                request.round,
                1e3 * (asked - self._began),
                1e3 * (time.perf_counter() - asked),
            )
        if isinstance(request, Begin) or (isinstance(request, Commit) and request.then_active):
            self._began = time.perf_counter()
        return reply

    def _get(self, session: Any, payload: bytes) -> ControlReply | None:
        token = zenoh.CancellationToken()
        with self._asking_lock:
            self._asking = token
        try:
            replies = list(
                session.get(
                    control_key(self.cfg.swarm),
                    payload=payload,
                    timeout=CONTROL_TIMEOUT_S,
                    cancellation_token=token,
                )
            )
        except zenoh.ZError as exc:  # the session is reconnecting to its router
            log.warning("control request failed: %s", exc)
            return None
        finally:
            with self._asking_lock:
                self._asking = None
        for reply in replies:
            if reply.ok is None:
                continue
            try:
                return ControlReply.decode(reply.ok.payload.to_bytes())
            except ProtocolError as exc:
                log.warning("world sent a bad control reply: %s", exc)
        return None
