"""The world process: the Zenoh shell around `world.core.WorldCore`.

Its callbacks only enqueue; one thread decodes each event, hands it to the core and sends what the
core answers. Nothing of the round's logic lives here. A Look the core cannot answer yet is held
(the newest per robot) and answered when the robot is activated: that answer is its activation.
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import queue
import threading
import time
from collections import Counter
from collections.abc import Callable
from typing import Any

import zenoh

from fatswarm.domain.outcome import ExitCode
from fatswarm.domain.seam import AlgorithmFailure
from fatswarm.domain.wire import ProtocolError, robot_of_key
from fatswarm.world.core import WorldCore
from fatswarm.world.inbox import Inbox
from fatswarm.world.instants import is_async
from fatswarm.world.journal import Journal, perform
from fatswarm.world.observers import WorldState
from fatswarm.world.protocol import (
    MAX_CONTROL_BYTES,
    MAX_LOOK_BYTES,
    MAX_MOVE_BYTES,
    ControlReply,
    LookRequest,
    MoveSubmitted,
    agent_alive_any_key,
    alive_key,
    control_key,
    decode_control,
    move_any_key,
    moves_held_key,
    robot_of_alive_key,
    snapshot_any_key,
    state_key,
)
from fatswarm.world.record import RecordWriteError

__all__ = [
    "REPUBLISH_S",
    "control_bytes",
    "look_bytes",
    "move_bytes",
    "observed_state",
    "serve",
]

log = logging.getLogger("fatswarm.world")

REPUBLISH_S = 1.0  # the state is re-published this often when nothing happens, for late observers
HOLD_LOOK_S = 20.0  # a held Look is let go (answered with nothing) after this, if its agent has
# not asked again first (it does after agent.service.LOOK_WAIT_S): Looks of agents that are gone
DROPPED_EVERY_S = 5.0  # dropped messages are counted in one log line at most this often

# --- the Zenoh shell --------------------------------------------------------------------------


def serve(
    core: WorldCore, journal: Journal, session: Any, stop: threading.Event | None = None
) -> int:
    """Run the world on an open Zenoh session until `stop` is set, then close it and `journal`
    (the run record the core's lines go to); returns 0, 4 when the record cannot be written, or 1
    when the algorithm's goal raised (the world cannot decide the run any more).

    The caller opens the session (`deploy.zconf.open_client`: a deadline, one-line errors).
    """
    shell = _Shell(core, journal)
    with session:
        _token = shell.declare(session)
        code = shell.run(stop or threading.Event())
    try:
        journal.close()
    except RecordWriteError as exc:
        log.error("%s", exc)
        code = ExitCode.RECORD_FAILED
    log.info("world stopped at round %d (%s)", core.readout.committed, core.readout.status)
    return code


class _Shell:
    """The world's Zenoh shell: callbacks only enqueue; one loop hands each event to the core,
    performs what it asks (the record first), answers, and publishes the state."""

    def __init__(self, core: WorldCore, journal: Journal) -> None:
        self.core, self.journal = core, journal
        self.events: Inbox[tuple[str, Any]] = Inbox()
        self.looks = HeldLooks()
        self.state_pub: Any = None
        self.held_pub: Any = None

    def declare(self, session: Any) -> Any:
        """Publishers, queryables, subscribers and the world's liveliness token (returned: it
        lives as long as the caller holds it)."""
        swarm = self.core.readout.setup.swarm
        self.state_pub = session.declare_publisher(
            state_key(swarm), congestion_control=zenoh.CongestionControl.DROP
        )
        self.held_pub = session.declare_publisher(
            moves_held_key(swarm), congestion_control=zenoh.CongestionControl.BLOCK, express=True
        )
        session.declare_queryable(snapshot_any_key(swarm), self._on_query("look", MAX_LOOK_BYTES))
        session.declare_queryable(control_key(swarm), self._on_query("control", MAX_CONTROL_BYTES))
        session.declare_subscriber(move_any_key(swarm), self._on_move)
        session.liveliness().declare_subscriber(
            agent_alive_any_key(swarm), self._on_alive, history=True
        )
        return session.liveliness().declare_token(alive_key(swarm))

    def _on_alive(self, sample: Any) -> None:
        alive = sample.kind == zenoh.SampleKind.PUT
        self.events.offer("alive", ("alive", (str(sample.key_expr), alive)))

    def _on_move(self, sample: Any) -> None:
        size = len(sample.payload)
        if size > MAX_MOVE_BYTES:
            self.events.too_big("move")
            return
        self.events.offer("move", ("move", (str(sample.key_expr), sample.payload.to_bytes())), size)

    def _on_query(self, kind: str, limit: int) -> Callable[[Any], None]:
        def take(query: Any) -> None:
            size = len(query.payload) if query.payload is not None else 0
            if size > limit:
                self.events.too_big(kind)
                query.drop()  # answered at once (with nothing): the asker does not wait
            elif not self.events.offer(kind, (kind, query), size):
                query.drop()

        return take

    def _publish(self) -> float:
        """Publish the observers' state (and do what making it asked); when it was published."""
        self.state_pub.put(observed_state(self.core).encode())
        perform(self.core.take_effects(), self.journal)
        return time.monotonic()

    def run(self, stop: threading.Event) -> ExitCode:
        """Serve until `stop` is set or the world cannot go on; the exit code."""
        core, events, looks = self.core, self.events, self.looks
        setup = core.readout.setup
        log.info("world of %d robots serving swarm %r", setup.n, setup.swarm)
        published, dirty = self._publish(), False
        said: Counter[str] = Counter()
        said_at = -DROPPED_EVERY_S
        code = ExitCode.OK
        while not stop.is_set():
            try:
                kind, item = events.get(timeout=0.2)
            except queue.Empty:
                if dirty or time.monotonic() - published > REPUBLISH_S:  # late joiners see it
                    published, dirty = self._publish(), False
                looks.expire(time.monotonic())
                continue
            if time.monotonic() - looks.expired_at > HOLD_LOOK_S / 4:  # also when never idle
                looks.expire(time.monotonic())
            if events.dropped != said:  # a flood: say so, at most every few seconds
                said_at = _say_dropped(events, said, said_at)
            outcome = self._step(kind, item)
            if isinstance(outcome, ExitCode):
                code = outcome
                break
            if outcome:
                published = time.monotonic()
            elif kind == "alive":
                dirty = True
        looks.let_go_all()
        return code

    def _step(self, kind: str, item: Any) -> bool | ExitCode:
        """One event: whether to publish the state at once, or the exit code if the world stops."""
        core, readout = self.core, self.core.readout
        try:
            publish = _handle(core, self.journal, kind, item, self.held_pub, self.looks)
            if publish:
                self.state_pub.put(observed_state(core).encode())
            perform(core.take_effects(), self.journal)
            return publish
        except zenoh.ZError as exc:  # e.g. the asker left before its reply: not our problem
            log.warning("zenoh refused a %s reply or notice: %s", kind, exc)
            return False
        except RecordWriteError as exc:  # what is in the record stays; resume goes on from it
            log.error(
                "%s; the world stops at round %d (resume it once this is fixed)",
                exc,
                readout.open_round or readout.committed,
            )
            return ExitCode.RECORD_FAILED
        except AlgorithmFailure as exc:  # its round is durable; nobody can say what next
            with contextlib.suppress(RecordWriteError):  # said on its own when closing
                perform(core.take_effects(), self.journal)
            log.error(
                "%s; the world stops at round %d (in its record)",
                exc,
                readout.open_round or readout.committed,
            )
            return ExitCode.NOT_FORMED


def observed_state(core: WorldCore) -> WorldState:
    """The state observers are shown: the core's, its `round` counting what the record counts.
    An async run's record counts ended cycles, and the coordinator's instants are not rounds: its
    state says how many cycles have ended, as its progress lines and its summary do."""
    state = core.state()
    if is_async(core.readout.setup):
        return dataclasses.replace(state, round=core.readout.progress().rounds)
    return state


def look_bytes(core: WorldCore, key: str) -> bytes | None:
    """The encoded snapshot for a look on `key`, or None (refused, counted)."""
    robot = robot_of_key(key)
    if robot is None:
        core.reject("look-bad-key", key)
        return None
    snapshot = core.look(robot)
    return None if snapshot is None else snapshot.encode()


def move_bytes(core: WorldCore, key: str, payload: bytes) -> bool:
    """Decode a move that came on `key` and hand it to the core; False if refused (counted)."""
    try:
        msg = MoveSubmitted.decode(payload)
    except ProtocolError as exc:
        core.reject("move-garbage", f"on {key}: {exc}")
        return False
    return core.move(robot_of_key(key), msg)


def control_bytes(core: WorldCore, payload: bytes) -> tuple[ControlReply, bool]:
    """Decode a control request and answer it; the flag says whether the state changed."""
    try:
        request = decode_control(payload)
    except ProtocolError as exc:
        core.reject("control-garbage", str(exc))
        return core.reply(False, f"bad request: {exc}"), False
    return core.control(request)


def _say_dropped(events: Inbox[Any], said: Counter[str], said_at: float) -> float:
    """Log how many messages were dropped (too big, or the inbox full) since it last said, at most
    every DROPPED_EVERY_S; when it last said."""
    now = time.monotonic()
    if now - said_at < DROPPED_EVERY_S:
        return said_at
    fresh = events.dropped - said
    log.warning(
        "dropped %s messages (too big, or more than the inbox holds)",
        ", ".join(f"{k} {v}" for k, v in sorted(fresh.items())),
    )
    said.update(fresh)
    return now


class HeldLooks:
    """Looks waiting for their robot's activation: the newest query per robot, and when it came.

    A query is always finalised: answered, let go when a newer one replaces it (an agent asks
    again every agent.service.LOOK_WAIT_S), or let go after HOLD_LOOK_S.
    """

    def __init__(self) -> None:
        self._held: dict[int, tuple[Any, LookRequest, float]] = {}
        self.expired_at = 0.0  # when `expire` last ran

    def __len__(self) -> int:
        return len(self._held)

    def hold(self, robot: int, query: Any, request: LookRequest, now: float) -> None:
        old = self._held.pop(robot, None)
        if old is not None:
            old[0].drop()
        self._held[robot] = (query, request, now)

    def answer_ready(self, core: WorldCore) -> None:
        """Answer every held Look the core can answer now (its robot was just activated)."""
        for robot in [r for r, (_, req, _) in self._held.items() if core.may_look(r, req)]:
            try:
                _answer_look(core, self._held.pop(robot)[0])
            except zenoh.ZError as exc:  # its agent left meanwhile: it asks again if it comes back
                log.debug("robot %d's held look: %s", robot, exc)

    def expire(self, now: float) -> None:
        self.expired_at = now
        for robot in [r for r, (_, _, since) in self._held.items() if now - since > HOLD_LOOK_S]:
            self._held.pop(robot)[0].drop()

    def let_go_all(self) -> None:
        for query, _, _ in self._held.values():
            query.drop()
        self._held.clear()


def _handle(
    core: WorldCore, journal: Journal, kind: str, item: Any, held_pub: Any, looks: HeldLooks
) -> bool:
    """Apply one event; True when the observers' state changed enough to publish at once."""
    if kind == "look":
        _take_look(core, item, looks, held_pub)
    elif kind == "move":
        if move_bytes(core, *item):
            _notify(core, held_pub)
    elif kind == "control":
        return _answer_control(core, journal, item, looks)
    elif kind == "alive":
        key, alive = item
        robot = robot_of_alive_key(key)
        if robot is not None and core.set_alive(robot, alive):
            _notify(core, held_pub)  # a robot gone mid-round is not waited for
    return False


def _notify(core: WorldCore, held_pub: Any) -> None:
    notice = core.moves_notice()
    if notice is not None:
        held_pub.put(notice.encode())


def _take_look(core: WorldCore, query: Any, looks: HeldLooks, held_pub: Any) -> None:
    """Take the move a Look carries, then answer the Look now, hold it until its robot is
    activated, or refuse it (a key with no robot of this run, or garbage)."""
    key = str(query.key_expr)
    robot = robot_of_key(key)
    try:
        request = LookRequest.decode(
            query.payload.to_bytes() if query.payload is not None else LookRequest().encode()
        )
    except ProtocolError as exc:
        core.reject("look-garbage", str(exc))
        try:
            query.reply_err(b"not a look request")
        finally:
            query.drop()
        return
    if request.move:
        _take_carried_move(core, robot, key, request.move, held_pub)
    if robot is None or not 0 <= robot < core.readout.setup.n or core.may_look(robot, request):
        _answer_look(core, query)
    else:
        looks.hold(robot, query, request, time.monotonic())


def _take_carried_move(
    core: WorldCore, robot: int | None, key: str, data: bytes, held_pub: Any
) -> None:
    """A move that a Look carries. The agent sends it again with every Look until one is answered
    (so that a Look lost with a router does not lose the move), so a repeat of a move the world
    holds, or a move of a round that is no longer open, is no news: dropped without a word."""
    try:
        msg = MoveSubmitted.decode(data)
    except ProtocolError as exc:
        core.reject("move-garbage", f"in a look on {key}: {exc}")
        return
    if msg.round != core.readout.open_round or robot in core.readout.held:
        return
    if core.move(robot, msg):
        _notify(core, held_pub)


def _answer_look(core: WorldCore, query: Any) -> None:
    try:
        data = look_bytes(core, str(query.key_expr))
        if data is None:
            query.reply_err(b"not a robot of this run")
        else:
            query.reply(query.key_expr, data)
    finally:
        query.drop()


def _answer_control(core: WorldCore, journal: Journal, query: Any, looks: HeldLooks) -> bool:
    """Answer a control request once what it committed is in the record (durable first)."""
    try:
        payload = query.payload.to_bytes() if query.payload is not None else b""
        reply, changed = control_bytes(core, payload)
        perform(core.take_effects(), journal)
        if changed:
            looks.answer_ready(core)  # a round opened: its robots start computing first
        query.reply(query.key_expr, reply.encode())
        return changed
    finally:
        query.drop()
